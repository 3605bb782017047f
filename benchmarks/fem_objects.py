"""The scripted grasp with pybullet's FEM pads (``fingers="fem"``, the coarse mesh) on named objects:
per object and seed, whether it lifts the object to the success height and holds it to the
episode's end, the lift at the end, the peak tilt of the object (its own: a standing object's up
axis from the vertical, a lying capsule's axis from the horizontal), the fingers' mean squeeze
once gripped, the deepest pad node inside the object or the ground, and the wall time. The gentle
start (SoftGraspEasy-v3: yaw U(+-5 deg), the object at U(+-1 cm)).

    PYTHONPATH=. python benchmarks/fem_objects.py                               # 2 seeds, five objects
    PYTHONPATH=. python benchmarks/fem_objects.py --seeds 1 --objects sphere,cube
    PYTHONPATH=. python benchmarks/fem_objects.py --objects cube --grip-force 0.3

A row is a minute or two (100 env steps of the coarse pads). The squeeze reads low: pybullet
reports no node contacts of a soft body (softgrasp_env/fingers/fem.py). The scripted policy lifts
only while both fingers read at least its ``grip_force`` (0.5 N), and on a flat face (the cube) one
finger read about 0.4 N while the pads held it: the policy set it down and went back for it. A
lower ``--grip-force`` separates that reading from the grasp.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.observation import OBS_NAMES
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.registration import make_as as make

ENV_ID = "SoftGraspEasy-v3"
OBJECTS = ("sphere", "cube", "cone", "capsule", "pebble-1")
INDEX = {n: k for k, n in enumerate(OBS_NAMES)}


def episode(obj: str, seed: int, resolution: str = "coarse", grip_force: float | None = None) -> dict:
    """One scripted episode of the FEM fingers on ``obj`` from ``seed`` (the policy's ``grip_force``
    [N], None: its default): held (the env's success), lift at the end [m], peak tilt [deg], mean
    squeeze once both fingers read the policy's grip_force [N], deepest penetration [m], steps, wall time [s]."""
    t0 = time.perf_counter()
    env = make(ENV_ID, fingers="fem", fem_resolution=resolution, object=obj)
    policy = ScriptedGraspPolicy.for_env(env, **({} if grip_force is None else {"grip_force": grip_force}))
    obs, _ = env.reset(seed=seed)
    scene = env.unwrapped.scene
    tilt, pen, squeeze, steps = 0.0, 0.0, [], 0
    done = False
    while not done:
        obs, _, term, trunc, info = env.step(policy(obs))
        done = term or trunc
        steps += 1
        tilt = max(tilt, math.degrees(scene.cylinder_tilt()))
        pen = max(pen, scene.penetration()[0])
        f = obs[[INDEX["force_left"], INDEX["force_right"]]]
        if (f >= policy.grip_force).all():
            squeeze.append(float(f.mean()))
    env.close()
    return {"ok": bool(info["is_success"]), "lift": float(obs[INDEX["lift"]]), "tilt": tilt, "pen": pen,
            "squeeze": float(np.mean(squeeze)) if squeeze else math.nan, "steps": steps,
            "wall": time.perf_counter() - t0}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--objects", default=",".join(OBJECTS))
    ap.add_argument("--resolution", choices=("coarse", "fine"), default="coarse")
    ap.add_argument("--grip-force", type=float, default=None,
                    help="the force both fingers must read for the policy to lift [N] (default: its 0.5)")  # fmt: skip
    a = ap.parse_args()
    print(f"scripted grasp, fingers='fem' ({a.resolution}), {ENV_ID} (the gentle start), seeds 0..{a.seeds - 1}"
          + ("" if a.grip_force is None else f", the policy's grip_force {a.grip_force:g} N"))  # fmt: skip
    print("| object | seed | held | lift at the end [mm] | peak tilt [deg] | mean squeeze [N] | max penetration [mm] "
          "| steps | wall s |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|")
    for obj in a.objects.split(","):
        for seed in range(a.seeds):
            r = episode(obj, seed, a.resolution, a.grip_force)
            print(f"| {obj} | {seed} | {'yes' if r['ok'] else 'no'} | {r['lift'] * 1000:.1f} | {r['tilt']:.1f} | "
                  f"{r['squeeze']:.2f} | {r['pen'] * 1000:.2f} | {r['steps']} | {r['wall']:.0f} |", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
