"""Convergence in the time step and the iteration count: every metric of
softgrasp_env/accuracy.py, and the pad's compression in the env's own grasp, at dt 1/1000 ...
1/120 s (3 iterations) and at 2 ... 20 iterations (1/240 s), in one run.

    PYTHONPATH=. python benchmarks/convergence.py [--quick] [--out benchmarks/out]

"Results converge" means halving dt (or adding iterations) moves each figure toward a limit:
this prints each figure's error against its analytic value (Coulomb, conservation) or, where
there is none, the figure itself, marks a series monotone when every step toward the finer
setting moves the error toward zero (or the figure in one direction), and draws one panel per
metric (docs/results/convergence.png). Metrics:

- ``ramp``: the pad on a slowly tilted ramp breaks loose at tan theta; Coulomb mu_s (0.9).
- ``slide``: its acceleration down a ramp 0.15 steeper; Coulomb g (sin theta - mu_k cos theta).
- ``stop``: slide-to-stop distance from 0.5 m/s on level ground; Coulomb v^2 / (2 mu_k g).
- ``bound``: the heaviest cylinder the scripted grasp (accuracy.run_grasp, 4 s lift) holds
  without slipping, bisection to 0.5 %; Coulomb 2 mu_s F / g (soft, both couplings, and rigid).
- ``in_hand``, ``penetration``: that grasp's in-hand motion and deepest penetration (0.1 kg).
- ``compression``: the pad's compression under the squeeze in the env's scripted grasp
  (SoftGraspEasy-v3, benchmarks/grasp_checks.py); a material property would not change.

One process, one thread; about 10 minutes (``--quick``: no bisection, 3 dt's, 3 iteration counts).
"""

from __future__ import annotations

import argparse
import csv
import math
from dataclasses import replace
from itertools import pairwise
from pathlib import Path

from softgrasp_env import accuracy, presets
from softgrasp_env.accuracy import GraspPlan, coulomb_hold_bound, find_hold_bound, run_grasp
from softgrasp_env.config import SimConfig, TissueConfig, kinetic_friction
from softgrasp_env.scene import GraspScene, SceneConfig

OUT = Path(__file__).resolve().parent / "out"
DTS = (1 / 1000, 1 / 480, 1 / 240, 1 / 120)
ITERATIONS = (2, 3, 5, 10, 20)
KINDS = {"soft, thesis": {}, "soft, consistent": {"coupling": "consistent"}, "rigid": {"fingers": "rigid"}}


def _scene(kind: dict, sim: SimConfig, **kw) -> SceneConfig:
    base = presets.scene_config("default")
    sim = replace(sim, coupling=kind.get("coupling", sim.coupling))
    return replace(base, sim=sim, fingers=kind.get("fingers", base.fingers), **kw)


def tissue_rows(sim: SimConfig) -> dict[str, tuple[float, float]]:
    """(figure, analytic) of the pad on the ramp and on the ground, at ``sim``."""
    tissue = TissueConfig()
    mu_s, mu_k, g = tissue.friction_static, kinetic_friction(tissue), sim.gravity
    theta = math.atan(mu_s + 0.15)
    v0 = 0.5
    return {
        "ramp": (accuracy.ramp_breakaway(tissue, sim), mu_s),
        "slide": (accuracy.slide_acceleration(theta, tissue, sim), g * (math.sin(theta) - mu_k * math.cos(theta))),
        "stop": (accuracy.stop_distance(v0, tissue, sim), v0 * v0 / (2.0 * mu_k * g)),
    }


def _grasp(cfg: SceneConfig, plan: GraspPlan):
    scene = GraspScene(cfg)
    try:
        return run_grasp(scene, plan)
    finally:
        scene.close()


def grasp_rows(kind: dict, sim: SimConfig, *, bound: bool) -> dict[str, tuple[float, float]]:
    """The scripted grasp's in-hand motion and penetration (0.1 kg), and its hold bound."""
    plan = GraspPlan()
    cfg = _scene(kind, sim)
    rec = _grasp(cfg, plan)
    out = {"in_hand": (rec.in_hand_motion, 0.0), "penetration": (rec.max_penetration, 0.0)}
    if bound:
        ref = coulomb_hold_bound(cfg.tissue.friction_static, cfg.finger_force, sim.gravity)

        # the static bound (tests/sim/test_world.py): a 1 s lift loses ~24 % to its transient
        slow = GraspPlan(lift=4.0, hold=3.0)

        def held(mass: float) -> bool:
            return _grasp(_scene(kind, sim, cylinder_mass=mass), slow).holds_without_slip(slow)

        try:
            m, _ = find_hold_bound(held, lo=0.8 * ref, hi=1.1 * ref, rel_tol=0.005)
        except ValueError:  # not bracketed: held at 1.1x Coulomb or dropped at 0.8x
            m = math.nan
        out["bound"] = (m, ref)
    return out


def compression(sim: SimConfig) -> float:
    """The pad's compression at the end of the env's scripted grasp [m]."""
    from benchmarks.grasp_checks import scripted_episode

    return scripted_episode({"fingers": "tissue", "iterations": sim.iterations}, "v3", dt=sim.dt)["compression"]


