"""Which finger model does a scene need? The scripted grasp and carry on every object, per finger
kind, over squeeze x misalignment and squeeze x carry band.

    PYTHONPATH=. python benchmarks/object_map.py                               # every object, the cheap methods
    PYTHONPATH=. python benchmarks/object_map.py --methods "tissue, converged" --cells reference
    PYTHONPATH=. python benchmarks/object_map.py --summary                     # the tables from the CSV

Every cell is one 5 s episode from the gentle start (``SoftGraspEasy-v4``'s physics for the tissue,
the open fingers around the object: each cell tests the grasp and the carry, not the approach),
with the carry test on (1.5 s of sway from 3.5 s; success: held at every step of it, in-hand slide
at most 5 mm) and the object of the row (``object=``, its own size). The maps, each x the squeeze
``finger_force`` (0.5, 1, 3, 6 N per finger):

- ``wedge``: the jaw wedge (-0.3 to 0.3 rad), aligned otherwise (yaw 0.05 rad, 5 mm offset);
- ``yaw``: the gripper's yaw (0 to pi/4);
- ``offset``: where along the faces the grasp lands (the policy aims 0, 1, 2 cm off the object's
  centre: stability_map.AimedPolicy);
- ``band``: the carry's sway (1.2 Hz at 0.5 m/s^2 across the jaw, 1.9 Hz at 1 m/s^2 across - the
  two-point grasp's pendulum - and 3 Hz at 1 m/s^2 along the closing axis), aligned;
- ``mass``: the object's mass, 0.1 to 0.4 kg (the reset option ``cylinder_mass``), aligned:
  Coulomb's bound for two fingers, m (g + a) / (2 mu), is 0.55-2.2 N at rest.

The misalignment and mass maps carry at 1.9 Hz, 1 m/s^2, across the jaw. Outcomes as the stability maps':
2 held (through the carry), 1 slipped (lifted, then lost or slid > 5 mm), 0 dropped (never
lifted), -1 diverged, -2 refused (the scene cannot start there: the object does not fit between the
open fingers at that wedge or yaw). Writes benchmarks/out/<name>.csv, appending: a method run
later (the converged tissue, on the cells where the cheap ones differ: ``--cells differ``) adds
its rows.

``--summary`` prints, from the CSV, the held cells per object and method, and the table "which
model does this scene need": per object, each method's cells that differ from the reference (the
converged tissue where it ran, else the default tissue), and the cheapest method within the
reference's own spread (the cells where the default tissue differs from the converged one).
"""

from __future__ import annotations

import argparse
import csv
import math
import time
from collections import defaultdict
from pathlib import Path

import gymnasium as gym
import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from benchmarks.stability_map import AimedPolicy, Cell, policy_for
from softgrasp_env.registration import OBJECT_SET, TISSUE_V4

OUT = Path(__file__).resolve().parent / "out"
SQUEEZES = (0.5, 1.0, 3.0, 6.0)
ALIGNED = {"yaw": 0.05, "lateral_offset": 0.005, "jaw_wedge": 0.0, "cylinder_xy": (0.0, 0.0)}
SWAY = {"carry_frequency": 1.9, "carry_acceleration": 1.0, "carry_direction": 0.0}
BANDS = {"1.2 Hz 0.5 across": {"carry_frequency": 1.2, "carry_acceleration": 0.5, "carry_direction": 0.0},
         "1.9 Hz 1.0 across": dict(SWAY),
         "3.0 Hz 1.0 along": {"carry_frequency": 3.0, "carry_acceleration": 1.0, "carry_direction": math.pi / 2}}
MAPS: dict[str, tuple[str, list]] = {
    "wedge": ("jaw_wedge", [-0.3, -0.15, 0.0, 0.15, 0.3]),
    "yaw": ("yaw", [0.0, 0.2, 0.4, math.pi / 4]),
    "offset": ("aim_offset", [0.0, 0.01, 0.02]),
    "band": ("band", list(BANDS)),
    "mass": ("cylinder_mass", [0.1, 0.2, 0.3, 0.4]),
}  # fmt: skip
REFERENCE: dict[str, tuple[tuple[str, ...], tuple[float, ...]]] = {
    "wedge": (("-0.3", "0", "0.3"), (1.0, 3.0)),
    "yaw": (("0.7854",), (1.0, 3.0)),
    "offset": (("0.02",), (1.0, 3.0)),
    "band": (tuple(BANDS), (1.0,)),
    "mass": (("0.2", "0.4"), (3.0,)),
}
"""``--cells reference``: the cells the converged tissue runs on (15 per object, about 30 s each on
one core): where a grasp is near a limit - 1 N (twice Coulomb's least for 0.1 kg) and 3 N, the
widest wedge both ways and none, the widest yaw, the grasp 2 cm along the faces, each band at
1 N, and the heavier objects at 3 N. 0.5 N holds nothing (below Coulomb's 0.55 N) and 6 N
everything the peers hold, so neither is run there."""
COST = ("rigid", "rigid_torsion", "rigid_torsion, patch", "segmented", "tissue", "tissue, converged")
"""The methods from the cheapest (wall time per env step) to the dearest."""


