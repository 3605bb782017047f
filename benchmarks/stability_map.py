"""Where each method fails: the scripted grasp over grids of settings, every finger kind, same
scene, same policy, same seed (issue 9).

    PYTHONPATH=. python benchmarks/stability_map.py [--quick | --tiny] [--methods rigid,tissue,...]

Maps (rows x columns):
1. jaw wedge (angle between the finger faces) x gripper yaw, lateral offset 5 mm;
2. lateral offset along the finger face, up to past its end (the face is 4 cm long) x friction
   scale (tissue, rigid finger and ground coefficients together), no wedge;
3. physics time step (1/1000 to 1/60 s) x finger force;
4. cylinder mass x cylinder radius.
A cell is one 5 s episode of SoftGraspEnv with agents.scripted.ScriptedGraspPolicy:
2 = held (lifted and held at the end), 1 = slipped (lifted, then lost), 0 = dropped (never lifted),
-1 = diverged, -2 = refused (gym.make raises a ValueError: the setting is outside what the
method accepts, e.g. the consistent coupling's squeeze impulse limit, config.py). Methods: the finger kinds of softgrasp_env.fingers.FINGERS, ours with both couplings. Writes
benchmarks/out/stability_map.csv and .png (one heatmap per method and map) and prints the grids.
"""

from __future__ import annotations

import argparse
import csv
from dataclasses import replace
from pathlib import Path

import gymnasium as gym
import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from agents.scripted import ScriptedGraspPolicy
from softgrasp_env.config import SimConfig
from softgrasp_env.fingers import FINGERS

OUT = Path(__file__).resolve().parent / "out"
LABELS = {2: "held", 1: "slipped", 0: "dropped", -1: "diverged", -2: "refused"}


TINY_SKIP = ("fem",)
"""Finger kinds the --tiny map leaves out: pybullet's FEM pads run at ~10 world steps/s (8
substeps of explicit elasticity, FemConfig.substeps), and the tiny map's two 5 s episodes
would add about 5 minutes to CI; tests/fingers/test_fem.py runs the fem grasp (marked slow)."""


def methods(*, tiny: bool = False) -> dict[str, dict]:
    """Every method: env arguments (without TINY_SKIP's kinds if ``tiny``)."""
    out = {}
    for kind in FINGERS:
        if tiny and kind in TINY_SKIP:
            continue
        if kind == "tissue":
            out["tissue, thesis"] = dict(fingers="tissue")
            out["tissue, consistent"] = dict(fingers="tissue", sim=SimConfig(coupling="consistent"))
        else:
            out[kind] = dict(fingers=kind)
    return out


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


MAKE_ARGS = ("finger_force", "dt")
"""Grid parameters that are env arguments (a new env per cell), not reset options."""


def grid(make: dict, rows: tuple[str, list[float]], cols: tuple[str, list[float]], fixed: dict) -> np.ndarray:
    out = np.zeros((len(rows[1]), len(cols[1])), dtype=int)
    env, key = None, None
    for i, rv in enumerate(rows[1]):
        for j, cv in enumerate(cols[1]):
            cell = {**fixed, rows[0]: rv, cols[0]: cv}
            kwargs = dict(make)
            for name in MAKE_ARGS:
                if name in cell:
                    value = cell.pop(name)
                    if name == "dt":
                        kwargs["sim"] = replace(kwargs.get("sim", SimConfig()), dt=value)
                    else:
                        kwargs[name] = value
            if env is None or repr(kwargs) != key:
                if env is not None:
                    env.close()
                key = repr(kwargs)
                try:  # the physics map: fingers start around the cylinder
                    env = gym.make("SoftGraspEasy-v3", **kwargs)
                except ValueError:  # outside what this method accepts
                    env = None
            out[i, j] = -2 if env is None else episode(env, cell, ScriptedGraspPolicy.for_env(env))
    if env is not None:
        env.close()
    return out


