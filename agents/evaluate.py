"""Evaluate a policy on a SoftGrasp environment: success rate, return, lift.

    python -m agents.evaluate --env SoftGrasp-v0 --policy scripted --episodes 20
    python -m agents.evaluate --env SoftGrasp-v0 --policy runs/SoftGrasp-v0_sac_0/model.zip

Episodes use seeds ``seed, seed + 1, ...`` so two policies meet the same starts.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)


@dataclass
class Evaluation:
    episodes: int
    success_rate: float
    """Fraction of episodes with ``is_success`` on their last step."""
    mean_return: float
    mean_final_lift: float
    """Cylinder lift at the end of the episode [m]."""
    diverged: int


def evaluate(env: gym.Env, policy: Callable[[object], np.ndarray], *, episodes: int = 10, seed: int = 0) -> Evaluation:
    """Run ``policy(obs) -> action`` for ``episodes`` episodes on ``env`` (time-limited, as made by
    ``gym.make``)."""
    if episodes < 1:
        raise ValueError(f"episodes must be >= 1, got {episodes}")
    successes, returns, lifts, diverged = [], [], [], 0
    for k in range(episodes):
        obs, info = env.reset(seed=seed + k)
        total, done = 0.0, False
        while not done:
            obs, r, term, trunc, info = env.step(policy(obs))
            total += float(r)
            done = term or trunc
        successes.append(bool(info["is_success"]))
        returns.append(total)
        lifts.append(float(info["lift_height"]))
        diverged += bool(info["diverged"])
    return Evaluation(episodes, float(np.mean(successes)), float(np.mean(returns)), float(np.mean(lifts)), diverged)


def load_policy(spec: str, env: gym.Env) -> Callable[[object], np.ndarray]:
    """``"scripted"``, ``"random"`` or the path of a model saved by train.py (its VecNormalize
    statistics are picked up from beside it)."""
    if spec == "scripted":
        from agents.scripted import ScriptedGraspPolicy

        return ScriptedGraspPolicy()
    if spec == "random":
        return lambda obs: env.action_space.sample()
    import json
    from pathlib import Path

    from agents.baselines import model_class

    path = Path(spec)
    if not path.exists():
        raise ValueError(f"policy must be 'scripted', 'random' or a saved model file; {spec!r} does not exist")
    meta = path.parent / "run.json"
    if not meta.exists():
        raise ValueError(f"no run.json beside {spec!r}; was it saved by train.py?")
    algo = json.loads(meta.read_text())["algo"]
    kwargs = {"env": env} if algo == "her-sac" else {}  # HER's buffer needs the env to load
    model = model_class(algo).load(str(path), device="cpu", **kwargs)
    norm = _load_obs_normaliser(path.parent / "vecnormalize.pkl")

    def act(obs):
        action, _ = model.predict(norm(obs), deterministic=True)
        return action

    return act


def _load_obs_normaliser(path) -> Callable[[object], object]:
    if not path.exists():
        return lambda obs: obs
    import pickle

    with open(path, "rb") as f:
        vn = pickle.load(f)
    return vn.normalize_obs


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m agents.evaluate", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    parser.add_argument("--env", default="SoftGrasp-v0", choices=softgrasp_env.ENV_IDS)
    parser.add_argument("--policy", default="scripted", help="'scripted', 'random' or a model.zip from train.py")
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--seed", type=int, default=1000)
    ns = parser.parse_args(argv)
    env = gym.make(ns.env)
    try:
        policy = load_policy(ns.policy, env)
        env.action_space.seed(ns.seed)
        ev = evaluate(env, policy, episodes=ns.episodes, seed=ns.seed)
    except ValueError as exc:
        parser.error(str(exc))
    finally:
        env.close()
    print(f"{ns.env} / {ns.policy}: success {ev.success_rate:.0%} over {ev.episodes} episodes, mean return "
          f"{ev.mean_return:.2f}, mean final lift {ev.mean_final_lift * 100:.2f} cm, diverged {ev.diverged}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
