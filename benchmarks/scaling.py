"""How an env step's cost grows with the tissue's particles: per density, the particles, the world
steps per physics step, env steps/s, the tissue kernel's time per call and per particle per
iteration, and the exponent of each in the particle count (a least-squares fit of the logs).

    PYTHONPATH=. python benchmarks/scaling.py [--densities 4000,16000,64000,256000] [--steps 20]
        [--repeats 2] [--threads 1] [--material-solve global] [--global-linear-solve multigrid]

SoftGraspEasy-v4 (the v4 tissue, layers 'auto': 1 / 1 / 2 / 4 at the four densities), random
actions (seed 0), resets inside the loop. The kernel's time is the solver's step timed around each
call (TissueSolver.step: the compiled step and its few microseconds of Python). Best of
``--repeats`` per density (the machine is shared). A cost linear in particles fits an exponent of
1; the env step's exponent is the kernel's plus the world steps', which grow as the groups
stiffen (compliant.substeps_for: kappa ~ G / (rho l^2)). ``--material-solve global`` solves the
material across its groups (gym.make's material_solve): the world steps are then the coupling's
alone, and the kernel's cost is the factor's solve's; ``--global-linear-solve multigrid`` solves
that system by a V-cycle a pass instead (gym.make's global_linear_solve).
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)


def measure(density: float, steps: int, threads: int, material_solve: str | None = None,
            linear_solve: str | None = None) -> dict:  # fmt: skip
    env = gym.make("SoftGraspEasy-v4", particle_density=density, threads=threads, material_solve=material_solve,
                   global_linear_solve=linear_solve)  # fmt: skip
    try:
        env.reset(seed=0)
        world = env.unwrapped.scene.world
        solver = world.solver
        spent = [0.0, 0]
        original = solver.step

        def timed(state, col):
            tic = time.perf_counter()
            out = original(state, col)
            spent[0] += time.perf_counter() - tic
            spent[1] += 1
            return out

        solver.step = timed
        rng = np.random.default_rng(0)
        env.step(rng.uniform(-1.0, 1.0, size=4).astype(np.float32))  # compile / load
        spent[:] = [0.0, 0]
        tic = time.perf_counter()
        for _ in range(steps):
            _, _, terminated, truncated, _ = env.step(rng.uniform(-1.0, 1.0, size=4).astype(np.float32))
            if terminated or truncated:
                env.reset()
        wall = time.perf_counter() - tic
        n = world.model.particle_count
        kernel = spent[0] / spent[1]
        return {"particles": n, "substeps": world.substeps, "rate": steps / wall, "kernel_us": kernel * 1e6,
                "per_particle_iter_us": kernel * 1e6 / (n * world.sim.iterations),
                "kernel_share": spent[0] / wall}  # fmt: skip
    finally:
        env.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--densities", default="4000,16000,64000,256000")
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--material-solve", choices=("groups", "global"), default=None,
                        help="how the material is solved (gym.make's material_solve; default: the id's)")
    parser.add_argument("--global-linear-solve", choices=("direct", "multigrid"), default=None,
                        help="how the global solve's passes solve their system (gym.make's global_linear_solve)")
    args = parser.parse_args()
    rows = []
    print(f"threads {args.threads}; best of {args.repeats}; material solve {args.material_solve or 'the id default'}"
          f"{'; linear solve ' + args.global_linear_solve if args.global_linear_solve else ''}")  # fmt: skip
    print(f"{'density':>9} {'particles':>9} {'world steps':>11} {'env steps/s':>11} {'kernel us':>10} "
          f"{'us/particle/iter':>16} {'kernel share':>12}")  # fmt: skip
    for d in (float(x) for x in args.densities.split(",")):
        best = None
        for _ in range(args.repeats):
            r = measure(d, args.steps, args.threads, args.material_solve, args.global_linear_solve)
            if best is None or r["rate"] > best["rate"]:
                best = r
        rows.append(best)
        print(f"{d:9.0f} {best['particles']:9d} {best['substeps']:11d} {best['rate']:11.2f} {best['kernel_us']:10.0f} "
              f"{best['per_particle_iter_us']:16.3f} {best['kernel_share']:12.2f}")  # fmt: skip
    if len(rows) > 1:
        p = np.log([r["particles"] for r in rows])
        for key, label in (("rate", "env step time"), ("kernel_us", "kernel per call"), ("substeps", "world steps")):
            y = np.log([r[key] for r in rows])
            slope = np.polyfit(p, y, 1)[0]
            print(f"{label:>16} ~ particles^{-slope if key == 'rate' else slope:.2f}")


if __name__ == "__main__":
    main()