def methods() -> dict[str, dict]:
    out = {"rigid": {"fingers": "rigid"}, "rigid_torsion": {"fingers": "rigid_torsion"}}
    try:  # the torsional peer with the lever of the tissue's own patch on each object, if this build has it
        from softgrasp_env.fingers import TorsionalRigidConfig

        out["rigid_torsion, patch"] = {"fingers": TorsionalRigidConfig(spinning_friction="patch")}
    except (TypeError, ValueError):
        pass
    out["segmented"] = {"fingers": "segmented"}
    out["tissue"] = {"fingers": "tissue", **TISSUE_V4}
    out["tissue, converged"] = {"fingers": "tissue", **TISSUE_V4, "preset": "converged"}
    return out


def episode(env, options: dict, aim: float) -> Cell:
    try:
        obs, _ = env.reset(seed=0, options=options)
    except ValueError:  # the scene cannot start there
        return Cell(-2)
    policy = policy_for(env)
    if aim:
        policy = AimedPolicy(policy, yaw=env.unwrapped.scene.config.yaw, along=aim, up=0.0,
                             names=tuple(env.unwrapped.obs_names))  # fmt: skip
    ever, tilt = False, 0.0
    for _ in range(100):
        obs, _, term, trunc, info = env.step(policy(obs))
        ever |= info["held"]
        tilt = max(tilt, math.degrees(env.unwrapped.scene.cylinder_tilt()))  # the object's own
        if info["diverged"]:
            return Cell(-1)
        if term or trunc:
            break
    extra = dict(lift_mm=1000.0 * float(info["lift_height"]), tilt_deg=tilt,
                 slide_mm=1000.0 * float(env.unwrapped.task.slide))  # fmt: skip
    return Cell(2 if info["is_success"] else (1 if ever else 0), **extra)


def cells(objects: list[str], maps: tuple[str, ...] = tuple(MAPS), squeezes: tuple[float, ...] = SQUEEZES):
    """(object, map, column value label, squeeze, reset options, aim) of every cell."""
    for obj in objects:
        for name in maps:
            param, values = MAPS[name]
            for squeeze in squeezes:
                for v in values:
                    options, aim = {**ALIGNED, **SWAY}, 0.0
                    if param == "band":
                        options.update(BANDS[v])
                    elif param == "aim_offset":
                        aim = v
                    else:
                        options[param] = v
                    yield obj, name, (v if isinstance(v, str) else f"{v:.4g}"), squeeze, options, aim


FIELDS = ["object", "map", "value", "squeeze", "method", "outcome", "lift_mm", "tilt_deg", "slide_mm", "wall_s"]


def read(path: Path) -> list[dict]:
    if not path.exists():
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def key(row: dict) -> tuple:
    return row["object"], row["map"], row["value"], f"{float(row['squeeze']):g}"


