"""A defect of the tissue's default friction, reproduced, and the contact cones that fix it
(docs/RESULTS.md, "The grip-force task"): a pad that sticks to the cylinder holds it after the squeeze is
gone.

    python benchmarks/friction_glue.py                    # seed 1013, the default then the cones, ~1 min
    python benchmarks/friction_glue.py --laws cones

The grip-force scene with the thesis tissue (the retired SoftGraspGrip-v3's: the rigid twin's grip
id with ``fingers="tissue"``, here SoftGraspGripRigid-v5, has its physics) with the cylinder's pose observed, so that the scripted
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
below Coulomb's least force; with ``friction_law="contact"`` every contact sticks or slides in its
own cone.

Once the squeeze starts to fall the arm holds still (zero arm action), so that after a slip only the
cores' squeeze and gravity act on the pads. Also printed, from the first world step the cylinder has
slid 2 mm below its highest: the largest force a pad presses it with against the largest the tissue
pushes its core with, each a mean over an env step, and the env steps where a pad presses more than
its core (``after_slack`` above it; within single world steps of a slide the two differ by up to
half a newton either way, the pad's inertia): a friction law that makes force from nowhere
shows there. (Letting the scripted arm go back down onto the fallen cylinder, as an earlier version
of this script did, lands the cores' bare ends on its top face: pybullet's core contacts then
carry 27 N, vertical, the arm's drive, which read as the pads' force flickering between 0 and
20-40 N.)
"""

from __future__ import annotations

import argparse
import math

import gymnasium as gym
import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.config import SimConfig, kinetic_friction
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.registration import TISSUE_V4
from softgrasp_env.scene.scene import LEFT, RIGHT
from softgrasp_env.tasks.lift import MIN_GRIP_FORCE


def _bearing(world, *, whole: bool = False):
    """The tissue's load-bearing contacts of the last world step: (normal multipliers, the
    tangential part of their friction, their rows of LastContacts); ``whole``: both halves of the
    friction (solver.LastContacts.friction_velocity), else the position half alone."""
    lc = world.solver.last_contacts()
    n = lc.count
    keep = ~lc.inner[:n] & (lc.normal_lambda[:n] > 0.0)
    f = lc.friction[:n][keep] + (lc.friction_velocity[:n][keep] if whole else 0.0)
    nrm = lc.normal[:n][keep]
    tangential = np.linalg.norm(f - np.sum(f * nrm, axis=1, keepdims=True) * nrm, axis=1)
    return lc.normal_lambda[:n][keep], tangential, lc, keep


def contact_cone(world, mu: float) -> tuple[int, int, float, float]:
    """The tissue's load-bearing contacts of the last world step: how many, how many with friction
    above mu times their normal multiplier, the median and the largest ratio of the two."""
    lam, tangential, _, keep = _bearing(world)
    ratio = tangential / lam if len(lam) else np.zeros(1)
    return int(keep.sum()), int(np.sum(ratio > mu * (1 + 1e-3))), float(np.median(ratio)), float(ratio.max())


def cone_excess(world, mu_s: float, mu_k: float) -> float:
    """The largest ratio, over the tissue's load-bearing contacts of the last world step, of a
    contact's whole tangential friction (both halves, solver.LastContacts.friction_velocity) to
    its cone: mu_k lambda_n where its patch slid, mu_s lambda_n where it stuck. At most 1 under a
    law that is Coulomb's at every contact."""
    lam, tangential, lc, keep = _bearing(world, whole=True)
    if not len(lam):
        return 0.0
    slid = lc.patch_slide[lc.patch[: lc.count][keep]]
    return float(np.max(tangential / (np.where(slid, mu_k, mu_s) * lam)))


OFF_GROUND = 0.01
"""[m] The cylinder counts as off the ground above this lift."""
HELD_SPEED = 0.01
"""[m/s] The cylinder counts as held up while it sinks slower than this: a cylinder sliding out of
a grip under kinetic friction is still "held" by the env's flag (it touches both pads, off the
ground) until it lands, while the creep of a grip near its limit (its contacts' edges slide first,
partial slip) is a few mm in all."""

