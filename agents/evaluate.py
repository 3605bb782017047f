"""Evaluate a policy on a SoftGrasp environment: success rate, return, lift.

    python -m agents.evaluate --env SoftGrasp-v5 --policy scripted --episodes 20
    python -m agents.evaluate --policy runs/SoftGrasp-v5_sac_0       # the run's env, kwargs and stats
    python -m agents.evaluate --policy SoftGrasp-v5_sac_1            # a shipped baseline, by name
    .venv-rllib/bin/python -m agents.evaluate --policy runs-rllib/SoftGrasp-v5_rllib-ppo/seed_0   # an RLlib trial

Episodes use seeds ``seed, seed + 1, ...`` so two policies meet the same starts. A learned
policy runs on one torch thread (``--torch-threads N`` for more; agents/threads.py).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from dataclasses import dataclass, field

import gymnasium as gym
import numpy as np

import softgrasp_env
from agents.threads import DEFAULT_TORCH_THREADS, set_threads, threads_error

DEFAULT_ENV = "SoftGrasp-v5"
"""The env of ``--policy scripted`` / ``random`` without ``--env``."""


@dataclass
class Episode:
    """One episode as :func:`run_episode` ran it."""

    steps: int
    total_reward: float
    terminated: bool
    truncated: bool
    observation: object
    """The last observation."""
    info: dict
    """The last step's info (the reset's if no step ran)."""
    successes: int
    """Steps with ``info["is_success"]``."""
    max_lift: float
    """Highest ``info["lift_height"]`` over the steps [m]."""

    @property
    def success(self) -> bool:
        """``is_success`` on the last step: what an episode counts as."""
        return bool(self.info["is_success"])

    @property
    def diverged(self) -> bool:
        return bool(self.info["diverged"])


def run_episode(env: gym.Env, policy: Callable[[object], np.ndarray], *, seed: int | None = None,
                options: dict | None = None, max_steps: int | None = None,
                on_step: Callable[[object, float, bool, bool, dict], None] | None = None) -> Episode:  # fmt: skip
    """Reset ``env`` (``seed``, ``options``) and step ``policy(obs) -> action`` until the episode
    ends, or for ``max_steps`` steps; ``on_step(obs, reward, terminated, truncated, info)`` sees
    every step. A policy with a ``reset()`` (a stateful one: the grip task's scripted policies) is
    reset at the episode's start. The one episode loop the evaluator, the benchmarks and the tests
    share."""
    obs, info = env.reset(seed=seed, options=options)
    reset = getattr(policy, "reset", None)
    if callable(reset):
        reset()
    steps, total, successes, max_lift = 0, 0.0, 0, -np.inf
    terminated = truncated = False
    while not (terminated or truncated) and (max_steps is None or steps < max_steps):
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        steps += 1
        total += float(reward)
        successes += bool(info["is_success"])
        max_lift = max(max_lift, float(info["lift_height"]))
        if on_step is not None:
            on_step(obs, reward, terminated, truncated, info)
    return Episode(steps, total, bool(terminated), bool(truncated), obs, info, successes, float(max_lift))


@dataclass
class Evaluation:
    episodes: int
    success_rate: float
    """Fraction of episodes with ``is_success`` on their last step."""
    mean_return: float
    mean_final_lift: float
    """Cylinder lift at the end of the episode [m]."""
    diverged: int
    by_object: dict[str, tuple[int, int]] = field(default_factory=dict)
    """Per object named by ``info["object"]`` (the object-set ids, or an ``object`` given):
    (successes, episodes), in the order first met; empty where the env names no object."""


def evaluate(env: gym.Env, policy: Callable[[object], np.ndarray], *, episodes: int = 10, seed: int = 0) -> Evaluation:
    """Run ``policy(obs) -> action`` for ``episodes`` episodes on ``env`` (time-limited, as made by
    ``gym.make``)."""
    if episodes < 1:
        raise ValueError(f"episodes must be >= 1, got {episodes}")
    successes, returns, lifts, diverged = [], [], [], 0
    by_object: dict[str, tuple[int, int]] = {}
    for k in range(episodes):
        ep = run_episode(env, policy, seed=seed + k)
        successes.append(ep.success)
        returns.append(ep.total_reward)
        lifts.append(float(ep.info["lift_height"]))
        diverged += ep.diverged
        if "object" in ep.info:
            won, met = by_object.get(ep.info["object"], (0, 0))
            by_object[ep.info["object"]] = (won + ep.success, met + 1)
    return Evaluation(episodes, float(np.mean(successes)), float(np.mean(returns)), float(np.mean(lifts)), diverged,
                      by_object)  # fmt: skip


def object_line(by_object: dict[str, tuple[int, int]]) -> str:
    """``by_object`` as one line, objects by name: ``cone 8/9, cube 10/10, ...``."""
    return ", ".join(f"{name} {won}/{met}" for name, (won, met) in sorted(by_object.items()))


def resolve(spec: str) -> str:
    """``spec`` as :func:`load_policy` takes it: the name of a shipped baseline
    (``softgrasp_env.policies.list_baselines()``) becomes its folder, unless a path of that name
    exists here; anything else is left as it is."""
    from pathlib import Path

    from softgrasp_env.policies import baseline_path, list_baselines

    if spec not in ("scripted", "random") and not Path(spec).exists() and spec in list_baselines():
        return str(baseline_path(spec))
    return spec


def load_policy(spec: str, env: gym.Env, *, other_env: bool = False) -> Callable[[object], np.ndarray]:
    """``"scripted"``, ``"random"``, a run saved by train.py (its directory, model.zip or a
    checkpoint zip; a shipped baseline is one, by folder or by name), loaded by
    :func:`agents.runs.load_run` (observation statistics applied there), or an RLlib trial of
    agents.rllib_train (its directory or a checkpoint in it,
    :func:`agents.rllib_policy.load_rllib_policy`: its observation filter applied there)."""
    spec = resolve(spec)
    if spec == "scripted":
        from softgrasp_env.policies import ScriptedGraspPolicy

        return ScriptedGraspPolicy.for_env(env)
    if spec == "random":
        return lambda obs: env.action_space.sample()
    from agents.rllib_policy import is_rllib_run, load_rllib_policy

    if is_rllib_run(spec):
        return load_rllib_policy(spec, env, other_env=other_env)
    from agents.runs import load_run

    return load_run(spec, env=env, other_env=other_env).policy


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m agents.evaluate", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    parser.add_argument("--env", default=None, choices=softgrasp_env.ENV_IDS,
                        help=f"default: the run's env (with its env kwargs) for a saved model, else {DEFAULT_ENV}")
    parser.add_argument("--policy", default="scripted",
                        help="'scripted', 'random', a run from train.py (its directory, model.zip or a checkpoint), "
                             "a shipped baseline by name (e.g. SoftGrasp-v5_sac_1) or an RLlib trial from "
                             "agents.rllib_train (its directory or a checkpoint_<N>)")  # fmt: skip
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--seed", type=int, default=1000)
    parser.add_argument("--other-env", action="store_true",
                        help="allow --env to differ from the run's env (same spaces), e.g. a soft-trained policy "
                             "on SoftGraspRigid-v3")  # fmt: skip
    parser.add_argument("--torch-threads", type=int, default=DEFAULT_TORCH_THREADS, metavar="N",
                        help="torch threads for a learned policy (default 1; agents/threads.py says why)")
    ns = parser.parse_args(argv)
    problem = threads_error(ns.torch_threads)
    if problem:
        parser.error(f"--torch-threads: {problem}")
    env = None
    try:
        if ns.policy in ("scripted", "random"):
            env = gym.make(ns.env or DEFAULT_ENV)
            ns.env = env.spec.id if env.spec is not None else ns.env or DEFAULT_ENV  # printed below
            policy = load_policy(ns.policy, env)
        else:
            from agents.rllib_policy import is_rllib_run, locate
            from agents.runs import make_env, run_files

            set_threads(ns.torch_threads)
            spec = resolve(ns.policy)
            # The env is re-created as the run made it: same id (unless --env says otherwise), same kwargs.
            meta = locate(spec)[0] if is_rllib_run(spec) else run_files(spec).meta
            env = make_env(meta, env_id=ns.env)
            ns.env = env.spec.id if env.spec is not None else meta["env"]
            policy = load_policy(spec, env, other_env=ns.other_env)
        env.action_space.seed(ns.seed)
        ev = evaluate(env, policy, episodes=ns.episodes, seed=ns.seed)
    except ValueError as exc:
        parser.error(str(exc))
    finally:
        if env is not None:
            env.close()
    print(f"{ns.env} / {ns.policy}: success {ev.success_rate:.0%} over {ev.episodes} episodes, mean return "
          f"{ev.mean_return:.2f}, mean final lift {ev.mean_final_lift * 100:.2f} cm, diverged {ev.diverged}")  # fmt: skip
    if ev.by_object:
        print("per object: " + object_line(ev.by_object))
    return 0


if __name__ == "__main__":
    sys.exit(main())
