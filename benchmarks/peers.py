"""Ours beside the peers users would pick, in one run: the same pad, material and grasp in our tissue
(the soft v4 ids' material), MuJoCo's flex pads (benchmarks/mujoco_peer.py; the ``[peers]`` extra)
and pybullet's FEM pads (``fingers="fem"``), at matching node counts.

    PYTHONPATH=. python benchmarks/peers.py [--levels 30,100,570] [--methods ours,ours_global,mujoco_full,...]
        [--budget 300] [--out benchmarks/out]

Levels are nodes a pad: 30 / 100 / 570 / 3,800, our tissue at 4,000 / 16,000 / 64,000 / 256,000
particles per m^2 of face (30 / 100 / 570 / 3,800 particles a pad, layers as thick as the spacing:
1 / 1 / 2 / 4) and MuJoCo's flexcomp grids 2x3x5 / 2x5x10 / 3x10x19 / 5x20x38. pybullet's FEM pad
has its own meshes (``--fem-resolutions``: coarse, one hex cell through the 8 mm, 6 tetrahedra a
cell; fine, two), each run once, in the first level's rows.

For each method and level:

- **rig**: one pad, its core fixed, gravity off, pressed by a frictionless cylinder with 1, 3 and
  6 N; compression against the plane-strain finite-element reference at nu 0 (pad_reference.py:
  1.344 / 2.865 / 4.603 mm). Ours: spatial_convergence.measure_tissue; MuJoCo: mujoco_peer.run_rig.
  pybullet's FEM pad: benchmarks/fem_rig.py, the fem kind's mesh and material in the same rig.
- **grasp**: accuracy.GraspPlan's scripted grasp (approach, squeeze at 3 N per finger, 5 cm lift in
  1 s, 2 s hold) of the 0.1 kg cylinder: held (GraspRecord.held), in-hand motion from the lift on,
  and speed, physics steps per wall second of the stepping alone (ours: the whole world step,
  pybullet's rigid bodies included; MuJoCo: mj_step) and simulated seconds per wall second at the
  default dt 1/240 s. A MuJoCo rig or grasp projected to take more than ``--budget`` wall seconds
  is not run to the end (its speed is then the approach's); ours and the FEM pads always run whole.

Then per level the ratio of our simulated seconds per wall second to each peer's. One process, one
thread (MuJoCo steps a model on one thread; ours at its default, threads=1). A measurement: no
assertions. CSV to ``--out``/peers.csv.
"""

from __future__ import annotations

import argparse
import csv
import math
import platform
import time
from dataclasses import replace
from pathlib import Path

from benchmarks.mujoco_peer import LEVELS, REFERENCE_MM, PeerConfig, cpu_name
from benchmarks.mujoco_peer import run_grasp as mujoco_grasp
from benchmarks.mujoco_peer import run_rig as mujoco_rig
from softgrasp_env.accuracy import GraspPlan, run_grasp
from softgrasp_env.config import SimConfig
from softgrasp_env.fingers import FemConfig
from softgrasp_env.presets import v4_tissue
from softgrasp_env.scene import GraspScene, SceneConfig

OUT = Path(__file__).resolve().parent / "out"
DENSITY = {"30": 4_000.0, "100": 16_000.0, "570": 64_000.0, "3800": 256_000.0}
"""Our particle density [1/m^2] whose pads have the level's particles a pad (measured: 30 / 100 /
570 / 3,800)."""
METHODS = ("ours", "ours_global", "mujoco_full", "mujoco_trilinear", "fem")
"""``ours``: the v4 tissue as the ids run it; ``ours_global``: the same with its material solved
across the groups (SimConfig.material_solve "global")."""
LOADS = (1.0, 3.0, 6.0)


def ours_rig(level: str, sim: SimConfig | None = None) -> dict:
    from benchmarks.spatial_convergence import measure_tissue

    t = v4_tissue(particle_density=DENSITY[level])
    r = measure_tissue(DENSITY[level], LOADS, tangential=False, material=t.group_energy, layers=t.layers,
                       law=t.friction_law, hourglass=t.hourglass_stiffness, sim=sim)  # fmt: skip
    return {f"compression_{f:g}N_mm": r[f"compression_{f:g}N"] * 1e3 for f in LOADS}


def _scene_grasp(cfg: SceneConfig, plan: GraspPlan) -> dict:
    scene = GraspScene(cfg)
    try:
        rec = run_grasp(scene, plan)
        particles = 0 if scene.world.model is None else scene.world.model.particle_count
    finally:
        scene.close()
    return {"particles": particles, "held": rec.held(plan), "in_hand_mm": rec.in_hand_motion * 1e3,
            "steps_per_s": rec.steps_per_second, "sim_s_per_wall_s": rec.steps_per_second * cfg.sim.dt}  # fmt: skip


def ours_grasp(level: str, plan: GraspPlan, sim: SimConfig | None = None) -> dict:
    cfg = SceneConfig(tissue=v4_tissue(particle_density=DENSITY[level]))
    r = _scene_grasp(cfg if sim is None else replace(cfg, sim=sim), plan)
    r["nodes_per_pad"] = r.pop("particles") // 2
    return r


