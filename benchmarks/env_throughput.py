"""Env steps per second of every registered id, random actions, in one run; and the same for the
scripted grasp policy (contacts active most of the time). One env step is 240 / 20 = 12 physics
steps at the defaults.

    python benchmarks/env_throughput.py [--steps 300] [--ids ID,ID@key=value@key=value,...]

An id may carry ``gym.make`` keyword arguments after ``@`` (values read as Python literals, else
as strings), so a setting is timed beside the default in the same run, e.g.
``--ids SoftGrasp-v5,SoftGrasp-v5@tissue_contact_cone=True`` (the cones' cost),
``--ids SoftGrasp-v5,"SoftGrasp-v5@tactile=(4,3)"`` (the taxels' cost).

Prints a table; the machine is shared, so each figure is the best of three runs. Episode resets
are inside the timed loop, as in training.
"""

from __future__ import annotations

import argparse
import ast
import time

import gymnasium as gym

import softgrasp_env
from agents.scripted import ScriptedGraspPolicy


def split_specs(text: str) -> list[str]:
    """The comma-separated specs of ``--ids``; a comma inside brackets belongs to a value
    (``SoftGrasp-v5@tactile=(4,3)``)."""
    specs, depth, start = [], 0, 0
    for k, ch in enumerate(text):
        depth += ch in "([{"
        depth -= ch in ")]}"
        if ch == "," and depth == 0:
            specs.append(text[start:k])
            start = k + 1
    specs.append(text[start:])
    return [s for s in specs if s]


def parse_spec(spec: str) -> tuple[str, dict]:
    """``"ID@key=value@..."`` -> (ID, kwargs); a malformed keyword argument is an error naming it."""
    env_id, *pairs = spec.split("@")
    kwargs = {}
    for pair in pairs:
        key, sep, text = pair.partition("=")
        if not sep or not key:
            raise ValueError(f"{spec!r}: {pair!r} is not key=value")
        try:
            kwargs[key] = ast.literal_eval(text)
        except (ValueError, SyntaxError):
            kwargs[key] = text
    return env_id, kwargs


def env_steps_per_second(env_id: str, steps: int, *, scripted: bool, repeats: int = 3, **kwargs) -> float:
    best = 0.0
    for r in range(repeats):
        env = gym.make(env_id, **kwargs)
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
    specs = split_specs(args.ids) if args.ids else softgrasp_env.ENV_IDS
    try:
        runs = [(spec, *parse_spec(spec)) for spec in specs]
    except ValueError as err:
        parser.error(str(err))
    unknown = sorted({env_id for _, env_id, _ in runs} - set(softgrasp_env.ENV_IDS))
    if unknown:
        parser.error(f"unknown ids {unknown}; choose from {', '.join(softgrasp_env.ENV_IDS)}")
    width = max(22, *(len(spec) + 2 for spec in specs))
    print(f"{'env id':<{width}}{'random env steps/s':>20}{'scripted env steps/s':>22}{'physics steps/s (random)':>26}")
    for spec, env_id, kwargs in runs:
        probe = gym.make(env_id, **kwargs)
        sub = probe.unwrapped.plan.substeps
        probe.close()
        rnd = env_steps_per_second(env_id, args.steps, scripted=False, **kwargs)
        scr = env_steps_per_second(env_id, args.steps, scripted=True, **kwargs)
        print(f"{spec:<{width}}{rnd:>20.0f}{scr:>22.0f}{rnd * sub:>26.0f}")


if __name__ == "__main__":
    main()