def run(args) -> None:
    every = methods()
    names = [m.strip() for m in args.methods.split(";")] if args.methods else [m for m in every if
                                                                                 m != "tissue, converged"]
    unknown = set(names) - set(every)
    if unknown:
        raise SystemExit(f"unknown methods {sorted(unknown)}; choose from {list(every)}")
    path = args.out / f"{args.name}.csv"
    done = {(key(r), r["method"]) for r in read(path)}
    wanted = None
    if args.only:  # object:map:value:squeeze, ';'-separated
        wanted = {tuple(part.split(":")) for part in args.only.split(";")}
        wanted = {(o, m, v, f"{float(q):g}") for o, m, v, q in wanted}
    elif args.cells == "reference":
        wanted = {(o, m, v, f"{q:g}") for o in args.objects.split(",") for m, (vals, qs) in REFERENCE.items()
                  for v in vals for q in qs}  # fmt: skip
    if args.cells == "differ":  # the cells where the methods already run disagree, and the diagonal
        by = defaultdict(dict)
        for r in read(path):
            by[key(r)][r["method"]] = int(r["outcome"]) == 2
        wanted = {k for k, v in by.items() if len(set(v.values())) > 1}
        wanted |= {k for k in by if k[1] == "band" or (k[1] == "wedge" and k[2] in ("0", "0.15"))}
    args.out.mkdir(parents=True, exist_ok=True)
    new = not path.exists()
    with open(path, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        if new:
            w.writeheader()
        for method in names:
            t_method, n = time.perf_counter(), 0
            env, made = None, None
            squeezes = tuple(float(x) for x in args.squeezes.split(","))
            for obj, mname, value, squeeze, options, aim in cells(args.objects.split(","), tuple(args.maps.split(",")),
                                                                  squeezes):  # fmt: skip
                k = (obj, mname, value, f"{squeeze:g}")
                if (k, method) in done or (wanted is not None and k not in wanted):
                    continue
                kwargs = {**every[method], "object": obj, "finger_force": squeeze, "carry": True}
                if made != repr(kwargs):
                    if env is not None:
                        env.close()
                    try:
                        env = gym.make("SoftGraspEasy-v4", **kwargs)
                    except ValueError:
                        env = None
                    made = repr(kwargs)
                t0 = time.perf_counter()
                c = Cell(-2) if env is None else episode(env, dict(options), aim)
                w.writerow({"object": obj, "map": mname, "value": value, "squeeze": f"{squeeze:g}", "method": method,
                            "outcome": c.outcome, "lift_mm": f"{c.lift_mm:.1f}", "tilt_deg": f"{c.tilt_deg:.1f}",
                            "slide_mm": f"{c.slide_mm:.2f}", "wall_s": f"{time.perf_counter() - t0:.2f}"})  # fmt: skip
                f.flush()
                n += 1
            if env is not None:
                env.close()
            print(f"{method}: {n} cells in {time.perf_counter() - t_method:.0f} s", flush=True)


def summary(args) -> None:
    rows = read(args.out / f"{args.name}.csv")
    held = defaultdict(lambda: defaultdict(int))
    cell = defaultdict(dict)
    wall = defaultdict(list)
    for r in rows:
        held[r["object"]][r["method"]] += int(r["outcome"]) == 2
        cell[key(r)][r["method"]] = int(r["outcome"])
        wall[r["method"]].append(float(r["wall_s"]))
    present = [m for m in COST if m in wall]
    objects = [o for o in OBJECT_SET if o in held]
    n_cells = len({k for k in cell if k[0] == objects[0]}) if objects else 0
    print(f"held through the carry, of {n_cells} cells per object (median wall s per 5 s episode in the header)")
    print("| object | " + " | ".join(f"{m} ({np.median(wall[m]):.1f} s)" for m in present) + " |")
    print("|---|" + "---|" * len(present))
    for o in objects:
        counts = [str(held[o][m]) if any(k[0] == o and m in v for k, v in cell.items()) else "-" for m in present]
        print(f"| {o} | " + " | ".join(counts) + " |")
    peers = [m for m in present if not m.startswith("tissue")]
    print("\nwhich model does this scene need: per peer, the cells whose verdict (held through the carry or "
          "not) differs from the default tissue's over the whole map, then from the converged tissue's on the "
          "cells it ran; the spread is where the default tissue itself differs from the converged")
    print("| object | " + " | ".join(f"{m}: vs tissue / vs converged" for m in peers) +
          " | spread (converged cells) | only the tissue holds | only the peers hold | cheapest within the spread |")
    print("|---|" + "---|" * (len(peers) + 4))
    for o in objects:
        mine = {k: v for k, v in cell.items() if k[0] == o}
        dflt = {k: v for k, v in mine.items() if "tissue" in v}
        conv = {k: v for k, v in mine.items() if "tissue, converged" in v and "tissue" in v}
        spread = sum((v["tissue"] == 2) != (v["tissue, converged"] == 2) for v in conv.values())
        parts, cheapest = [], None
        for m in peers:
            d = sum((v[m] == 2) != (v["tissue"] == 2) for v in dflt.values() if m in v)
            dc = sum((v[m] == 2) != (v["tissue, converged"] == 2) for v in conv.values() if m in v)
            parts.append(f"{d if dflt else '-'} / {dc if conv else '-'}")
            if cheapest is None and conv and dc <= spread:
                cheapest = m
        best = "rigid_torsion, patch" if "rigid_torsion, patch" in peers else (peers[-1] if peers else None)
        # cells the tissue (either resolution) holds and no peer does, and the other way round
        only_t = sum(any(v.get(t) == 2 for t in ("tissue", "tissue, converged")) and
                     not any(v.get(m) == 2 for m in peers) for v in dflt.values())  # fmt: skip
        only_p = sum(best is not None and v.get(best) == 2 and v["tissue"] != 2 and v.get("tissue, converged", 0) != 2
                     for v in dflt.values())  # fmt: skip
        verdict = (cheapest or "tissue") if conv else "- (no converged run)"
        print(f"| {o} | " + " | ".join(parts) + f" | {spread if conv else '-'} ({len(conv)}) | {only_t} | {only_p} | "
              f"{verdict} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--objects", default=",".join(OBJECT_SET))
    ap.add_argument("--methods", default="", help="';'-separated (default: every method but the converged tissue)")
    ap.add_argument("--cells", choices=("all", "reference", "differ"), default="all")
    ap.add_argument("--only", default="", help="these cells only: object:map:value:squeeze, ';'-separated")
    ap.add_argument("--maps", default=",".join(MAPS))
    ap.add_argument("--squeezes", default=",".join(f"{f:g}" for f in SQUEEZES))
    ap.add_argument("--name", default="object_map")
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--summary", action="store_true")
    a = ap.parse_args()
    if a.summary:
        summary(a)
    else:
        run(a)


if __name__ == "__main__":
    main()
