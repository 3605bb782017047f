"""The tissue's torsional lever on every named object, against the squeeze: what the
``rigid_torsion`` peer's ``spinning_friction="patch"`` reads (softgrasp_env/fingers/rigid.py,
``PATCH_LEVERS``, is this script's default-resolution table).

    PYTHONPATH=. python benchmarks/patch_levers.py                          # default and converged tissue
    PYTHONPATH=. python benchmarks/patch_levers.py --presets default --objects sphere,cone --loads 1,3
    PYTHONPATH=. python benchmarks/patch_levers.py --speed      # the peer's env steps/s, fixed vs "patch"

Coulomb friction over a patch bounds the torsion about its normal by mu * l * N, with the lever
l = sum_i N_i |r_i - c| / sum_i N_i over the tissue's particle contacts (benchmarks/contact_patch.py
says how it is read: ``patch_figures``). On the upright cylinder the patch is the pad wrapped along
the whole face and l hardly moves with the load; on a sphere it is a disc whose radius grows with
the squeeze (the chord sqrt(2 R delta - delta^2): benchmarks/sphere_patch.py), on a box's face a
rectangle, on a cone or a pebble what the shape's curvature leaves in touch - so the lever is
measured per object and per load.

Per object (softgrasp_env.scene.objects.PRESETS) and per squeeze, SoftGraspEasy-v4 (the v4
tissue) at ``preset`` (default; converged: 64,000 particles per m^2), aligned and centred
(benchmarks/sphere_patch.py's ALIGNED), with the squeeze as the action as the grip-force task has
it (``finger_action="force"``; ``finger_force`` the squeeze wanted, commanded in full once
gripped): the scripted policy (its grip threshold at most half the squeeze) approaches, grips and
lifts, and the figures are averaged over env steps 40-69, when it has lifted and settled. Where the
grip does not hold the object aloft through those steps (a squeeze too light for the object's
weight), the grasp is run again with the policy's lift target at 0: the object is squeezed where
it stands on the ground ("ground" in the table), so the patch is the squeeze's alone.

Printed per finger: the measured normal force N [N] (the commanded squeeze, checked), the lever l
[mm] (mean over the hold, and its spread max - min), the patch's largest radius about the centre
of pressure a_max [mm] and the contacts; then the default tissue's table as ``PATCH_LEVERS``
literal (the two fingers' mean N and l per squeeze). No timing, no assertions: a measurement.

``--speed`` instead times the torsional rigid peer (SoftGraspRigidTorsion-v3, the scripted carry)
with its fixed lever and with ``spinning_friction="patch"``, interleaved episode by episode in one
process: env steps per second of ``env.step`` alone, and the ``changeDynamics`` calls "patch" makes
per physics step (counted in episodes of their own, untimed).
"""

from __future__ import annotations

import argparse
import sys
import time

import gymnasium as gym
import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from benchmarks.contact_patch import patch_figures
from benchmarks.sphere_patch import ALIGNED
from softgrasp_env.fingers import TorsionalRigidConfig
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.scene.objects import PRESETS
from softgrasp_env.scene.scene import CYLINDER_SHAPE

LOADS = (0.5, 1.0, 3.0, 6.0)
"""Each finger's squeeze [N]: the grip-force task's span (GRIP_TASK's 0-6 N) from its low end."""
HOLD = (40, 70)
"""Env steps of the hold sampled (the scripted grasp has lifted and settled by step 30)."""
KEYS = ("N", "lever", "a", "contacts")


def measure(obj: str, force: float, preset: str, *, lift: bool = True) -> dict:
    """Per finger (left, right) the mean over the hold of ``patch_figures``' N, lever, a and
    contacts (and the lever's spread), and whether the object was held aloft at every sampled step
    (``lift=False``: the policy holds it on the ground). Empty per-finger dicts: no contact."""
    env = gym.make("SoftGraspEasy-v4", object=obj, finger_action="force", finger_force=force, preset=preset)
    try:
        kw = {} if lift else {"lift_to": 0.0}
        policy = ScriptedGraspPolicy.for_env(env, grip_force=min(0.5, 0.5 * force), **kw)
        obs, _ = env.reset(seed=0, options=ALIGNED)
        solver = env.unwrapped.scene.world.solver
        dt = solver.sim.dt  # the solver's own step (its multipliers are per world step)
        rows: list[list[dict]] = [[], []]
        held = True
        for k in range(HOLD[1]):
            obs, _, term, trunc, info = env.step(policy(obs))
            if term or trunc:
                held = False
                break
            if k < HOLD[0]:
                continue
            held &= bool(info["held"])
            # the solver's scratch holds the last physics step's contacts: sampled once per env step
            figs = [patch_figures(solver, CYLINDER_SHAPE, body, dt) for body in (0, 1)]
            if all(f is not None for f in figs):
                for body, f in enumerate(figs):
                    rows[body].append(f)
        out = []
        for r in rows:
            if not r:
                out.append({})
                continue
            fig = {key: float(np.mean([f[key] for f in r])) for key in KEYS}
            levers = [f["lever"] for f in r]
            fig["spread"] = max(levers) - min(levers)
            out.append(fig)
        return {"fingers": out, "held": held}
    finally:
        env.close()