after_slack = 0.05
"""[N] Once the squeeze is lowered, a pad may press the cylinder with at most what the tissue pushes
its core with, plus this (the pad's own weight, ~0.01 N, and its inertia): more is a force the
friction law made, not the cores."""

LAWS = {"patch": {}, "cones": {"tissue_contact_cone": True}, "contact": {"friction_law": "contact"},
        "v4": dict(TISSUE_V4)}  # fmt: skip
"""The tissue friction laws compared, as gym.make keywords: the patch law (the v3 ids'), the patch
law with contact cones, Coulomb per contact on the shape-matching material, and the v4 tissue
(Coulomb per contact on the continuum material, registration.TISSUE_V4)."""


def glue(seed: int = 1013, report=print, cones: bool = False, law: str | None = None,
         friction_kinetic: float | None = None, coupling: str | None = None,
         particle_density: float | None = None) -> dict:  # fmt: skip
    """The scene of the module docstring from ``seed``; ``report`` gets the table's lines. Returns
    the last step's figures: the squeeze commanded, the pads' measured normal force, the
    load-bearing contacts and how many have friction above mu_s times their normal multiplier,
    whether the cylinder is held, the largest friction / normal ratio (``top_ratio``) against mu_s
    (``mu``), the largest contact friction over its own cone in any world step (``cone_excess``);
    and the least mean push of the two cores (the solver's impulses
    along the jaw) the cylinder was held up with after the lift (``weakest_hold``), against
    Coulomb's least force (``least``)."""
    law = law or ("cones" if cones else "patch")
    sim = None if coupling is None else SimConfig(coupling=coupling)  # the tissue's coupling (SimConfig.coupling)
    env = gym.make("SoftGraspGripRigid-v5", fingers="tissue", observe_object=True, friction_kinetic=friction_kinetic,
                   sim=sim, particle_density=particle_density, **LAWS[law])  # fmt: skip
    obs, _ = env.reset(seed=seed)
    u = env.unwrapped
    world, cfg = u.scene.world, u.scene.config
    mu, mass = cfg.tissue.friction_static, cfg.cylinder_mass
    law = {"patch": "the patch law (the v3 ids')", "cones": "contact cones", "contact": "Coulomb per contact",
           "v4": "the v4 tissue (Coulomb per contact, continuum)"}[law]
    report(f"{law}, seed {seed}: {mass:.3f} kg, mu_s {mu:.2f}, least squeeze m g / (2 mu_s) = "
           f"{mass * 9.81 / (2 * mu):.3f} N per finger")  # fmt: skip
    arm = ScriptedGraspPolicy.for_env(u, grip_force=MIN_GRIP_FORCE)
    i = {n: k for k, n in enumerate(u.obs_names)}
    axis = np.array([math.cos(cfg.yaw), math.sin(cfg.yaw), 0.0])
    force, still, floor = 4.0, 0, None
    history: list[tuple[float, bool]] = []  # per step once the squeeze falls: (the cores' mean push, held)
    impulses = np.zeros(2)
    dt_world = world.solver.sim.dt  # one world step (the env may take several per physics step)
    cylinder_shape = u.scene.fingers.site.cylinder_shape
    after = {"tissue": 0.0, "cores": 0.0, "over": 0, "steps": 0, "excess": -math.inf}  # after a slip: see the docstring
    slipped = [False]
    pads_step, cores_step = np.zeros(2), np.zeros(2)  # summed over an env step's world steps
    calls = [0]
    peak = [0.0]
    worst = [0.0]  # the largest cone_excess of any world step
    mu_k = kinetic_friction(cfg.tissue)

    def watched_solve(state, colliders, original=world.solver.step):  # every world step's impulses
        out = original(state, colliders)
        impulses[:] += [out.rigid_impulse[LEFT] @ axis, out.rigid_impulse[RIGHT] @ axis]
        pads_step[:] += world.solver.contact_normal_force(cylinder_shape)
        cores_step[:] += np.linalg.norm(out.rigid_impulse[[LEFT, RIGHT]], axis=1) / dt_world
        calls[0] += 1
        worst[0] = max(worst[0], cone_excess(world, mu, mu_k))
        return out

    world.solver.step = watched_solve
    report(" step  commanded  measured (left, right)  tissue on cores  lift  vz[mm/s] contacts over mu_s (median, max ratio)")
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
        if floor is not None:
            action[:3] = 0.0  # the arm holds still while the squeeze is lowered (see the docstring)
        action[3] = 2.0 * force / u.args.control.finger_force - 1.0
        impulses[:] = 0.0
        pads_step[:] = 0.0
        cores_step[:] = 0.0
        calls[0] = 0
        obs, _, terminated, _, info = env.step(action)
        if slipped[0]:
            pads, cores = pads_step / calls[0], cores_step / calls[0]  # means over the env step
            after["tissue"] = max(after["tissue"], float(pads.max()))
            after["cores"] = max(after["cores"], float(cores.max()))
            after["over"] += int(np.any(pads > cores + after_slack))
            after["excess"] = max(after["excess"], float(np.max(pads - cores)))
            after["steps"] += 1
        if floor is not None:
            peak[0] = max(peak[0], u._last.lift)
            slipped[0] = slipped[0] or u._last.lift < peak[0] - 0.002
        n, over, med, top = contact_cone(world, mu)
        if floor is not None:
            # held: off the ground in both pads' grip and sinking slower than HELD_SPEED (a pad that
            # slides a little as its squeeze falls and sticks again holds). Not the env's flag: a grip
            # that sinks a few mm over its unloading slips falls below the task's success height
            # while it still holds.
            gripped = bool(u._last.force.min() >= MIN_GRIP_FORCE and u._last.lift > OFF_GROUND)
            history.append((float(np.mean(np.abs(impulses))) / dt,  # the cores' push, not the contacts' press
                            gripped and obs[i["cyl_vz"]] > -HELD_SPEED))  # fmt: skip
        if k % 6 == 0 or k >= 96:
            report(f"{k:5d}  {force:7.3f} N  {u._last.force[0]:6.3f} {u._last.force[1]:6.3f} N      "
                   f"{-impulses[0] / dt:+.3f} {impulses[1] / dt:+.3f} N  {u._last.lift:.4f} {obs[i['cyl_vz']] * 1e3:+6.1f}  {over:2d} of {n:2d} "
                   f"({med:.2f}, {top:.2f}; mu_s {mu:.2f})")  # fmt: skip
        if terminated:
            break
    least = mass * 9.81 / (2 * mu)
    weakest = min((push for push, ok in history if ok), default=math.inf)
    result = {"commanded": force, "measured": u._last.force.copy(), "contacts": n, "over": over,
              "held": bool(info["held"]), "weakest_hold": weakest, "least": least, "top_ratio": top, "mu": mu,
              "pads_after": after["tissue"], "cores_after": after["cores"], "steps_over_cores": after["over"],
              "steps_after": after["steps"], "after_excess": after["excess"], "cone_excess": worst[0]}  # fmt: skip
    if slipped[0]:
        report(f"after the slip: the pads pressed the cylinder with at most {after['tissue']:.3f} N, the tissue "
               f"pushed its cores with at most {after['cores']:.3f} N; env steps where a pad pressed more than its "
               f"core + {after_slack} N: {after['over']} of {after['steps']} (by at most {after['excess']:+.3f} N)")  # fmt: skip
    report(f"the largest contact friction over its cone (mu_k where it slid), any world step: {worst[0]:.6f}")
    report(f"held at the end: {result['held']}; the least the cores pushed with while it was held: {weakest:.3f} N, "
           f"{weakest / least:.2f} x Coulomb's least m g / (2 mu_s)")  # fmt: skip
    env.close()
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=1013)
    parser.add_argument("--laws", nargs="+", default=list(LAWS), choices=list(LAWS),
                        help="the default patch law, tissue_contact_cone=True, friction_law='contact'")  # fmt: skip
    parser.add_argument("--friction-kinetic", type=float, default=None, help="mu_k (default: the preset's, = mu_s)")
    parser.add_argument("--coupling", default=None, choices=["thesis", "consistent"],
                        help="the tissue's coupling (default: the preset's)")
    args = parser.parse_args()
    for law in args.laws:
        glue(args.seed, law=law, friction_kinetic=args.friction_kinetic, coupling=args.coupling)
        print()


if __name__ == "__main__":
    main()