def monotone(errors: list[float]) -> bool:
    """Every step toward the finer setting (the list runs coarse to fine) moves |error| down."""
    e = [abs(x) for x in errors]
    return all(b <= a * (1 + 1e-9) + 1e-12 for a, b in pairwise(e))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="no bisection; 3 dt's and 3 iteration counts")
    parser.add_argument("--from-csv", type=Path, default=None, help="report and plot a CSV this script wrote, no runs")
    parser.add_argument("--out", type=Path, default=OUT)
    ns = parser.parse_args(argv)
    ns.out.mkdir(parents=True, exist_ok=True)
    if ns.from_csv is not None:
        rows = [(r["axis"], float(r["value"]), r["method"], r["metric"], float(r["figure"]), float(r["analytic"]))
                for r in csv.DictReader(open(ns.from_csv))]  # fmt: skip
    else:
        rows = measure(quick=ns.quick)
        with open(ns.out / "convergence.csv", "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["axis", "value", "method", "metric", "figure", "analytic"])
            w.writerows([(a, f"{v:.6g}", m, k, f"{x:.6g}", f"{r:.6g}") for a, v, m, k, x, r in rows])
    report(rows, ns.out)
    return 0


def measure(*, quick: bool) -> list[tuple]:
    """Every metric at every setting: (axis, value, method, metric, figure, analytic)."""
    dts = DTS[1:] if quick else DTS
    iters = (2, 3, 10) if quick else ITERATIONS
    settings = [("dt", dt, SimConfig(dt=dt)) for dt in dts] + [("iterations", n, SimConfig(iterations=n)) for n in iters]
    rows = []
    for axis, value, sim in settings:
        label = f"1/{round(1 / value)}" if axis == "dt" else str(value)
        for metric, (fig, ref) in tissue_rows(sim).items():
            rows.append((axis, value, "tissue pad", metric, fig, ref))
        for name, kind in KINDS.items():
            for metric, (fig, ref) in grasp_rows(kind, sim, bound=not quick).items():
                rows.append((axis, value, name, metric, fig, ref))
        rows.append((axis, value, "soft, thesis", "compression", compression(sim), math.nan))
        print(f"{axis} {label}: " + ", ".join(f"{r[2]} {r[3]} {r[4]:.5g}" for r in rows if r[0] == axis and r[1] == value),
              flush=True)  # fmt: skip
    return rows


def report(rows: list[tuple], out: Path) -> None:
    """Print each series coarse to fine with its verdict, and draw convergence.png."""
    print("\nerror against the analytic value (figure itself where there is none), coarse -> fine:")
    series: dict[tuple[str, str, str], list[tuple[float, float]]] = {}
    for axis, value, method, metric, fig, ref in rows:
        err = fig - ref if math.isfinite(ref) and ref != 0.0 else fig
        rel = err / ref if math.isfinite(ref) and ref != 0.0 else err
        series.setdefault((axis, method, metric), []).append((value, rel))
    for (axis, method, metric), pts in series.items():
        pts.sort(key=lambda p: -p[0] if axis == "dt" else p[0])  # coarse first
        vals = [p[1] for p in pts]
        mono = monotone(vals) if metric != "compression" else all(b <= a for a, b in pairwise(vals)) or all(
            b >= a for a, b in pairwise(vals))  # fmt: skip
        unit = "rel" if metric in ("ramp", "slide", "stop", "bound") else "m"
        print(f"  {axis:<10} {method:<17} {metric:<12} [{unit}] " + "  ".join(f"{v:+.4g}" for v in vals)
              + ("   monotone" if mono else "   NOT monotone"))  # fmt: skip
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    metrics = sorted({k[2] for k in series})
    fig, axes = plt.subplots(2, len(metrics), figsize=(2.6 * len(metrics), 5.2), squeeze=False)
    for j, metric in enumerate(metrics):
        for i, axis in enumerate(("dt", "iterations")):
            ax = axes[i, j]
            xs: list[float] = []
            for (a, method, m), pts in series.items():
                if a == axis and m == metric:
                    xs = [p[0] for p in pts]
                    ax.plot(xs, [abs(p[1]) for p in pts], "o-", label=method, ms=3)
            ax.set_xscale("log")
            ax.minorticks_off()
            ax.set_xticks(xs, [f"1/{round(1 / x)}" if axis == "dt" else f"{x:g}" for x in xs])
            unit = "|relative error|" if metric in ("ramp", "slide", "stop", "bound") else "[m]"
            ax.set_title(f"{metric} {unit}", fontsize=8)
            ax.tick_params(labelsize=6)
            ax.set_xlabel("dt [s]" if axis == "dt" else "iterations (dt 1/240)", fontsize=7)
    axes[0, 0].legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(out / "convergence.png", dpi=90)
    print(f"\nwrote {out / 'convergence.png'}")


if __name__ == "__main__":
    raise SystemExit(main())
