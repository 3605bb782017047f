"""Speed against accuracy of the soft grasp, one run, one chart.

Each solver setting runs the scripted grasp (approach, squeeze, lift 5 cm, hold 2 s). Accuracy is
measured against the same solver at a much finer setting (4x the particle density, 16 iterations,
dt / 4): the RMS difference of the cylinder's height over the run, and the deepest tissue
penetration. Speed is whole-world physics steps per second (tissue + pybullet).

    python benchmarks/speed_accuracy.py [--quick]

Writes benchmarks/out/speed_accuracy.csv and .png and prints the table.
"""

from __future__ import annotations

import argparse
import csv
import itertools
from dataclasses import replace
from pathlib import Path

import numpy as np

from softgrasp_env.accuracy import GraspPlan, run_grasp
from softgrasp_env.config import SceneConfig
from softgrasp_env.scene import GraspScene

OUT = Path(__file__).resolve().parent / "out"


def run(cfg: SceneConfig) -> tuple[dict, np.ndarray, np.ndarray]:
    """Scripted grasp; returns metrics and the cylinder height trace (time, z)."""
    scene = GraspScene(cfg)
    times, heights = [], []
    world = scene.world
    original_step = world.step

    def step() -> None:
        original_step()
        times.append(world.step_count * cfg.sim.dt)
        heights.append(scene.lift_height())

    world.step = step  # record the trace without touching the script
    try:
        res = run_grasp(scene, GraspPlan())
    finally:
        scene.close()
    n = 0 if world.model is None else world.model.particle_count
    metrics = dict(
        particles=n,
        steps_per_s=res.steps_per_second,
        held=res.held(GraspPlan()),
        lift_cm=100 * res.lift_height,
        penetration_mm=1000 * res.max_penetration,
    )
    return metrics, np.asarray(times), np.asarray(heights)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer settings (for a smoke run)")
    args = parser.parse_args()
    base = SceneConfig()
    ref_cfg = replace(
        base,
        tissue=replace(base.tissue, density=4 * base.tissue.density),
        sim=replace(base.sim, iterations=16, rotation_iterations=4, dt=base.sim.dt / 4),
    )
    ref, ref_t, ref_z = run(ref_cfg)
    print(f"reference: {ref['particles']} particles, 16 iterations, dt/4: lift {ref['lift_cm']:.2f} cm, "
          f"penetration {ref['penetration_mm']:.3f} mm, {ref['steps_per_s']:.0f} steps/s")  # fmt: skip

    iterations = (1, 2, 4) if args.quick else (1, 2, 3, 4, 6, 8)
    rotation = (1, 4) if args.quick else (1, 2, 4)
    groups = (8,) if args.quick else (6, 8)
    rows = []
    rigid, _, rigid_z = run(replace(base, fingers="rigid"))
    rows.append(dict(setting="rigid-only", iterations=0, rotation_iterations=0, group_size=0, **rigid,
                     height_rms_mm=np.nan))  # fmt: skip
    for it, rot, gs in itertools.product(iterations, rotation, groups):
        cfg = replace(base, tissue=replace(base.tissue, group_size=gs),
                      sim=replace(base.sim, iterations=it, rotation_iterations=rot))  # fmt: skip
        m, t, z = run(cfg)
        err = np.sqrt(np.mean((z - np.interp(t, ref_t, ref_z)) ** 2))
        rows.append(dict(setting=f"it{it} rot{rot} g{gs}", iterations=it, rotation_iterations=rot, group_size=gs,
                         **m, height_rms_mm=1000 * err))  # fmt: skip

    OUT.mkdir(exist_ok=True)
    with open(OUT / "speed_accuracy.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"{'setting':<16}{'particles':>10}{'steps/s':>10}{'held':>6}{'lift cm':>9}{'pen mm':>8}{'z rms mm':>10}")
    for r in rows:
        print(f"{r['setting']:<16}{r['particles']:>10}{r['steps_per_s']:>10.0f}{str(r['held']):>6}"
              f"{r['lift_cm']:>9.2f}{r['penetration_mm']:>8.3f}{r['height_rms_mm']:>10.3f}")  # fmt: skip

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    soft = [r for r in rows if r["iterations"] > 0]
    for r in soft:
        color = "tab:blue" if r["held"] else "tab:red"
        ax[0].scatter(r["steps_per_s"], r["height_rms_mm"], c=color, s=12 + 6 * r["iterations"])
        ax[0].annotate(r["setting"], (r["steps_per_s"], r["height_rms_mm"]), fontsize=6)
        ax[1].scatter(r["steps_per_s"], r["penetration_mm"], c=color, s=12 + 6 * r["iterations"])
    ax[0].set_xlabel("physics steps/s (whole world)")
    ax[0].set_ylabel("cylinder height RMS vs reference [mm]")
    ax[0].set_yscale("log")
    ax[1].set_xlabel("physics steps/s (whole world)")
    ax[1].set_ylabel("max tissue penetration [mm]")
    ax[1].axhline(2.0, color="grey", lw=0.8, ls="--")
    ax[1].axvline(rigid["steps_per_s"] * 0.25, color="grey", lw=0.8, ls=":")
    fig.suptitle(f"soft grasp, {soft[0]['particles']} particles (blue held, red dropped); "
                 f"rigid-only: {rigid['steps_per_s']:.0f} steps/s, dotted = 0.25x rigid")  # fmt: skip
    fig.tight_layout()
    fig.savefig(OUT / "speed_accuracy.png", dpi=130)
    print(f"wrote {OUT / 'speed_accuracy.csv'} and {OUT / 'speed_accuracy.png'}")


if __name__ == "__main__":
    main()
