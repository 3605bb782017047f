"""Seeded trajectories of every registered id (and of the finger kinds reached only through
kwargs), recorded through the public API alone: ``gym.make``, ``reset``, ``step`` and the scripted
policy. ``tests/data/trajectories.npz`` holds the v1/v2 ids as recorded before issue 18's
restructuring, ``tests/data/trajectories_v3.npz`` the v3 ids as 0.5.0 shipped them (recorded
before issue 20's speed work); ``tests/test_trajectories.py`` replays them and asserts
bit-identical observations, rewards and flags, so a refactor or a speed-up that changes behaviour
cannot land quietly.

Record again (only when behaviour is meant to change, with the ids moving version, or the change
named and measured):

    python -m tests.trajectories [--set v1v2 | v3]
"""

from __future__ import annotations

import platform
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np

DATA = Path(__file__).parent / "data" / "trajectories.npz"
DATA_V3 = Path(__file__).parent / "data" / "trajectories_v3.npz"

INFO_FLAGS = ("is_success", "held", "carrying", "diverged", "action_clipped")
"""Boolean info entries recorded per step."""

# (case name, env id, gym.make kwargs, policy, steps). "random" draws actions in [-1.2, 1.2]
# (clipping exercised) and resets after an episode ends; "scripted" runs the scripted policy.
CASES: tuple[tuple[str, str, dict, str, int], ...] = (
    *((f"{env_id}/random", env_id, {}, "random", 130) for env_id in (
        "SoftGrasp-v2", "SoftGraspRigid-v2", "SoftGraspSparse-v2", "SoftGrasp-v1", "SoftGraspRigid-v1",
        "SoftGraspSparse-v1", "SoftGraspGoal-v1", "SoftGraspEasy-v1", "SoftGraspEasyRigid-v1")),
    *((f"{env_id}/scripted", env_id, {}, "scripted", 100) for env_id in (
        "SoftGrasp-v2", "SoftGraspRigid-v2", "SoftGraspSparse-v2", "SoftGrasp-v1", "SoftGraspRigid-v1",
        "SoftGraspSparse-v1", "SoftGraspGoal-v1", "SoftGraspEasy-v1", "SoftGraspEasyRigid-v1")),
    ("segmented/scripted", "SoftGraspEasy-v1", {"fingers": "segmented"}, "scripted", 60),
    ("segmented/random", "SoftGrasp-v2", {"fingers": "segmented"}, "random", 40),
    ("fem/scripted", "SoftGraspEasy-v1", {"fingers": "fem"}, "scripted", 12),
    ("tissue-all-consistent/random", "SoftGrasp-v2",
     {"tissue_faces": "all", "sim": "consistent"}, "random", 40),
    ("fast-preset/scripted", "SoftGrasp-v2", {"preset": "fast"}, "scripted", 60),
    ("ranges/random", "SoftGraspRigid-v2",
     {"friction_range": 0.3, "cylinder_mass_range": 0.5, "cylinder_radius_range": 0.005}, "random", 60),
)  # fmt: skip

V3_IDS = ("SoftGrasp-v3", "SoftGraspRigid-v3", "SoftGraspSparse-v3", "SoftGraspGoal-v3", "SoftGraspEasy-v3",
          "SoftGraspEasyRigid-v3", "SoftGraspRigidTorsion-v3", "SoftGraspEasyRigidTorsion-v3")
V3_CASES: tuple[tuple[str, str, dict, str, int], ...] = (
    *((f"{env_id}/random", env_id, {}, "random", 130) for env_id in V3_IDS),
    *((f"{env_id}/scripted", env_id, {}, "scripted", 100) for env_id in V3_IDS),  # through the carry (3.5-5 s)
    ("v3-consistent/scripted", "SoftGrasp-v3", {"sim": "consistent"}, "scripted", 100),
    ("v3-per-step/random", "SoftGrasp-v3", {"tissue_material": "per_step"}, "random", 60),
    ("v3-dt1000/scripted", "SoftGraspEasy-v3", {"sim": "dt1000"}, "scripted", 40),
    ("v3-dt120/scripted", "SoftGraspEasy-v3", {"sim": "dt120"}, "scripted", 60),
)  # fmt: skip
"""The v3 ids (issue 19's physics) and the settings a speed-up might treat differently: the
consistent coupling, the per-step material, one world substep (1/1000 s) and four (1/120 s)."""


