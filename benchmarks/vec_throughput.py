"""Env steps/s of SB3's vectorised envs on this machine: one env in-process (DummyVecEnv), then
1, 2, ... up to the core count in subprocesses (SubprocVecEnv, what ``train.py --n-envs N``
uses), in one run, with the speed-up over one subprocess env.

    PYTHONPATH=. python benchmarks/vec_throughput.py [--env SoftGrasp-v2] [--seconds 20] [--max-envs N]

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
        rng = np.random.default_rng(0)
        venv.reset()
        for _ in range(20):  # warm-up
            venv.step(rng.uniform(-1, 1, (n_envs, 4)).astype(np.float32))
        steps, tic = 0, time.perf_counter()
        while time.perf_counter() - tic < seconds:
            venv.step(rng.uniform(-1, 1, (n_envs, 4)).astype(np.float32))
            steps += n_envs
        return steps / (time.perf_counter() - tic)
    finally:
        venv.close()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default="SoftGrasp-v2")
    parser.add_argument("--seconds", type=float, default=20.0, help="timed window per configuration")
    parser.add_argument("--max-envs", type=int, default=os.cpu_count() or 1)
    ns = parser.parse_args()
    if ns.seconds <= 0 or ns.max_envs < 1:
        parser.error("--seconds must be > 0 and --max-envs >= 1")
    for name in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(name, "1")  # as train.py sets for its subprocesses
    print(f"{ns.env}, random actions, {ns.seconds:g} s per configuration, {os.cpu_count()} cores")
    base = measure(ns.env, 1, "dummy", ns.seconds)
    print(f"  DummyVecEnv    1 env : {base:7.0f} env steps/s", flush=True)
    one = None
    for n in range(1, ns.max_envs + 1):
        rate = measure(ns.env, n, "subproc", ns.seconds)
        one = one or rate
        print(f"  SubprocVecEnv {n:2d} envs: {rate:7.0f} env steps/s   x{rate / one:.2f} over 1 subprocess, "
              f"x{rate / base:.2f} over in-process", flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
