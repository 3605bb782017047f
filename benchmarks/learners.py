"""Learners against each other and against a trivial env (speed; learner_race.py measures success): env
steps/s end to end of SB3's SAC, sb3-contrib's TQC and sbx's (JAX) SAC, TQC and CrossQ on a
SoftGrasp id and on Pendulum-v1, each in its own process on one thread, in one run.

    PYTHONPATH=. python benchmarks/learners.py [--env SoftGrasp-v5] [--steps 2000] [--learners sac,tqc,...]

The ratio env / Pendulum says what the env and our glue cost against the learner itself (the
target: >= 0.7, the env under a third of the learner's time). Each run trains a fresh
model for ``--steps`` env steps after ``WARMUP`` random ones (not timed), with train.py's SAC
preset where the learner takes it (network 128 x 128, batch 256, gamma 0.98, tau 0.02, one
gradient step per two env steps; CrossQ keeps its own network and no target network, as sbx
defines it). Learners whose package is not installed are skipped with a line saying so
(``pip install sb3-contrib sbx-rl``). Success against wall-clock time, the other half,
is ``benchmarks/learner_race.py``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
WARMUP = 300
LEARNERS = {
    "sac": ("stable_baselines3", "SAC"),
    "tqc": ("sb3_contrib", "TQC"),
    "sbx-sac": ("sbx", "SAC"),
    "sbx-tqc": ("sbx", "TQC"),
    "sbx-crossq": ("sbx", "CrossQ"),
}
"""name -> (module, class)."""

ONE_THREAD = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1",
              "XLA_FLAGS": "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"}  # fmt: skip
"""Every learner on one thread (torch's and XLA's CPU pools), read when the process starts."""


def preset(name: str, *, learning_starts: int = WARMUP) -> dict:
    """train.py's SAC preset (agents/baselines.py) where ``name`` takes it; CrossQ keeps sbx's own
    network and learning rate (it has no target network: no tau)."""
    common = {"gamma": 0.98, "batch_size": 256, "learning_starts": learning_starts, "train_freq": 2,
              "buffer_size": 300_000}  # fmt: skip
    if name == "sbx-crossq":
        return common
    return {**common, "learning_rate": 1e-3, "tau": 0.02, "policy_kwargs": {"net_arch": [128, 128]}}


def worker(name: str, env_id: str, steps: int, seed: int) -> float:
    import importlib

    import gymnasium as gym

    import softgrasp_env  # noqa: F401

    module, cls_name = LEARNERS[name]
    if module == "stable_baselines3" or module == "sb3_contrib":
        import torch

        torch.set_num_threads(1)
    cls = getattr(importlib.import_module(module), cls_name)
    env = gym.make(env_id)
    model = cls("MlpPolicy", env, seed=seed, verbose=0, **preset(name))
    model.learn(total_timesteps=WARMUP + 50)  # the random steps and the first updates (JIT compiles)
    tic = time.perf_counter()
    model.learn(total_timesteps=steps, reset_num_timesteps=False)
    rate = steps / (time.perf_counter() - tic)
    env.close()
    return rate


def _run(name: str, env_id: str, steps: int, seed: int) -> float:
    cmd = [sys.executable, __file__, "--worker", name, "--env", env_id, "--steps", str(steps), "--seed", str(seed)]
    env = {**os.environ, **ONE_THREAD, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run(cmd, check=False, cwd=ROOT, capture_output=True, text=True, env=env, timeout=3600)
    if proc.returncode != 0:
        raise RuntimeError(f"{name} on {env_id} failed: {proc.stderr[-1500:]}")
    line = next(ln for ln in reversed(proc.stdout.splitlines()) if ln.startswith("{"))  # pybullet prints argv[0]=
    return float(json.loads(line)["steps_per_second"])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default="SoftGrasp-v5")
    parser.add_argument("--steps", type=int, default=2000, help="timed env steps per learner and env")
    parser.add_argument("--learners", default=",".join(LEARNERS))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    ns = parser.parse_args(argv)
    if ns.worker:
        print(json.dumps({"steps_per_second": worker(ns.worker, ns.env, ns.steps, ns.seed)}))
        return 0
    names = ns.learners.split(",")
    unknown = sorted(set(names) - set(LEARNERS))
    if unknown:
        parser.error(f"unknown learners {unknown}; choose from {', '.join(LEARNERS)}")
    import importlib.util

    print(f"{ns.steps} timed env steps after {WARMUP} random ones, one thread per process; env steps/s end to end")
    print(f"{'learner':<12}{ns.env:>16}{'Pendulum-v1':>14}{'ratio':>8}")
    for name in names:
        module = LEARNERS[name][0]
        if importlib.util.find_spec(module) is None:
            print(f"{name:<12}  skipped: {module} is not installed")
            continue
        ours = _run(name, ns.env, ns.steps, ns.seed)
        pendulum = _run(name, "Pendulum-v1", ns.steps, ns.seed)
        print(f"{name:<12}{ours:>16.0f}{pendulum:>14.0f}{ours / pendulum:>8.2f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
