"""Where each method fails: the scripted grasp over grids of misalignment, rigid-only vs soft
fingers, same scene, same policy, same seeds.

    PYTHONPATH=. python benchmarks/stability_map.py [--quick]

Map 1: jaw wedge (angle between the finger faces) x gripper yaw, lateral offset 5 mm.
Map 2: lateral offset x friction scale (tissue and rigid finger friction, ground), no wedge.
Map 3: finger force x solver iterations (the tissue's own limits; rigid fingers ignore iterations).
A cell is the outcome of one 5 s episode: 2 = held (is_success at the end), 1 = lifted but lost or
not held at the end, 0 = never lifted 5 cm, -1 = simulation diverged. Writes
benchmarks/out/stability_map.csv and .png and prints the grids.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import gymnasium as gym
import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from agents.scripted import ScriptedGraspPolicy
from softgrasp_env.config import SimConfig

OUT = Path(__file__).resolve().parent / "out"
IDS = ("SoftGraspRigid-v0", "SoftGrasp-v0")


def episode(env, options: dict, policy) -> int:
    obs, _ = env.reset(seed=0, options=options)
    ever = False
    for _ in range(100):
        obs, _, term, trunc, info = env.step(policy(obs))
        ever |= info["is_success"]
        if info["diverged"]:
            return -1
        if term or trunc:
            break
    if info["is_success"]:
        return 2
    return 1 if ever else 0


MAKE_ARGS = ("finger_force", "iterations")
"""Grid parameters that are env arguments (a new env per cell), not reset options."""


def grid(env_id: str, rows: tuple[str, list[float]], cols: tuple[str, list[float]], fixed: dict) -> np.ndarray:
    policy = ScriptedGraspPolicy()
    out = np.zeros((len(rows[1]), len(cols[1])), dtype=int)
    env = None
    for i, rv in enumerate(rows[1]):
        for j, cv in enumerate(cols[1]):
            cell = {**fixed, rows[0]: rv, cols[0]: cv}
            make = {k: cell.pop(k) for k in MAKE_ARGS if k in cell}
            if "iterations" in make:
                make["sim"] = SimConfig(iterations=int(make.pop("iterations")))
            if env is None or make:
                if env is not None:
                    env.close()
                env = gym.make(env_id, **make)
            out[i, j] = episode(env, cell, policy)
    env.close()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="coarser grids")
    args = parser.parse_args()
    wedges = [0.0, 0.05, 0.2, 0.45] if args.quick else [0.0, 0.025, 0.05, 0.1, 0.2, 0.3, 0.45]
    yaws = [0.0, 0.2] if args.quick else [0.0, 0.1, 0.2, 0.3]
    offsets = [0.0, 0.01, 0.02] if args.quick else [0.0, 0.005, 0.01, 0.015, 0.02]
    frictions = [0.3, 1.0] if args.quick else [0.2, 0.3, 0.5, 0.75, 1.0]
    forces = [1.0, 10.0] if args.quick else [1.0, 3.0, 6.0, 10.0, 20.0]
    iterations = [1, 3] if args.quick else [1, 2, 3, 6]
    maps = [
        ("jaw_wedge", wedges, "yaw", yaws, {"lateral_offset": 0.005, "cylinder_xy": (0.0, 0.0)}),
        ("lateral_offset", offsets, "friction_scale", frictions, {"yaw": 0.0, "jaw_wedge": 0.0, "cylinder_xy": (0.0, 0.0)}),
        ("finger_force", forces, "iterations", iterations, {"yaw": 0.05, "lateral_offset": 0.005, "jaw_wedge": 0.0,
                                                             "cylinder_xy": (0.0, 0.0)}),
    ]
    OUT.mkdir(exist_ok=True)
    rows_csv = []
    results = []
    for rname, rvals, cname, cvals, fixed in maps:
        for env_id in IDS:
            g = grid(env_id, (rname, rvals), (cname, cvals), fixed)
            results.append((env_id, rname, rvals, cname, cvals, g))
            print(f"\n{env_id}: rows {rname}, columns {cname} (2 held, 1 lost, 0 never lifted, -1 diverged)")
            print(" " * 10 + "".join(f"{c:>8g}" for c in cvals))
            for rv, line in zip(rvals, g):
                print(f"{rv:>10g}" + "".join(f"{v:>8d}" for v in line))
                rows_csv += [(env_id, rname, rv, cname, cv, int(v)) for cv, v in zip(cvals, line)]
    with open(OUT / "stability_map.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["env_id", "row_param", "row_value", "col_param", "col_value", "outcome"])
        w.writerows(rows_csv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(15, 8))
    for ax, (env_id, rname, rvals, cname, cvals, g) in zip(axes.T.ravel(), results):
        ax.imshow(g, cmap="RdYlGn", vmin=-1, vmax=2, origin="lower", aspect="auto")
        ax.set_xticks(range(len(cvals)), [f"{c:g}" for c in cvals])
        ax.set_yticks(range(len(rvals)), [f"{r:g}" for r in rvals])
        ax.set_xlabel(cname)
        ax.set_ylabel(rname)
        ax.set_title(env_id)
    fig.suptitle("Scripted grasp outcome: green held, yellow lost, orange never lifted, red diverged")
    fig.tight_layout()
    fig.savefig(OUT / "stability_map.png", dpi=100)
    print(f"\nwrote {OUT / 'stability_map.csv'} and {OUT / 'stability_map.png'}")


if __name__ == "__main__":
    main()
