"""The object-set ids' scripted baselines, per object: each id made with one object of its set
(``gym.make(id, object=name)``: that object at the id's drawn size, mass and friction), seeds
0..N-1, the id's own start and carry. The carry ids run the scripted grasp
(``ScriptedGraspPolicy.for_env``), the grip-force ids the tactile grip (``TactileGripPolicy``).
Printed per object: success, held at the end (through the carry), the median lift at the end and
the peak tilt; for the grip ids the median of the carry's squeeze over the least that holds.

    PYTHONPATH=. python benchmarks/object_set.py                                   # every id, 10 seeds
    PYTHONPATH=. python benchmarks/object_set.py --ids SoftGraspObjects-v1 --seeds 3 --objects sphere,cone
"""

from __future__ import annotations

import argparse
import math
import time

import gymnasium as gym
import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.policies.grip import TactileGripPolicy
from softgrasp_env.registration import ENV_IDS, OBJECT_SET

IDS = tuple(i for i in ENV_IDS if i.startswith("SoftGraspObjects"))


def episode(env_id: str, obj: str, seed: int) -> dict:
    env = gym.make(env_id, object=obj)
    grip = env.unwrapped.args.control.finger_action == "force"
    policy = TactileGripPolicy(env) if grip else ScriptedGraspPolicy.for_env(env)
    obs, info = env.reset(seed=seed)
    tilt, done = 0.0, False
    while not done:
        obs, _, term, trunc, info = env.step(policy(obs))
        done = term or trunc
        tilt = max(tilt, math.degrees(env.unwrapped.scene.cylinder_tilt()))  # the object's own
    env.close()
    ratio = info["carry_squeeze"] / info["least_squeeze"] if grip and info.get("least_squeeze") else math.nan
    return {"ok": bool(info["is_success"]), "held": bool(info["held"]), "lift": float(info["lift_height"]),
            "tilt": tilt, "ratio": ratio}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--objects", default=",".join(OBJECT_SET))
    ap.add_argument("--ids", default=",".join(IDS))
    a = ap.parse_args()
    print(f"the object-set ids' scripted baselines, {a.seeds} seeds per object")
    print("| id | object | success | held at the end | lift at the end [mm] | peak tilt [deg] | squeeze / least | wall s |")
    print("|---|---|---|---|---|---|---|---|")
    for env_id in a.ids.split(","):
        total = held = 0
        for obj in a.objects.split(","):
            t0 = time.perf_counter()
            rows = [episode(env_id, obj, s) for s in range(a.seeds)]
            wall = time.perf_counter() - t0
            ok, kept = sum(r["ok"] for r in rows), sum(r["held"] for r in rows)
            total, held = total + ok, held + kept
            lifts = [r["lift"] * 1000 for r in rows]
            ratio = np.nanmedian([r["ratio"] for r in rows]) if any(r["ratio"] == r["ratio"] for r in rows) else None
            print(f"| {env_id} | {obj} | {ok}/{a.seeds} | {kept}/{a.seeds} | {np.median(lifts):.1f} | "
                  f"{max(r['tilt'] for r in rows):.1f} | {'-' if ratio is None else f'{ratio:.2f}'} | {wall:.0f} |",
                  flush=True)  # fmt: skip
        n = a.seeds * len(a.objects.split(","))
        print(f"| {env_id} | all | {total}/{n} | {held}/{n} | | | | |", flush=True)


if __name__ == "__main__":
    main()
