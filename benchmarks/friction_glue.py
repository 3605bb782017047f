"""A defect of the tissue's default friction, reproduced, and the contact cones that fix it (issue 21's
and 22's notes; docs/RESULTS.md, "The grip-force task"): a pad that sticks to the cylinder holds it
after the squeeze is gone.

    python benchmarks/friction_glue.py                    # seed 1013, the default then the cones, ~1 min
    python benchmarks/friction_glue.py --laws cones

The grip-force scene (SoftGraspGrip-v3) with the cylinder's pose observed, so that the scripted
grasp takes the grip down onto the cylinder's centre with the fingers squeezing 4 N all the way
(they close on the way down, the pads dragged along the cylinder), lifts it, and then lowers the
squeeze as the tactile policy's search does - by 0.8 per step to W / 0.4, then by 0.9 every second
step - without ever stopping. At each printed step: the squeeze commanded, the contact normal force
each pad presses the cylinder with (the env's measured force), what the tissue pushes its cores with
along the jaw (the solver's impulses over the world steps of the env step), and the tissue's
contacts whose friction exceeds mu_s times their normal multiplier. A Coulomb contact cannot. The
default patch law (tissue/friction.py) bounds what a patch transmits, not the self-equilibrated
rest, and the pad holds the cylinder while its core pushes 0.06 N; with ``tissue_contact_cone=True``
each contact is bounded by its own cone as well, and the cylinder drops once the cores' push falls
below Coulomb's least force.
"""

from __future__ import annotations

import argparse
import math

import gymnasium as gym
import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.scene.scene import LEFT, RIGHT
from softgrasp_env.tasks.lift import MIN_GRIP_FORCE


def contact_cone(world, mu: float) -> tuple[int, int, float, float]:
    """The tissue's load-bearing contacts of the last world step: how many, how many with friction
    above mu times their normal multiplier, the median and the largest ratio of the two."""
    lc = world.solver.last_contacts()
    n = lc.count
    keep = ~lc.inner[:n] & (lc.normal_lambda[:n] > 0.0)
    lam, f, nrm = lc.normal_lambda[:n][keep], lc.friction[:n][keep], lc.normal[:n][keep]
    tangential = np.linalg.norm(f - np.sum(f * nrm, axis=1, keepdims=True) * nrm, axis=1)
    ratio = tangential / lam if len(lam) else np.zeros(1)
    return int(keep.sum()), int(np.sum(ratio > mu * (1 + 1e-3))), float(np.median(ratio)), float(ratio.max())


def glue(seed: int = 1013, report=print, cones: bool = False) -> dict:
    """The scene of the module docstring from ``seed``; ``report`` gets the table's lines. Returns
    the last step's figures: the squeeze commanded, the pads' measured normal force, the
    load-bearing contacts and how many have friction above mu_s times their normal multiplier,
    whether the cylinder is held, the largest friction / normal ratio (``top_ratio``) against mu_s
    (``mu``); and the least mean push of the two cores (the solver's impulses
    along the jaw) the cylinder was held up with after the lift (``weakest_hold``), against
    Coulomb's least force (``least``)."""
    env = gym.make("SoftGraspGrip-v3", observe_object=True, tissue_contact_cone=cones)
    obs, _ = env.reset(seed=seed)
    u = env.unwrapped
    world, cfg = u.scene.world, u.scene.config
    mu, mass = cfg.tissue.friction_static, cfg.cylinder_mass
    law = "contact cones" if cones else "the patch law (default)"
    report(f"{law}, seed {seed}: {mass:.3f} kg, mu_s {mu:.2f}, least squeeze m g / (2 mu_s) = "
           f"{mass * 9.81 / (2 * mu):.3f} N per finger")  # fmt: skip
    arm = ScriptedGraspPolicy.for_env(u, grip_force=MIN_GRIP_FORCE)
    i = {n: k for k, n in enumerate(u.obs_names)}
    axis = np.array([math.cos(cfg.yaw), math.sin(cfg.yaw), 0.0])
    force, still, floor = 4.0, 0, None
    weakest = math.inf  # the least mean push of the cores the cylinder was held up with, once lifted
    impulses = np.zeros(2)

    def watched_solve(state, colliders, original=world.solver.step):  # every world step's impulses
        out = original(state, colliders)
        impulses[:] += [out.rigid_impulse[LEFT] @ axis, out.rigid_impulse[RIGHT] @ axis]
        return out

    world.solver.step = watched_solve
    report(" step  commanded  measured (left, right)  tissue on cores  lift    contacts over mu_s (median, max ratio)")
    dt = u.plan.scene.sim.dt * u.plan.substeps
    for k in range(env.spec.max_episode_steps):
        if floor is None:
            up = obs[i["lift"]] >= arm.lift_to - 0.002 and abs(obs[i["cyl_vz"]]) < 0.005
            still = still + 1 if up else 0
            if still >= 3:
                floor = mass * 9.81 / 2 / 0.4  # each pad's share over 0.4 (the policy reads it off its taxels)
        elif force > floor:
            force = max(force * 0.8, floor)
        elif k % 2 == 0:
            force = max(force * 0.9, 0.05)
        action = arm(obs)
        action[3] = 2.0 * force / u.args.control.finger_force - 1.0
        impulses[:] = 0.0
        obs, _, terminated, _, info = env.step(action)
        n, over, med, top = contact_cone(world, mu)
        if floor is not None and info["held"]:
            weakest = min(weakest, float(np.mean(np.abs(impulses))) / dt)  # the cores' push, not the contacts' press
        if k % 6 == 0 or k >= 96:
            report(f"{k:5d}  {force:7.3f} N  {u._last.force[0]:6.3f} {u._last.force[1]:6.3f} N      "
                   f"{-impulses[0] / dt:+.3f} {impulses[1] / dt:+.3f} N  {u._last.lift:.4f}  {over:2d} of {n:2d} "
                   f"({med:.2f}, {top:.2f}; mu_s {mu:.2f})")  # fmt: skip
        if terminated:
            break
    least = mass * 9.81 / (2 * mu)
    result = {"commanded": force, "measured": u._last.force.copy(), "contacts": n, "over": over,
              "held": bool(info["held"]), "weakest_hold": weakest, "least": least, "top_ratio": top, "mu": mu}  # fmt: skip
    report(f"held at the end: {result['held']}; the least the cores pushed with while it was held: {weakest:.3f} N, "
           f"{weakest / least:.2f} x Coulomb's least m g / (2 mu_s)")  # fmt: skip
    env.close()
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=1013)
    parser.add_argument("--laws", nargs="+", default=["patch", "cones"], choices=["patch", "cones"],
                        help="the default patch law, and tissue_contact_cone=True")  # fmt: skip
    args = parser.parse_args()
    for law in args.laws:
        glue(args.seed, cones=law == "cones")
        print()


if __name__ == "__main__":
    main()
