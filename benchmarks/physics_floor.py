"""The physics floor and how near each env gets to it, in one run.

    PYTHONPATH=. python benchmarks/physics_floor.py [--seconds 3] [--repeats 3] [--ids SoftGrasp-v5,...]
        [--min-rows 2]      # the soft ids' pads with two particle rows across every face (tissue_min_rows)
        [--material-solve groups]   # the soft ids' material swept group by group (gym.make's material_solve)

- **Floor**: pybullet alone stepping the scene's rigid bodies - the ground, the free cylinder, the
  palm on its arm constraint and the two prismatic finger cores squeezing the cylinder - nothing
  of ours around it: the env's own scene after the scripted grasp has closed, then only
  ``stepSimulation`` in a loop. Measured at 1/240 s (the rigid kinds' world step) and at the soft
  env's world step (1/240 s over the tissue's world steps per physics step: 2 for SoftGrasp-v5's
  pads, 6 for SoftGrasp-v4's sweep; the tissue is not stepped).
- **Envs**: env steps/s of each id, random actions, resets inside the loop.
- **Ratios**: the overall one, env steps/s x physics steps per env step (12) / the 1/240 s floor; and
  per world step, env steps/s x pybullet steps per env step / the floor at that world step (what
  is left for everything of ours when pybullet's share is fixed).
- **Breakdown** per env step, measured with timers around the stages in the same episodes:
  pybullet (``stepSimulation``), the tissue kernel (``solver._step``), the solver's Python around
  it (``TissueSolver.step`` less the kernel: the call's fixed cost), the hand-over (impulses to
  pybullet, pose reads, attached particles synced), and the env (everything else: the arm's
  path, finger forces, the task, the observation, gymnasium's wrappers).

- **Targets**: each id's ratio to the floor against the speed work's aims (soft >= 0.25, rigid >=
  0.8), the hand-over and the env's own Python as a share of an env step (soft <= 25 %, rigid <=
  40 %), and SoftGrasp-v5 at ``preset="converged"`` on one thread (>= 100 env steps/s;
  ``--no-converged`` leaves it out): met or missed, in this run.

Interleaved: every configuration runs once per repeat, in turn, and the best of the repeats is
kept (the machine is shared).
"""

from __future__ import annotations

import argparse
import math
import time
from collections import defaultdict

import gymnasium as gym

import softgrasp_env
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.tissue import solver as solver_module

IDS = ("SoftGrasp-v5", "SoftGraspRigid-v3", "SoftGraspRigidTorsion-v3")
CONVERGED_ID = "SoftGrasp-v5"
TARGETS = {"soft floor": 0.25, "rigid floor": 0.8, "soft ours": 0.25, "rigid ours": 0.40, "converged env steps/s": 100.0}
"""What the speed work aims at: env steps/s x 12 over the 1/240 s floor (soft ids, rigid ids); the
hand-over and the env's own Python as a share of an env step (soft, rigid); the converged preset's
env steps/s on one thread."""


def _grasped(env_id: str, **kwargs):
    """The env after the scripted grasp has closed on the cylinder (40 env steps from the gentle
    start): the bodies and contacts the floor steps; ``kwargs`` go to gym.make."""
    easy = env_id.replace("SoftGrasp", "SoftGraspEasy", 1) if "Easy" not in env_id else env_id
    env = gym.make(easy, **kwargs)
    policy = ScriptedGraspPolicy.for_env(env)
    obs, _ = env.reset(seed=0)
    for _ in range(40):
        obs, *_ = env.step(policy(obs))
    return env


def floor(env_id: str, seconds: float, **kwargs) -> tuple[float, float]:
    """(pybullet steps/s, its world step [s]) of ``env_id``'s scene (``kwargs`` to gym.make), nothing
    of ours around it."""
    env = _grasped(env_id, **kwargs)
    scene = env.unwrapped.scene
    client = scene.client
    h = env.unwrapped.plan.scene.sim.dt / (scene.bullet_steps * scene.world_steps)
    n, tic = 0, time.perf_counter()
    while time.perf_counter() - tic < seconds:
        for _ in range(100):
            client.stepSimulation()
        n += 100
    rate = n / (time.perf_counter() - tic)
    env.close()
    return rate, h


