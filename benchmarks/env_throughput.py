"""Env steps per second of every registered id, random actions, in one run; and the same for the
scripted grasp policy (contacts active most of the time). One env step is 240 / 20 = 12 physics
steps at the defaults.

    python benchmarks/env_throughput.py [--steps 300]

Prints a table; the machine is shared, so each figure is the best of three runs. Episode resets
are inside the timed loop, as in training.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym

import softgrasp_env
from agents.scripted import ScriptedGraspPolicy


def env_steps_per_second(env_id: str, steps: int, *, scripted: bool, repeats: int = 3) -> float:
    best = 0.0
    for r in range(repeats):
        env = gym.make(env_id)
        policy = ScriptedGraspPolicy.for_env(env)
        env.action_space.seed(r)
        obs, _ = env.reset(seed=r)
        env.step(env.action_space.sample())  # anything left to compile or load
        tic = time.perf_counter()
        for _ in range(steps):
            action = policy(obs) if scripted else env.action_space.sample()
            obs, _, term, trunc, _ = env.step(action)
            if term or trunc:
                obs, _ = env.reset()
        best = max(best, steps / (time.perf_counter() - tic))
        env.close()
    return best


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=300, help="timed env steps per run")
    parser.add_argument("--ids", default="", help="comma-separated ids (default: every registered one)")
    args = parser.parse_args(argv)
    ids = args.ids.split(",") if args.ids else softgrasp_env.ENV_IDS
    unknown = sorted(set(ids) - set(softgrasp_env.ENV_IDS))
    if unknown:
        parser.error(f"unknown ids {unknown}; choose from {', '.join(softgrasp_env.ENV_IDS)}")
    print(f"{'env id':<22}{'random env steps/s':>20}{'scripted env steps/s':>22}{'physics steps/s (random)':>26}")
    for env_id in ids:
        probe = gym.make(env_id)
        sub = probe.unwrapped.args.substeps
        probe.close()
        rnd = env_steps_per_second(env_id, args.steps, scripted=False)
        scr = env_steps_per_second(env_id, args.steps, scripted=True)
        print(f"{env_id:<22}{rnd:>20.0f}{scr:>22.0f}{rnd * sub:>26.0f}")


if __name__ == "__main__":
    main()
