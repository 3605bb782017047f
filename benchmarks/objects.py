"""The scripted grasp on every named object, per finger kind: how often it lifts the object to the
success height and holds it to the episode's end, the lift at the end, the peak tilt of the object
(its own: a standing object's up axis from the vertical, a lying capsule's axis from the horizontal)
and the fingers' mean squeeze once gripped. The gentle start (the Easy ids, yaw U(+-5 deg), the
object at U(+-1 cm)), seeds 0..N-1.

    PYTHONPATH=. python benchmarks/objects.py                       # 10 seeds, soft and rigid
    PYTHONPATH=. python benchmarks/objects.py --seeds 3 --objects sphere,cone --kinds soft
    PYTHONPATH=. python benchmarks/objects.py --task carry --kinds soft,rigid,rigid_torsion
    PYTHONPATH=. python benchmarks/objects.py --kinds rigid_torsion_patch,segmented --seeds 5
    PYTHONPATH=. python benchmarks/objects.py --task carry --finger-force 1 --mass 0.05   # a light squeeze

rigid_torsion_patch: the torsional peer with the tissue's lever of each object following the load
(``TorsionalRigidConfig(spinning_friction="patch")``); segmented: the sprung segments on the v3
ids (``fingers="segmented"``).
"""

from __future__ import annotations

import argparse
import math
import time

import gymnasium as gym
import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.fingers import TorsionalRigidConfig
from softgrasp_env.observation import OBS_NAMES
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.scene.objects import PRESETS

KINDS = {"soft": "SoftGraspEasy-v4", "rigid": "SoftGraspEasyRigid-v3", "rigid_torsion": "SoftGraspEasyRigidTorsion-v3",
         "rigid_torsion_patch": "SoftGraspEasyRigidTorsion-v3", "segmented": "SoftGraspEasy-v4"}  # fmt: skip
CARRY = {"soft": "SoftGrasp-v4", "rigid": "SoftGraspRigid-v3", "rigid_torsion": "SoftGraspRigidTorsion-v3",
         "rigid_torsion_patch": "SoftGraspRigidTorsion-v3", "segmented": "SoftGrasp-v4"}  # fmt: skip
"""--task carry: the ids' own task - the reach from a misaligned start (yaw, jaw wedge, offset), the
lift and the carry's sway."""
FINGERS = {"rigid_torsion_patch": TorsionalRigidConfig(spinning_friction="patch"), "segmented": "segmented"}
"""The kinds that are an id with other fingers (gym.make's ``fingers=``)."""
INDEX = {n: k for k, n in enumerate(OBS_NAMES)}


def episode(env_id: str, obj: str, seed: int, **kwargs) -> dict:
    env = gym.make(env_id, object=obj, **kwargs)
    policy = ScriptedGraspPolicy.for_env(env)
    obs, _ = env.reset(seed=seed)
    tilt, squeeze = 0.0, []
    done = False
    while not done:
        obs, _, term, trunc, info = env.step(policy(obs))
        done = term or trunc
        tilt = max(tilt, math.degrees(env.unwrapped.scene.cylinder_tilt()))  # the object's own (no roll)
        f = obs[[INDEX["force_left"], INDEX["force_right"]]]
        if (f > 0.5).all():
            squeeze.append(float(f.mean()))
    env.close()
    return {"ok": bool(info["is_success"]), "lift": float(obs[INDEX["lift"]]), "tilt": tilt,
            "squeeze": float(np.mean(squeeze)) if squeeze else math.nan}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--objects", default=",".join(PRESETS))
    ap.add_argument("--kinds", default="soft,rigid")
    ap.add_argument("--task", choices=("easy", "carry"), default="easy",
                    help="easy: the gentle start, no carry (the Easy ids); carry: the ids' reach and carry")  # fmt: skip
    ap.add_argument("--finger-force", type=float, default=None, help="each finger's squeeze [N] (default: the ids' 3)")
    ap.add_argument("--mass", type=float, default=None, help="the object's mass [kg] (default: the ids' 0.1)")
    a = ap.parse_args()
    extra = {k: v for k, v in (("finger_force", a.finger_force), ("cylinder_mass", a.mass)) if v is not None}
    ids = KINDS if a.task == "easy" else CARRY
    print(f"scripted grasp per object, {a.seeds} seeds, " + ("the gentle start" if a.task == "easy" else
                                                            "the reach from a misaligned start and the carry")
          + (f", {extra}" if extra else ""))  # fmt: skip
    print("| object | kind | held | lift at the end [mm] | peak tilt [deg] | mean squeeze [N] | wall s |")
    print("|---|---|---|---|---|---|---|")
    for obj in a.objects.split(","):
        for kind in a.kinds.split(","):
            t0 = time.perf_counter()
            kw = ({"fingers": FINGERS[kind]} if kind in FINGERS else {}) | extra
            rows = [episode(ids[kind], obj, s, **kw) for s in range(a.seeds)]
            wall = time.perf_counter() - t0
            held = sum(r["ok"] for r in rows)
            lifts = [r["lift"] * 1000 for r in rows]
            print(f"| {obj} | {kind} | {held}/{a.seeds} | {np.median(lifts):.1f} (min {min(lifts):.1f}) | "
                  f"{max(r['tilt'] for r in rows):.1f} | {np.nanmedian([r['squeeze'] for r in rows]):.2f} | "
                  f"{wall:.0f} |", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