class _Timer:
    """Wraps a callable and adds its wall time to ``totals[name]``."""

    def __init__(self, fn, name: str, totals: dict[str, float]) -> None:
        self.fn, self.name, self.totals = fn, name, totals

    def __call__(self, *args, **kwargs):
        tic = time.perf_counter()
        try:
            return self.fn(*args, **kwargs)
        finally:
            self.totals[self.name] += time.perf_counter() - tic


def env_rate(env_id: str, seconds: float, *, breakdown: bool, **kwargs) -> tuple[float, dict[str, float], int]:
    """(env steps/s, seconds per env step by stage, pybullet steps per env step); ``kwargs`` go to
    gym.make."""
    totals: dict[str, float] = defaultdict(float)
    env = gym.make(env_id, **kwargs)
    env.action_space.seed(0)
    env.reset(seed=0)
    kernel = solver_module._step
    timed: set[int] = set()

    def instrument() -> None:
        """Timers on this episode's objects (a reset may build them anew)."""
        scene = env.unwrapped.scene
        world = scene.world
        for obj in (scene.client, world):
            if id(obj) in timed:
                continue
            timed.add(id(obj))
            if obj is scene.client:
                obj.stepSimulation = _Timer(obj.stepSimulation, "pybullet", totals)
            else:
                world.refresh = _Timer(world.refresh, "hand-over", totals)
                world._sync = _Timer(world._sync, "hand-over", totals)
                world._impulses.apply = _Timer(world._impulses.apply, "hand-over", totals)
                if world.solver is not None:
                    world.solver.step = _Timer(world.solver.step, "tissue call", totals)

    if breakdown:
        solver_module._step = _Timer(kernel, "kernel", totals)
        instrument()
    try:
        env.step(env.action_space.sample())
        totals.clear()
        n, tic = 0, time.perf_counter()
        while time.perf_counter() - tic < seconds:
            _, _, term, trunc, _ = env.step(env.action_space.sample())
            n += 1
            if term or trunc:
                env.reset()
                if breakdown:
                    instrument()
        wall = time.perf_counter() - tic
    finally:
        solver_module._step = kernel
    per_step = {k: v / n for k, v in totals.items()}
    if breakdown:
        if "tissue call" in per_step:  # the solver's Python around the kernel
            per_step["solver call"] = per_step.pop("tissue call") - per_step.get("kernel", 0.0)
        per_step["env"] = wall / n - sum(per_step.values())
    scene = env.unwrapped.scene
    pybullet_per_env_step = env.unwrapped.plan.substeps * scene.bullet_steps * scene.world_steps
    env.close()
    return n / wall, per_step, pybullet_per_env_step


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=3.0, help="timed wall time per configuration and repeat")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--ids", default=",".join(IDS))
    parser.add_argument("--no-converged", action="store_true",
                        help="leave out SoftGrasp-v5 at preset='converged' (its target: env steps/s on one thread)")
    parser.add_argument("--min-rows", type=int, default=None,
                        help="the soft ids' fewest particle rows across a finger face (gym.make's tissue_min_rows)")
    parser.add_argument("--material-solve", choices=("groups", "global"), default=None,
                        help="how the soft ids' material is solved (gym.make's material_solve; default: the id's)")
    ns = parser.parse_args(argv)
    soft = {} if ns.min_rows is None else {"tissue_min_rows": ns.min_rows}
    if ns.material_solve is not None:
        soft["material_solve"] = ns.material_solve

    def kw(env_id: str) -> dict:
        return {} if "Rigid" in env_id else soft

    ids = ns.ids.split(",")
    unknown = sorted(set(ids) - set(softgrasp_env.ENV_IDS))
    if unknown:
        parser.error(f"unknown ids {unknown}; choose from {', '.join(softgrasp_env.ENV_IDS)}")
    if ns.seconds <= 0 or ns.repeats < 1:
        parser.error("--seconds must be > 0 and --repeats >= 1")

    floors: dict[float, float] = {}
    rates: dict[str, float] = defaultdict(float)
    stages: dict[str, dict[str, float]] = {}
    pb_steps: dict[str, int] = {}
    # the floor at 1/240 s and at each soft id's world step (the tissue's world steps per physics step)
    floor_ids = dict.fromkeys(["SoftGraspRigid-v3"] + [i for i in ids if "Rigid" not in i])
    for r in range(ns.repeats):
        for fid in floor_ids:
            rate, h = floor(fid, ns.seconds, **kw(fid))
            floors[h] = max(floors.get(h, 0.0), rate)
        for env_id in ids:
            rate, _, steps = env_rate(env_id, ns.seconds, breakdown=False, **kw(env_id))
            rates[env_id] = max(rates[env_id], rate)
            pb_steps[env_id] = steps
        if r == ns.repeats - 1:
            for env_id in ids:
                stages[env_id] = env_rate(env_id, ns.seconds, breakdown=True, **kw(env_id))[1]

    converged = math.nan
    if not ns.no_converged:  # one thread, the env's default
        converged = max(env_rate(CONVERGED_ID, ns.seconds, breakdown=False, preset="converged", **soft)[0] for _ in range(ns.repeats))

    sim_dt = 1.0 / 240.0
    base = floors[min(floors, key=lambda h: abs(h - sim_dt))]
    print(f"floor: pybullet alone, the grasped scene's bodies (best of {ns.repeats}, {ns.seconds:g} s each)")
    for h, rate in sorted(floors.items(), reverse=True):
        print(f"  world step 1/{round(1 / h)} s: {rate:,.0f} pybullet steps/s ({1e6 / rate:.1f} us)")
    print()
    print(f"{'env id':<28}{'env steps/s':>12}{'x12 / floor':>13}{'pybullet/env step':>19}{'per world step':>16}")
    for env_id in ids:
        rate, steps = rates[env_id], pb_steps[env_id]
        h = sim_dt * 12 / steps
        world_floor = floors.get(min(floors, key=lambda f: abs(f - h)), base)
        print(f"{env_id:<28}{rate:>12.0f}{rate * 12 / base:>13.2f}{steps:>19d}{rate * steps / world_floor:>16.2f}")
    print()
    print("where an env step goes (the last repeat, timers around each stage) [us per env step]")
    names = ("pybullet", "kernel", "solver call", "hand-over", "env")
    print(f"{'env id':<28}" + "".join(f"{n:>12}" for n in names) + f"{'total':>12}")
    for env_id in ids:
        st = stages[env_id]
        total = sum(st.values())
        print(f"{env_id:<28}" + "".join(f"{st.get(n, 0.0) * 1e6:>12.0f}" for n in names) + f"{total * 1e6:>12.0f}")
    print()
    print("targets (this run)")
    for env_id in ids:
        soft = "Rigid" not in env_id
        ratio, aim = rates[env_id] * 12 / base, TARGETS["soft floor" if soft else "rigid floor"]
        st = stages[env_id]
        ours = (st.get("hand-over", 0.0) + st.get("env", 0.0)) / sum(st.values())
        share = TARGETS["soft ours" if soft else "rigid ours"]
        print(f"  {env_id:<28} {ratio:.2f} of the floor (target >= {aim:g}): {'met' if ratio >= aim else 'missed'}; "
              f"hand-over + env {ours:.0%} of an env step (target <= {share:.0%}): {'met' if ours <= share else 'missed'}")  # fmt: skip
    if not ns.no_converged:
        aim = TARGETS["converged env steps/s"]
        print(f"  {CONVERGED_ID}, preset='converged': {converged:.1f} env steps/s on one thread (target >= {aim:g}): "
              f"{'met' if converged >= aim else 'missed'}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
