"""Env steps/s of SB3's vectorised envs on the machine it runs on: one env in-process (DummyVecEnv), then
1, 2, ... up to the core count in subprocesses (SubprocVecEnv, what ``train.py --n-envs N``
uses), then gymnasium's own ``gym.make_vec(..., vectorization_mode="async")`` the same way, in
one run, with the speed-up over one subprocess env; with ``--rllib`` (in the RLlib venv)
also RLlib sampling with 1, 2, ... env runners (what ``agents.rllib_train --num-env-runners N``
uses), and what 64 cores over several machines would give at the measured per-runner rate.

    PYTHONPATH=. python benchmarks/vec_throughput.py [--env SoftGrasp-v5] [--seconds 20] [--max-envs N]
    PYTHONPATH=. .venv-rllib/bin/python benchmarks/vec_throughput.py --rllib     # SB3 and RLlib in one run

Random actions, seeded; each configuration is warmed up (process start, numba's cached kernels
loaded, first reset) before the timed window. Only stepping is timed; the policy is not (a
trainer adds its own cost on top: SB3's PPO update, SAC's gradient steps). On a shared machine
the figures vary by 10-20 % from run to run: compare the ratios within one run.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

import softgrasp_env  # noqa: F401  (at the top: SubprocVecEnv's workers import this module, and with it the ids)


def measure(env_id: str, n_envs: int, vec: str, seconds: float) -> float:
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    cls = SubprocVecEnv if vec == "subproc" else DummyVecEnv
    venv = make_vec_env(env_id, n_envs=n_envs, seed=0, vec_env_cls=cls)
    try:
        venv.reset()
        return _stepping_rate(venv, n_envs, seconds)
    finally:
        venv.close()


def _stepping_rate(venv, n_envs: int, seconds: float) -> float:
    """Env steps/s of a reset vector env (SB3's or gymnasium's: both step an (n, 4) batch) under
    seeded random actions, after 20 warm-up steps."""
    rng = np.random.default_rng(0)
    for _ in range(20):
        venv.step(rng.uniform(-1, 1, (n_envs, 4)).astype(np.float32))
    steps, tic = 0, time.perf_counter()
    while time.perf_counter() - tic < seconds:
        venv.step(rng.uniform(-1, 1, (n_envs, 4)).astype(np.float32))
        steps += n_envs
    return steps / (time.perf_counter() - tic)


def measure_gym(env_id: str, n_envs: int, mode: str, seconds: float) -> float:
    """Env steps/s of gymnasium's own vector env: ``gym.make_vec(..., vectorization_mode=mode)``
    ("sync": in this process, one after the other; "async": one subprocess each)."""
    import gymnasium as gym

    venv = gym.make_vec(env_id, num_envs=n_envs, vectorization_mode=mode)
    try:
        venv.reset(seed=0)
        return _stepping_rate(venv, n_envs, seconds)
    finally:
        venv.close()


def measure_rllib(env_id: str, n_runners: int, seconds: float) -> float:
    """Env steps/s RLlib's env runners sample with PPO's (untrained) policy: every runner samples
    at once, 200 steps per call, for ``seconds``; the learner does not train (sampling only, as
    the SB3 figures are stepping only)."""
    from agents.rllib_train import build_algorithm

    algo = build_algorithm(env_id, num_env_runners=n_runners, num_cpus_per_env_runner=0.5)
    try:
        group = algo.env_runner_group
        group.foreach_env_runner(lambda r: r.sample(num_timesteps=100), local_env_runner=False)  # warm-up
        steps, tic = 0, time.perf_counter()
        while time.perf_counter() - tic < seconds:
            episodes = group.foreach_env_runner(lambda r: r.sample(num_timesteps=200), local_env_runner=False)
            steps += sum(len(e) for batch in episodes for e in batch)
        return steps / (time.perf_counter() - tic)
    finally:
        algo.stop()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default="SoftGrasp-v5")
    parser.add_argument("--seconds", type=float, default=20.0, help="timed window per configuration")
    parser.add_argument("--max-envs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--rllib", action="store_true", help="also RLlib env runners (needs Ray: .venv-rllib)")
    ns = parser.parse_args()
    if ns.seconds <= 0 or ns.max_envs < 1:
        parser.error("--seconds must be > 0 and --max-envs >= 1")
    for name in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(name, "1")  # as train.py sets for its subprocesses
    print(f"{ns.env}, random actions, {ns.seconds:g} s per configuration, {os.cpu_count()} cores")
    base = measure(ns.env, 1, "dummy", ns.seconds)
    print(f"  DummyVecEnv    1 env : {base:7.0f} env steps/s", flush=True)
    runners = (("SubprocVecEnv", "", lambda n: measure(ns.env, n, "subproc", ns.seconds)),
               ("gym.make_vec ", " (async)", lambda n: measure_gym(ns.env, n, "async", ns.seconds)))  # fmt: skip
    for label, note, run in runners:
        one = None
        for n in range(1, ns.max_envs + 1):
            rate = run(n)
            one = one or rate
            print(f"  {label} {n:2d} envs{note}: {rate:7.0f} env steps/s   x{rate / one:.2f} over 1 subprocess, "
                  f"x{rate / base:.2f} over in-process", flush=True)  # fmt: skip
    if ns.rllib:
        import ray

        ray.init(num_cpus=os.cpu_count(), include_dashboard=False, log_to_driver=False)
        try:
            first = None
            for n in range(1, ns.max_envs + 1):
                rate = measure_rllib(ns.env, n, ns.seconds)
                first = first or rate
                print(f"  RLlib         {n:2d} env runners: {rate:7.0f} env steps/s   x{rate / first:.2f} over 1 runner",
                      flush=True)  # fmt: skip
            per_core = rate / ns.max_envs
            print(f"  on paper, 64 cores (one env runner each, learner aside) at {per_core:.0f} env steps/s per runner: "
                  f"{64 * per_core:,.0f} env steps/s; 10 M steps in {1e7 / (64 * per_core) / 60:.0f} min of sampling")
        finally:
            ray.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