def maps(quick: bool, tiny: bool) -> list[tuple[str, list, str, list, dict]]:
    if tiny:  # CI: the wedge where rigid blocks fail and tissue holds
        return [("jaw_wedge", [0.0, 0.1], "yaw", [0.1], {"lateral_offset": 0.005, "cylinder_xy": (0.0, 0.0)})]
    q = quick
    return [
        ("jaw_wedge", [0.0, 0.05, 0.2, 0.45] if q else [0.0, 0.025, 0.05, 0.1, 0.2, 0.3, 0.45],
         "yaw", [0.0, 0.2] if q else [0.0, 0.1, 0.2, 0.3], {"lateral_offset": 0.005, "cylinder_xy": (0.0, 0.0)}),
        ("lateral_offset", [0.0, 0.02, 0.03] if q else [0.0, 0.01, 0.02, 0.025, 0.03],
         "friction_scale", [0.3, 1.0] if q else [0.2, 0.3, 0.5, 0.75, 1.0], {"yaw": 0.0, "jaw_wedge": 0.0, "cylinder_xy": (0.0, 0.0)}),
        ("dt", [1 / 1000, 1 / 240, 1 / 60] if q else [1 / 1000, 1 / 480, 1 / 240, 1 / 120, 1 / 60],
         "finger_force", [1.0, 10.0] if q else [1.0, 3.0, 6.0, 10.0, 20.0], {"yaw": 0.05, "lateral_offset": 0.005, "jaw_wedge": 0.0, "cylinder_xy": (0.0, 0.0)}),
        ("cylinder_mass", [0.05, 0.4] if q else [0.05, 0.1, 0.2, 0.4, 0.6],
         "cylinder_radius", [0.02, 0.04] if q else [0.015, 0.02, 0.03, 0.04], {"yaw": 0.05, "lateral_offset": 0.005, "jaw_wedge": 0.0, "cylinder_xy": (0.0, 0.0)}),
    ]  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="coarser grids")
    parser.add_argument("--tiny", action="store_true", help="the CI smoke run: one wedge row")
    parser.add_argument("--methods", default="", help="comma-separated subset of the methods")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    chosen = methods(tiny=args.tiny and not args.methods)  # named explicitly, fem runs even in --tiny
    if args.methods:
        names = args.methods.split(",")
        unknown = set(names) - set(chosen)
        if unknown:
            parser.error(f"unknown methods {sorted(unknown)}; choose from {sorted(chosen)}")
        chosen = {k: chosen[k] for k in names}
    args.out.mkdir(parents=True, exist_ok=True)
    rows_csv, results = [], []
    for rname, rvals, cname, cvals, fixed in maps(args.quick, args.tiny):
        for name, make in chosen.items():
            g = grid(make, (rname, rvals), (cname, cvals), fixed)
            results.append((name, rname, rvals, cname, cvals, g))
            print(f"\n{name}: rows {rname}, columns {cname} (2 held, 1 slipped, 0 dropped, -1 diverged, -2 refused)")
            print(" " * 10 + "".join(f"{c:>8g}" for c in cvals))
            for rv, line in zip(rvals, g):
                print(f"{rv:>10.4g}" + "".join(f"{v:>8d}" for v in line), flush=True)
                rows_csv += [(name, rname, rv, cname, cv, int(v), LABELS[int(v)]) for cv, v in zip(cvals, line)]
    with open(args.out / "stability_map.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["method", "row_param", "row_value", "col_param", "col_value", "outcome", "label"])
        w.writerows(rows_csv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n_maps = len(results) // len(chosen)
    fig, axes = plt.subplots(n_maps, len(chosen), figsize=(3.6 * len(chosen), 3.0 * n_maps), squeeze=False)
    for k, (name, rname, rvals, cname, cvals, g) in enumerate(results):
        ax = axes[k // len(chosen), k % len(chosen)]
        cmap = plt.get_cmap("RdYlGn").copy()
        cmap.set_bad("lightgray")  # refused
        ax.imshow(np.ma.masked_less(g, -1), cmap=cmap, vmin=-1, vmax=2, origin="lower", aspect="auto")
        ax.set_xticks(range(len(cvals)), [f"{c:g}" for c in cvals], fontsize=7)
        ax.set_yticks(range(len(rvals)), [f"{r:.3g}" for r in rvals], fontsize=7)
        ax.set_xlabel(cname, fontsize=8)
        ax.set_ylabel(rname, fontsize=8)
        ax.set_title(name, fontsize=9)
    fig.suptitle("Scripted grasp: green held, yellow slipped, orange dropped, red diverged, grey refused")
    fig.tight_layout()
    fig.savefig(args.out / "stability_map.png", dpi=90)
    print(f"\nwrote {args.out / 'stability_map.csv'} and {args.out / 'stability_map.png'}")


if __name__ == "__main__":
    main()
