"""Torch threads against training speed: SB3's SAC with train.py's preset on SoftGrasp-v5 (the
docs' figures were measured on SoftGrasp-v3, retired), end to end (env steps and gradient steps
together), at 1 and 2 torch threads, one process alone and two side by side (two seeds at a time,
as the baselines were trained), in one run.

    PYTHONPATH=. python benchmarks/torch_threads.py [--steps 1500] [--threads 1,2] [--env SoftGrasp-v5]

Each configuration trains a fresh model for ``--steps`` env steps after 200 random ones (its
learning_starts) and prints the env steps/s of the timed part; side by side, both processes'
figures. Every process runs its env on one numba thread (agents/threads.py).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
WARMUP = 200
"""Random env steps before learning (SAC's learning_starts): not timed."""


def worker(env_id: str, threads: int, steps: int, seed: int) -> float:
    """Env steps/s of SAC training for ``steps`` steps after the warm-up, on ``threads`` threads."""
    import gymnasium as gym

    import softgrasp_env  # noqa: F401
    from agents.baselines import make_model
    from agents.threads import set_threads

    got = set_threads(threads)
    env = gym.make(env_id)
    model = make_model("sac", env, seed=seed, learning_starts=WARMUP)
    model.learn(total_timesteps=WARMUP)  # the random steps, then the first gradient step's set-up
    tic = time.perf_counter()
    model.learn(total_timesteps=steps, reset_num_timesteps=False)
    rate = steps / (time.perf_counter() - tic)
    env.close()
    assert got["torch"] == threads, got
    return rate


def _launch(env_id: str, threads: int, steps: int, seed: int) -> subprocess.Popen:
    cmd = [sys.executable, __file__, "--worker", "--env", env_id, "--threads", str(threads), "--steps", str(steps),
           "--seed", str(seed)]  # fmt: skip
    return subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                            env={**__import__("os").environ, "PYTHONPATH": str(ROOT)})  # fmt: skip


def _result(proc: subprocess.Popen) -> float:
    out, _ = proc.communicate()
    if proc.returncode != 0:
        raise RuntimeError(f"worker failed ({proc.returncode}): {out}")
    line = next(ln for ln in reversed(out.splitlines()) if ln.startswith("{"))  # pybullet prints argv[0]= lines
    return float(json.loads(line)["steps_per_second"])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default="SoftGrasp-v5")
    parser.add_argument("--steps", type=int, default=1500, help="timed env steps per configuration")
    parser.add_argument("--threads", default="1,2", help="comma-separated torch thread counts")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ns = parser.parse_args(argv)
    if ns.steps < 1:
        parser.error(f"--steps must be >= 1, got {ns.steps}")
    if ns.worker:
        print(json.dumps({"steps_per_second": worker(ns.env, int(ns.threads), ns.steps, ns.seed)}))
        return 0
    counts = [int(t) for t in ns.threads.split(",")]
    print(
        f"SAC (train.py's preset) on {ns.env}, {ns.steps} timed env steps after {WARMUP} random ones; "
        f"env steps/s end to end"
    )
    print(f"{'torch threads':>14}{'alone':>10}{'side by side (each)':>26}")
    for n in counts:
        alone = _result(_launch(ns.env, n, ns.steps, ns.seed))
        pair = [_launch(ns.env, n, ns.steps, ns.seed + k) for k in (1, 2)]
        both = [_result(p) for p in pair]
        print(f"{n:>14}{alone:>10.0f}{both[0]:>16.0f} / {both[1]:.0f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
