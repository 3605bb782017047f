"""What the tests share: the episode loop (agents.evaluate.run_episode: the same one the evaluator
runs), bit-for-bit comparison, seeded random rollouts."""

from __future__ import annotations

import numpy as np

from agents.evaluate import Episode, run_episode
from softgrasp_env.registration import TISSUE_V3

__all__ = ["Episode", "assert_same", "obs_vector", "rollout", "run_episode"]


def obs_vector(obs) -> np.ndarray:
    """The vector observation (the goal env's ``observation`` entry)."""
    return obs["observation"] if isinstance(obs, dict) else obs


def assert_same(a, b) -> None:
    """Bit-identical (arrays, dicts, sequences, scalars)."""
    if isinstance(a, (tuple, list)):
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            assert_same(x, y)
    elif isinstance(a, dict):
        assert a.keys() == b.keys()
        for k in a:
            assert_same(a[k], b[k])
    elif isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape
        assert a.tobytes() == b.tobytes()
    else:
        assert a == b


def rollout(env, seed: int, steps: int, action_seed: int) -> list:
    """Every reset and step result of ``steps`` seeded random actions, resetting after an
    episode ends."""
    out = [env.reset(seed=seed)]
    rng = np.random.default_rng(action_seed)
    for _ in range(steps):
        res = env.step(rng.uniform(-1.0, 1.0, size=4).astype(np.float32))
        out.append(res)
        if res[2] or res[3]:
            out.append(env.reset())
    return out


SOFT_PHYSICS = ("thesis", "v5")
"""The soft physics the threshold tests run on: the thesis tissue they were first measured on (a
family's v4 id with TISSUE_V3) and the soft ids' latest (its v5: the v4 tissue solved globally)."""


def soft_physics(family: str, physics: str) -> tuple[str, dict]:
    """The id and ``gym.make`` keywords of ``family`` (``"SoftGrasp"``, ``"SoftGraspEasy"``) on
    ``physics`` (one of :data:`SOFT_PHYSICS`)."""
    if physics == "thesis":
        return f"{family}-v4", dict(TISSUE_V3)
    if physics == "v5":
        return f"{family}-v5", {}
    raise ValueError(f"physics must be one of {SOFT_PHYSICS}, got {physics!r}")
