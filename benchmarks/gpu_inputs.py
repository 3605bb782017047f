"""The measured inputs of the GPU cost model (docs/results/gpu.md), per preset of SoftGraspEasy-v4:
particles and groups, members per group, world steps per physics step, group solves per env step,
the solver's bytes per particle (state, model and scratch), the greedy colouring of the groups'
conflict graph (two groups conflict if they share a member, so a Gauss-Seidel sweep cannot solve
them at once), and pybullet's time per world step in the default scene.

    PYTHONPATH=. python benchmarks/gpu_inputs.py [--presets default,fine,converged] [--steps 100]
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)

PHYSICS_STEPS_PER_ENV_STEP = 12  # 1/240 s physics steps in one 1/20 s env step


def greedy_colours(offsets: np.ndarray, members: np.ndarray) -> np.ndarray:
    """Each group's colour, greedily in group order: the least colour no group sharing a member
    with it has yet."""
    groups = len(offsets) - 1
    of_particle: dict[int, list[int]] = {}
    for g in range(groups):
        for p in members[offsets[g] : offsets[g + 1]].tolist():
            of_particle.setdefault(p, []).append(g)
    colour = np.full(groups, -1)
    for g in range(groups):
        used = {colour[h] for p in members[offsets[g] : offsets[g + 1]].tolist() for h in of_particle[p]}
        c = 0
        while c in used:
            c += 1
        colour[g] = c
    return colour


def preset_inputs(preset: str) -> dict:
    env = gym.make("SoftGraspEasy-v4", **({} if preset == "default" else {"preset": preset}))
    try:
        env.reset(seed=0)
        world = env.unwrapped.scene.world
        m, solver = world.model, world.solver
        groups = m.group_offsets.shape[0] - 1
        members = m.group_members.shape[0]
        per_colour = np.bincount(greedy_colours(m.group_offsets, m.group_members))
        solves = groups * world.sim.iterations * world.substeps * PHYSICS_STEPS_PER_ENV_STEP
        return {"particles": m.particle_count, "groups": groups, "members/group": members / groups,
                "world steps": world.substeps, "solves/env step": solves,
                "bytes/particle": sum(a.nbytes for a in solver._scratch.values()) / m.particle_count,
                "colours": len(per_colour), "per colour": (per_colour.min(), int(np.median(per_colour)),
                                                           per_colour.max())}  # fmt: skip
    finally:
        env.close()


def pybullet_step_us(steps: int) -> tuple[float, int]:
    """pybullet's stepSimulation per world step [us] in the default scene, random actions."""
    env = gym.make("SoftGraspEasy-v4")
    try:
        env.reset(seed=0)
        client = env.unwrapped.scene.world.client
        step, spent = client.stepSimulation, [0.0, 0]

        def timed():
            t = time.perf_counter()
            step()
            spent[0] += time.perf_counter() - t
            spent[1] += 1

        client.stepSimulation = timed
        rng = np.random.default_rng(0)
        for _ in range(steps):
            _, _, terminated, truncated, _ = env.step(rng.uniform(-1.0, 1.0, 4).astype(np.float32))
            if terminated or truncated:
                env.reset()
        return 1e6 * spent[0] / spent[1], spent[1]
    finally:
        env.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--presets", default="default,fine,converged")
    parser.add_argument("--steps", type=int, default=100, help="env steps over which pybullet is timed")
    args = parser.parse_args()
    print(f"{'preset':>10} {'particles':>9} {'members/group':>13} {'world steps':>11} {'solves/env step':>15} "
          f"{'bytes/particle':>14} {'colours':>7} {'groups per colour (min/median/max)':>35}")  # fmt: skip
    for preset in args.presets.split(","):
        r = preset_inputs(preset)
        print(f"{preset:>10} {r['particles']:9d} {r['members/group']:13.1f} {r['world steps']:11d} "
              f"{r['solves/env step']:15,d} {r['bytes/particle']:14.0f} {r['colours']:7d} "
              f"{'/'.join(str(v) for v in r['per colour']):>35}")  # fmt: skip
    us, n = pybullet_step_us(args.steps)
    print(f"pybullet: {us:.1f} us per world step (default scene, {n} world steps)")


if __name__ == "__main__":
    main()
