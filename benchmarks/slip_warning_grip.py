"""The slip warning in the grip-force task: lift, hold and carry at a constant squeeze near the least.

    PYTHONPATH=. python benchmarks/slip_warning_grip.py [--seeds 12] [--factors 1.0,1.2,1.5,2.0]
        [--ids SoftGraspGrip-v6,SoftGraspGripRigidTorsion-v5,SoftGraspGripRigid-v5]

Each episode squeezes with a constant force (policies/grip.py ``ConstantGripPolicy``) of ``factor``
times the static least, m g / (2 mu) with the episode's drawn mass and friction (read from the
env's privileged state, which the detector is told too: it knows mu). The grip lifts, holds and
then carries (the sway of the carry test). Gross slip: the cylinder 1 mm lower in the grip than
when the lift ended. Every env step the detector (fingers/tactile.py ``slip_warning`` on the
episode's 4 x 4 taxels) says whether part of the grip slides; its warning is its last uninterrupted
run of "on" up to gross slip, and the lead is the time from its start to gross slip. An episode that
never slips but had the detector on for three steps or more after the lift is counted: under a
steady load below mu P the edges of the contact sit at their cone (Cattaneo and Mindlin's stick
zone does not grow back), so the detector reads how close to the least force a grip holds, not
only a slip on its way.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

import softgrasp_env  # noqa: F401
from softgrasp_env.fingers.tactile import slip_warning
from softgrasp_env.observation import PRIVILEGED_NAMES, tactile_view
from softgrasp_env.policies.grip import ConstantGripPolicy

P = {n: k for k, n in enumerate(PRIVILEGED_NAMES)}
SLIP = 1e-3
"""Gross slip: the cylinder this far lower in the grip than when the lift ended [m]."""
ALARM = 3
"""Env steps of warning without a slip that count as a false alarm."""


def constant_grip(env: gym.Env, factor: float, seed: int) -> tuple[ConstantGripPolicy, float, float, float, float]:
    """The constant grip of ``factor`` times the seeded episode's static least force m g / (2 mu),
    its mass and friction read from the env's privileged state, capped at the finger's full force:
    (policy, mu, mass, static least [N], force [N]). The env is left reset to the episode's start."""
    base = env.unwrapped
    env.reset(seed=seed)
    state = base.privileged_state()
    mu, mass = float(state[P["friction_static"]]), float(state[P["object_mass"]])
    least = mass * 9.81 / (2.0 * mu)
    force = min(factor * least, float(base.plan.args.control.finger_force))
    return ConstantGripPolicy(env, force), mu, mass, least, force


def episode(env: gym.Env, factor: float, seed: int) -> dict[str, float | bool]:
    base = env.unwrapped
    policy, mu, mass, _, force = constant_grip(env, factor, seed)
    obs, _ = env.reset(seed=seed)
    rel0, warn, steps, slip_step = None, [], 0, None
    dt = 1.0 / base.control_frequency
    done = False
    while not done:
        obs, _, term, trunc, info = env.step(policy(obs))
        done = term or trunc
        steps += 1
        if rel0 is None:
            if policy.lifted(obs):
                rel0 = float(base.privileged_state()[P["cyl_rel_z"]])
            continue
        warn.append(bool(slip_warning(tactile_view(obs, base.obs_names), mu)))
        drop = rel0 - float(base.privileged_state()[P["cyl_rel_z"]])
        if drop > SLIP or not info["held"]:
            slip_step = len(warn) - 1
            break
    out = {"seed": seed, "factor": factor, "mu": mu, "mass": mass, "force": force, "lifted": rel0 is not None,
           "slipped": slip_step is not None, "lead_s": 0.0, "false_alarm": False}  # fmt: skip
    w = np.array(warn, dtype=bool)
    if slip_step is not None and w.size and w[-1]:
        start = len(w) - 1
        while start > 0 and w[start - 1]:
            start -= 1
        out["lead_s"] = (len(w) - 1 - start) * dt
    elif slip_step is None and w.size:
        runs = np.diff(np.flatnonzero(np.diff(np.r_[0, w.astype(int), 0])))[::2]  # lengths of the on-runs
        out["false_alarm"] = bool(runs.size and runs.max() >= ALARM)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ids", default="SoftGraspGrip-v6,SoftGraspGripRigidTorsion-v5,SoftGraspGripRigid-v5")
    parser.add_argument("--seeds", type=int, default=12)
    parser.add_argument("--first-seed", type=int, default=1000)
    parser.add_argument("--factors", default="1.0,1.2,1.5,2.0", help="squeeze over the static least m g / (2 mu)")
    ns = parser.parse_args(argv)
    if ns.seeds < 1:
        parser.error(f"--seeds must be >= 1, got {ns.seeds}")
    factors = [float(v) for v in ns.factors.split(",") if v]
    if not factors or min(factors) <= 0:
        parser.error("--factors must be > 0")
    print("| id | squeeze / static least | lifted | slipped after the lift | warned ahead (lead > 0) | lead [ms]: "
          "median (min - max) | held | held with the detector on for 3+ steps |")
    print("|---|---|---|---|---|---|---|---|")
    for env_id in ns.ids.split(","):
        env = gym.make(env_id)
        try:
            for f in factors:
                rows = [episode(env, f, ns.first_seed + s) for s in range(ns.seeds)]
                lifted = [r for r in rows if r["lifted"]]
                slipped = [r for r in lifted if r["slipped"]]
                warned = [r for r in slipped if r["lead_s"] > 0]
                held = [r for r in lifted if not r["slipped"]]
                leads = np.array([r["lead_s"] for r in warned]) * 1e3
                lead = f"{np.median(leads):.0f} ({leads.min():.0f} - {leads.max():.0f})" if leads.size else "-"
                print(f"| {env_id} | {f:g} | {len(lifted)} of {len(rows)} | {len(slipped)} | {len(warned)} | {lead} | "
                      f"{len(held)} | {sum(r['false_alarm'] for r in held)} |", flush=True)  # fmt: skip
        finally:
            env.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
