"""The tissue solver on one thread and on two (SimConfig.threads: each finger's pad swept on a
thread of its own), env steps per second side by side, per particle density.

    PYTHONPATH=. python benchmarks/threads.py [--densities 16000,64000,256000] [--steps 20] [--repeats 3]
        [--material-solve global]   # the material solved across its groups, each pad's block on a thread

SoftGraspEasy-v4 with random actions (seed 0), layers as the v4 ids have them ('auto'); the two
counts alternate, best of ``--repeats`` each, so that a neighbour's load falls on both alike. The
two runs must end in the same particle state to the bit (checked). Printed: particles, env steps/s
on 1 and 2 threads and their ratio. Needs two free cores to mean anything: a thread that waits
for a busy core stalls the other at every sweep.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numba
import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.config import MATERIAL_SOLVES


def run(density: float, threads: int, steps: int, solve: str = "groups") -> tuple[float, np.ndarray, int]:
    """(env steps/s over ``steps`` random steps after a warm-up step, final particle positions,
    particle count); ``solve``: gym.make's material_solve."""
    env = gym.make("SoftGraspEasy-v4", particle_density=density, threads=threads, material_solve=solve)
    try:
        env.reset(seed=0)
        rng = np.random.default_rng(0)
        env.step(rng.uniform(-1.0, 1.0, size=4).astype(np.float32))  # compile / load the kernels
        tic = time.perf_counter()
        for _ in range(steps):
            _, _, terminated, truncated, _ = env.step(rng.uniform(-1.0, 1.0, size=4).astype(np.float32))
            if terminated or truncated:
                env.reset()
        rate = steps / (time.perf_counter() - tic)
        world = env.unwrapped.scene.world
        return rate, world.state.particle_x.copy(), world.model.particle_count
    finally:
        env.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--densities", default="16000,64000,256000")
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--material-solve", default="groups", choices=MATERIAL_SOLVES)
    args = parser.parse_args()
    if numba.config.NUMBA_NUM_THREADS < 2:
        raise SystemExit("numba has one thread here (NUMBA_NUM_THREADS): nothing to compare")
    print(f"{'density':>9} {'particles':>9} {'1 thread':>9} {'2 threads':>9} {'ratio':>6}  (env steps/s, best of "
          f"{args.repeats}; material_solve={args.material_solve!r})")
    for d in (float(x) for x in args.densities.split(",")):
        best = {1: 0.0, 2: 0.0}
        final = {}
        for _ in range(args.repeats):
            for threads in (1, 2):
                rate, x, n = run(d, threads, args.steps, args.material_solve)
                best[threads] = max(best[threads], rate)
                final[threads] = x
        if final[1].tobytes() != final[2].tobytes():
            raise SystemExit(f"1 and 2 threads disagree at {d:.0f} per m^2")
        print(f"{d:9.0f} {n:9d} {best[1]:9.2f} {best[2]:9.2f} {best[2] / best[1]:6.2f}")


if __name__ == "__main__":
    main()
