"""What the tests share: the episode loop (agents.evaluate.run_episode: the same one the evaluator
runs), bit-for-bit comparison, seeded random rollouts."""

from __future__ import annotations

import numpy as np

from agents.evaluate import Episode, run_episode

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