def peer_episode(obj: str, seed: int, patch: bool, *, count: bool = False) -> tuple[int, float, int, bool]:
    """One scripted carry of the torsional rigid peer: (env steps, seconds in env.step, the
    changeDynamics calls made on the gripper during the steps if ``count`` else 0, success)."""
    kw = {"fingers": TorsionalRigidConfig(spinning_friction="patch")} if patch else {}
    env = gym.make("SoftGraspRigidTorsion-v3", object=obj, **kw)
    try:
        policy = ScriptedGraspPolicy.for_env(env)
        obs, _ = env.reset(seed=seed)
        calls = [0]
        if count:
            client = env.unwrapped.scene.client
            real = client.changeDynamics

            def counted(*a, **k):
                calls[0] += 1
                return real(*a, **k)

            client.changeDynamics = counted
        steps, wall, done, info = 0, 0.0, False, {}
        while not done:
            action = policy(obs)
            t0 = time.perf_counter()
            obs, _, term, trunc, info = env.step(action)
            wall += time.perf_counter() - t0
            steps += 1
            done = term or trunc
        return steps, wall, calls[0], bool(info.get("is_success", False))
    finally:
        env.close()


def speed(objects: list[str], rounds: int) -> None:
    """The peer's env steps/s with the fixed lever and with "patch", interleaved (module docstring)."""
    print(f"torsional rigid peer, SoftGraspRigidTorsion-v3, scripted carry, {rounds} rounds interleaved (seed = round)")
    print("| object | lever | env steps/s (median of rounds) | min-max | changeDynamics per physics step | held |")
    print("|---|---|---|---|---|---|")
    for obj in objects:
        rates: dict[bool, list[float]] = {False: [], True: []}
        held = {False: 0, True: 0}
        for r in range(rounds):
            for patch in (False, True):
                steps, wall, _, ok = peer_episode(obj, r, patch)
                rates[patch].append(steps / wall)
                held[patch] += ok
        steps, _, calls, _ = peer_episode(obj, 0, True, count=True)
        per = calls / (steps * 12)  # 12 physics steps per env step at the defaults
        for patch in (False, True):
            v = rates[patch]
            print(f"| {obj} | {'patch' if patch else 'fixed 16.7 mm'} | {np.median(v):.0f} | {min(v):.0f}-{max(v):.0f} "
                  f"| {per if patch else 0.0:.3f} | {held[patch]}/{rounds} |", flush=True)  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--objects", default=",".join(PRESETS))
    parser.add_argument("--loads", default=",".join(f"{f:g}" for f in LOADS), help="each finger's squeeze [N]")
    parser.add_argument("--presets", default="default,converged")
    parser.add_argument("--speed", action="store_true", help="time the peer, fixed lever vs 'patch', instead")
    parser.add_argument("--rounds", type=int, default=5, help="--speed: episodes per lever and object")
    ns = parser.parse_args(argv)
    if ns.speed:
        speed(ns.objects.split(",") if ns.objects != ",".join(PRESETS) else ["cylinder", "sphere", "cone"], ns.rounds)
        return 0
    loads = [float(f) for f in ns.loads.split(",")]
    print("the tissue's patch per object and squeeze, SoftGraspEasy-v4, aligned, the squeeze as the action; per "
          f"finger (left / right), mean over env steps {HOLD[0]}-{HOLD[1] - 1}")  # fmt: skip
    print("| tissue | object | squeeze [N] | hold | N [N] | l [mm] | l spread [mm] | a_max [mm] | contacts | wall s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    table: dict[str, dict[str, list[tuple[float, float]]]] = {}
    for preset in ns.presets.split(","):
        table[preset] = {}
        for obj in ns.objects.split(","):
            for force in loads:
                t0 = time.perf_counter()
                res = measure(obj, force, preset)
                where = "lifted"
                if not res["held"]:
                    res = measure(obj, force, preset, lift=False)
                    where = "ground"
                wall = time.perf_counter() - t0
                left, right = res["fingers"]
                if not left or not right:
                    print(f"| {preset} | {obj} | {force:g} | {where} | no contact on both fingers in the hold "
                          f"| | | | | {wall:.0f} |", flush=True)  # fmt: skip
                    continue

                def pair(key, scale=1e3, fmt=".2f", left=left, right=right):
                    return f"{left[key] * scale:{fmt}} / {right[key] * scale:{fmt}}"

                print(f"| {preset} | {obj} | {force:g} | {where} | {pair('N', 1.0)} | {pair('lever')} | "
                      f"{pair('spread')} | {pair('a', fmt='.1f')} | {pair('contacts', 1.0, '.0f')} | {wall:.0f} |",
                      flush=True)  # fmt: skip
                n = 0.5 * (left["N"] + right["N"])
                lever = 0.5 * (left["lever"] + right["lever"])
                table[preset].setdefault(obj, []).append((n, lever))
    for preset, rows in table.items():
        print(f"\n# {preset} tissue: object -> ((N [N], l [m]), ...), the two fingers' mean")
        print("PATCH_LEVERS = {")
        for obj, pts in rows.items():
            print(f'    "{obj}": (' + ", ".join(f"({n:.2f}, {lv:.5f})" for n, lv in pts) + "),")
        print("}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