def _kwargs(kwargs: dict) -> dict:
    out = dict(kwargs)
    if out.get("sim") == "consistent":  # a SimConfig is not an npz-friendly literal: named here
        from softgrasp_env.config import SimConfig

        out["sim"] = SimConfig(coupling="consistent")
    elif isinstance(out.get("sim"), str) and out["sim"].startswith("dt"):
        from softgrasp_env.config import SimConfig

        out["sim"] = SimConfig(dt=1.0 / int(out["sim"][2:]))
    return out


def _obs_vector(obs) -> np.ndarray:
    if isinstance(obs, dict):
        return np.concatenate([obs["observation"], obs["achieved_goal"], obs["desired_goal"]])
    return np.asarray(obs)


def record(env_id: str, kwargs: dict, policy: str, steps: int, *, seed: int = 7) -> dict[str, np.ndarray]:
    """One case: arrays of the observations (reset's first), rewards, terminated / truncated, the
    info flags, lift heights and reward terms, step by step."""
    from agents.scripted import ScriptedGraspPolicy

    env = gym.make(env_id, **_kwargs(kwargs))
    rng = np.random.default_rng(seed + 1)
    scripted = ScriptedGraspPolicy.for_env(env)
    obs, info = env.reset(seed=seed)
    rows: dict[str, list] = {k: [] for k in ("obs", "reward", "terminated", "truncated", "lift", "terms", "reset",
                                             *INFO_FLAGS)}  # fmt: skip
    rows["obs"].append(_obs_vector(obs))
    rows["reset"].append(True)
    for _ in range(steps):
        if policy == "random":
            action = rng.uniform(-1.2, 1.2, size=4).astype(np.float32)
        else:
            action = scripted(obs)
        obs, reward, terminated, truncated, info = env.step(action)
        rows["obs"].append(_obs_vector(obs))
        rows["reward"].append(float(reward))
        rows["terminated"].append(bool(terminated))
        rows["truncated"].append(bool(truncated))
        rows["lift"].append(float(info["lift_height"]))
        terms = info.get("reward_terms", {})
        rows["terms"].append([float(terms[k]) for k in sorted(terms)])
        for k in INFO_FLAGS:
            rows[k].append(bool(info[k]))
        rows["reset"].append(False)
        if terminated or truncated:
            obs, info = env.reset()
            rows["obs"].append(_obs_vector(obs))
            rows["reset"].append(True)
    env.close()
    return {k: np.asarray(v) for k, v in rows.items()}


def fingerprint() -> str:
    """The instruction set and libraries a recording was made on: bit-identity is promised on the
    same ones (a CPU with other vector units may take another code path in a library's sin or
    exp and round differently; the CPU's model name does not matter)."""
    import numba
    import pybullet

    flags = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("flags"):
                have = set(line.split(":", 1)[1].split())
                flags = ",".join(f for f in ("fma", "avx2", "avx512f") if f in have)
                break
    except OSError:
        pass
    return (f"{platform.machine()} [{flags}] python {sys.version.split()[0]} numpy {np.__version__} "
            f"numba {numba.__version__} pybullet {pybullet.getAPIVersion()}")  # fmt: skip


SETS = {"v1v2": (CASES, DATA), "v3": (V3_CASES, DATA_V3)}


def main(argv: list[str] | None = None) -> None:
    import argparse

    import softgrasp_env  # noqa: F401  (registers the ids)

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--set", choices=sorted(SETS), default="v1v2")
    cases, path = SETS[parser.parse_args(argv).set]
    out: dict[str, np.ndarray] = {"fingerprint": np.array(fingerprint())}
    for name, env_id, kwargs, policy, steps in cases:
        for key, arr in record(env_id, kwargs, policy, steps).items():
            out[f"{name}/{key}"] = arr
        print(f"{name}: {steps} steps")
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **out)
    print(f"wrote {path} ({path.stat().st_size / 1024:.0f} kB) on {out['fingerprint']}")


if __name__ == "__main__":
    main()