def mujoco_row(level: str, dof: str, plan: GraspPlan, budget: float) -> dict:
    cfg = PeerConfig(counts=LEVELS[level], dof=dof)
    rig = mujoco_rig(cfg, LOADS, budget=budget)
    out: dict = {"nodes_per_pad": cfg.nodes_per_pad}
    if rig.completed:
        out.update({f"compression_{f:g}N_mm": c * 1e3 for f, c in zip(LOADS, rig.compression, strict=True)})
    g = mujoco_grasp(cfg, plan, budget=budget)
    out.update({"held": g.held(plan) if g.completed else "not run (budget)", "steps_per_s": g.steps_per_second,
                "sim_s_per_wall_s": g.realtime})  # fmt: skip
    if g.completed:
        out["in_hand_mm"] = g.in_hand_motion * 1e3
    return out


def fem_row(plan: GraspPlan, resolution: str = "coarse") -> dict:
    from benchmarks.fem_rig import run_rig
    from softgrasp_env.fingers.fem import FEM_CELLS_THROUGH, pad_mesh

    cfg = SceneConfig(fingers=FemConfig(resolution=resolution))
    nodes = pad_mesh(cfg.finger_half_extents, cfg.tissue.extrude, FEM_CELLS_THROUGH[resolution]).node_count
    rig = run_rig(resolution, LOADS, substeps=cfg.fingers.substeps)
    r = _scene_grasp(cfg, plan)
    r.pop("particles")
    return {"nodes_per_pad": nodes, **{f"compression_{f:g}N_mm": c * 1e3 for f, c in zip(LOADS, rig.compression, strict=True)},
            **r}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--levels", default="30,100,570", help=f"comma-separated, of {', '.join(DENSITY)}")
    parser.add_argument("--methods", default=",".join(METHODS), help=f"comma-separated, of {', '.join(METHODS)}")
    parser.add_argument("--budget", type=float, default=300.0, help="wall seconds a peer's grasp may take")
    parser.add_argument("--fem-resolutions", default="coarse",
                        help="comma-separated FemConfig resolutions of the fem row (fine: about an hour)")
    parser.add_argument("--out", type=Path, default=OUT)
    ns = parser.parse_args(argv)
    levels, methods = ns.levels.split(","), ns.methods.split(",")
    bad = [lv for lv in levels if lv not in DENSITY] + [m for m in methods if m not in METHODS]
    if bad:
        parser.error(f"unknown levels or methods {bad}: levels {tuple(DENSITY)}, methods {METHODS}")
    from softgrasp_env.fingers.fem import FEM_CELLS_THROUGH

    bad_fem = [r for r in ns.fem_resolutions.split(",") if r not in FEM_CELLS_THROUGH]
    if bad_fem:
        parser.error(f"unknown --fem-resolutions {bad_fem}: of {tuple(FEM_CELLS_THROUGH)}")
    if not ns.budget > 0:
        parser.error(f"--budget must be > 0 s, got {ns.budget}")
    plan = GraspPlan()
    print(f"{cpu_name()} ({platform.machine()}), one process, one thread; dt 1/240 s; "
          f"reference compression {' / '.join(f'{REFERENCE_MM[f]:g}' for f in LOADS)} mm at 1 / 3 / 6 N", flush=True)  # fmt: skip
    rows = []
    for level in levels:
        for method in methods:
            if method == "fem" and level != levels[0]:
                continue  # its own meshes: run once
            tic = time.perf_counter()
            if method.startswith("ours"):
                sim = replace(SceneConfig().sim, material_solve="global") if method == "ours_global" else None
                row = {**ours_rig(level, sim), **ours_grasp(level, plan, sim)}
            elif method.startswith("mujoco"):
                row = mujoco_row(level, method.split("_")[1], plan, ns.budget)
            else:
                for resolution in ns.fem_resolutions.split(","):
                    tic = time.perf_counter()
                    row = {"level": level, "method": f"fem_{resolution}", **fem_row(plan, resolution)}
                    rows.append({**row, "wall_s": time.perf_counter() - tic})
                    print(_line(rows[-1]), flush=True)
                continue
            row = {"level": level, "method": method, **row, "wall_s": time.perf_counter() - tic}
            rows.append(row)
            print(_line(row), flush=True)
    print()
    print("simulated seconds per wall second, ours over each peer at the same level:")
    for level in levels:
        for ours in (r for r in rows if r["level"] == level and r["method"].startswith("ours")):
            for r in rows:
                if r["level"] == level and not r["method"].startswith("ours"):
                    print(f"  {level:>5} nodes a pad: {ours['method']} / {r['method']} = "
                          f"{ours['sim_s_per_wall_s'] / r['sim_s_per_wall_s']:.2f} (the peer held: {r.get('held')})")  # fmt: skip
    ns.out.mkdir(parents=True, exist_ok=True)
    keys: list[str] = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    path = ns.out / "peers.csv"
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()} for r in rows)
    print(f"wrote {path}")
    return 0


def _line(r: dict) -> str:
    comp = " / ".join(f"{(r[f'compression_{f:g}N_mm'] / REFERENCE_MM[f] - 1.0):+.1%}"
                      if f"compression_{f:g}N_mm" in r else "-" for f in LOADS)  # fmt: skip
    in_hand = r.get("in_hand_mm", math.nan)
    return (f"{r['level']:>5} {r['method']:<17} {r['nodes_per_pad']:>5} a pad  compression vs ref {comp:<26} "
            f"held {str(r.get('held')):<6} in hand {in_hand:6.2f} mm  {r['steps_per_s']:8.1f} steps/s  "
            f"{r['sim_s_per_wall_s']:7.3f} sim s / wall s  ({r['wall_s']:.0f} s)")  # fmt: skip


if __name__ == "__main__":
    raise SystemExit(main())
