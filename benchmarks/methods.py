"""Every method side by side: speed against accuracy, one run, one chart.

    PYTHONPATH=. python benchmarks/methods.py [--quick] [--no-bound]

Methods (all in the same scene, the same scripted grasp, seed-free: the scene is deterministic):
- rigid blocks (``fingers="rigid"``), and whatever other finger kinds softgrasp_env.fingers.FINGERS offers;
- ours, oriented-particle tissue, ``coupling="thesis"`` and ``"consistent"``, swept one knob at a
  time around the default over iterations, time step (substeps: dt / k), particle density (to
  16 x the default, 64,000 per m^2 in two layers: the v4 tissue is the same material at every
  density), group size and the faces covered (``tissue_faces="all"``: every face, not only where
  contact can happen), plus the presets (softgrasp_env/presets.py). The tissue is the soft v4
  ids' (``--tissue v3``: the v3 ids'); with the v4 tissue also its material solved across the
  groups (``material_solve="global"``) over the same iterations and densities.

For each: whole-world physics steps/s (the stepping alone), and errors measured the same way for
every method (softgrasp_env/accuracy.py): deepest penetration over every step, in-hand motion of
the cylinder over lift and hold, the hold-bound error |m* / (2 mu_s F / g) - 1| (bisection, 4 s
lift; skipped with --no-bound), and for the tissue the RMS cylinder-position error against a
converged run (4x density, 16 iterations, dt / 4). Writes benchmarks/out/methods.csv and
methods.png: x = steps/s (log), y = each error (log), one marker per method, the Pareto front
(no other point both faster and more accurate) drawn per panel. Prints convergence orders: the
slope of log(pose error) against log(iterations), log(dt), log(spacing).
"""

from __future__ import annotations

import argparse
import csv
import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from softgrasp_env import presets
from softgrasp_env.accuracy import GraspPlan, coulomb_hold_bound, find_hold_bound, pose_error, run_grasp
from softgrasp_env.fingers import FINGERS, FemConfig, TissueFingerConfig
from softgrasp_env.scene import GraspScene, SceneConfig

OUT = Path(__file__).resolve().parent / "out"
TISSUES = ("v4", "v3")
PLAN = GraspPlan()
BOUND_PLAN = GraspPlan(lift=4.0, hold=3.0)
NO_BOUND = ("fem",)
"""Finger kinds whose hold bound is not bisected: a bisection trial of the FEM pads (4 s lift, 3 s
hold at ~10 world steps/s) takes about 200 s, ten of them half an hour; their bound column is NaN."""
TINY_PRESETS_SKIP = ("converged",)
"""Presets the --tiny run leaves out: ``converged`` (64,000 particles per m^2, two layers) runs
about 3 env steps/s."""
TINY_SKIP = ("fem",)
"""Finger kinds the --tiny run leaves out: pybullet's FEM pads run at ~10 world steps/s (8
substeps of explicit elasticity, FemConfig.substeps), so their one grasp alone would take
minutes; tests/fingers/test_fem.py runs it (marked slow)."""


def measure(cfg: SceneConfig, *, bound: bool, reference: np.ndarray | None) -> dict:
    scene = GraspScene(cfg)
    try:
        rec = run_grasp(scene, PLAN, trace=True)
        particles = 0 if scene.world.model is None else scene.world.model.particle_count
    finally:
        scene.close()
    row = dict(
        particles=particles,
        steps_per_s=rec.steps_per_second,
        realtime=rec.steps_per_second * cfg.sim.dt,
        held=rec.held(PLAN),
        penetration_mm=1000 * rec.max_penetration,
        in_hand_mm=1000 * rec.in_hand_motion,
        pose_rms_mm=math.nan,
        bound_err_pct=math.nan,
    )
    if reference is not None and rec.finite:
        row["pose_rms_mm"] = 1000 * pose_error(rec.trace, reference)[0]
    if bound and cfg.fingers not in NO_BOUND:
        ref = coulomb_hold_bound(cfg.tissue.friction_static, cfg.finger_force, cfg.sim.gravity)

        def held(mass: float) -> bool:
            sc = GraspScene(replace(cfg, cylinder_mass=mass))
            try:
                return run_grasp(sc, BOUND_PLAN).holds_without_slip(BOUND_PLAN)
            finally:
                sc.close()

        try:
            m, _ = find_hold_bound(held, lo=0.4 * ref, hi=1.6 * ref, rel_tol=0.02)
            row["bound_err_pct"] = 100 * (m / ref - 1.0)
        except ValueError:  # not bracketed: it holds nothing, or everything
            row["bound_err_pct"] = math.nan
    return row


def base_scene(tissue: str = "v4") -> SceneConfig:
    """The scene every point starts from: the soft ids' v4 tissue (presets.v4_tissue: the
    continuum energy, Coulomb per contact, layers as thick as the spacing) or, with ``"v3"``, the
    v3 ids' (TissueConfig's defaults: shape matching, the patch law)."""
    if tissue not in TISSUES:
        raise ValueError(f"tissue must be one of {TISSUES}, got {tissue!r}")
    return SceneConfig(tissue=presets.v4_tissue()) if tissue == "v4" else SceneConfig()


def _at_density(tissue, density: float):
    """``tissue`` at ``density`` [1/m^2], the v4 tissue's layers re-chosen for it (auto_layers)."""
    t = replace(tissue, particle_density=density)
    return replace(t, layers=t.auto_layers) if t.group_energy == "continuum" else t


MUJOCO_POINTS = (("full", "30"), ("full", "100"), ("full", "570"), ("trilinear", "30"), ("trilinear", "100"),
                 ("trilinear", "570"))  # fmt: skip
"""MuJoCo's flex pads on the chart (benchmarks/mujoco_peer.py, with the ``[peers]`` extra): (dof, nodes a
pad), the node counts of our tissue's 4,000 / 16,000 / 64,000 per m^2; the hold bound only up to 100."""
MUJOCO_BOUND_NODES = 100


def mujoco_available() -> bool:
    try:
        import mujoco  # noqa: F401
    except ImportError:
        return False
    return True


def measure_mujoco(cfg, *, bound: bool) -> dict:
    """measure()'s row for a MuJoCo peer (mujoco_peer.PeerConfig): the same figures from its own
    grasp; penetration is its contacts' deepest overlap (the flat facets' chord against the curved
    cylinder included)."""
    from benchmarks.mujoco_peer import hold_bound
    from benchmarks.mujoco_peer import run_grasp as mujoco_grasp

    g = mujoco_grasp(cfg, PLAN)
    row = dict(particles=cfg.nodes_per_pad * 2, steps_per_s=g.steps_per_second, realtime=g.realtime, held=g.held(PLAN),
               penetration_mm=1000 * g.max_penetration, in_hand_mm=1000 * g.in_hand_motion, pose_rms_mm=math.nan,
               bound_err_pct=math.nan)  # fmt: skip
    if bound and cfg.nodes_per_pad <= MUJOCO_BOUND_NODES:
        scene = SceneConfig()  # the peer's friction, squeeze and gravity are the scene's
        ref = coulomb_hold_bound(scene.tissue.friction_static, scene.finger_force, scene.sim.gravity)
        h = hold_bound(cfg, BOUND_PLAN, lo=0.4 * ref, hi=1.6 * ref)
        row["bound_err_pct"] = 100 * (h["mass"] / ref - 1.0)
    return row


def settings(quick: bool, tiny: bool = False, tissue: str = "v4", fem_fine: bool = False) -> list[tuple[str, str, SceneConfig]]:
    """(method family, setting label, scene) for every point of the chart; MuJoCo's points (with the
    ``[peers]`` extra, not in the tiny run) carry a mujoco_peer.PeerConfig instead of a scene.
    ``fem_fine``: also pybullet's fine FEM pads (about 40 minutes for their one grasp)."""
    base = base_scene(tissue)
    rows: list[tuple[str, str, SceneConfig]] = []
    if tiny:  # CI: one point per family and the resolution sweep the test checks
        rows += [(kind, kind, replace(base, fingers=kind)) for kind in FINGERS if kind not in ("tissue", *TINY_SKIP)]
        rows += [("preset", name, presets.scene_config(name, base=base)) for name in presets.PRESETS
                 if name not in TINY_PRESETS_SKIP]
        rows += [("tissue, thesis", "default", base), ("tissue, thesis", "dt/2", replace(base, sim=replace(base.sim, dt=base.sim.dt / 2)))]
        return rows
    for kind in FINGERS:
        if kind != "tissue":
            rows.append((kind, kind, replace(base, fingers=kind)))
    if fem_fine:
        rows.append(("fem", "fem fine", replace(base, fingers=FemConfig(resolution="fine"))))
    if mujoco_available():
        from benchmarks.mujoco_peer import LEVELS, PeerConfig

        rows += [("MuJoCo flex", f"{dof} {n}", PeerConfig(counts=LEVELS[n], dof=dof)) for dof, n in MUJOCO_POINTS
                 if not quick or n == "30"]  # fmt: skip
    else:
        print("MuJoCo is not installed (the [peers] extra): its flex pads are left off the chart")
    for name in presets.PRESETS:
        rows.append(("preset", name, presets.scene_config(name, base=base)))
    iters = (1, 2, 4, 8) if not quick else (2, 4)
    substeps = (2, 4) if not quick else (2,)
    # the v4 tissue means the same material at every density: its sweep runs to the converged
    # preset's 16 x (64,000 per m^2, two layers); the v3 tissue's material changes with it
    dens = ((0.625, 4.0, 16.0) if tissue == "v4" else (0.5, 2.0)) if not quick else (4.0,)
    for coupling in ("thesis", "consistent"):
        fam = f"tissue, {coupling}"
        sim0 = replace(base.sim, coupling=coupling)
        c0 = replace(base, sim=sim0)
        rows.append((fam, "default", c0))
        for n in iters:
            rows.append((fam, f"{n} iterations", replace(c0, sim=replace(sim0, iterations=n))))
        for k in substeps:
            rows.append((fam, f"dt/{k}", replace(c0, sim=replace(sim0, dt=sim0.dt / k))))
        if coupling == "thesis":
            for f in dens:
                rows.append((fam, f"density x{f:g}",
                             replace(c0, tissue=_at_density(base.tissue, f * base.tissue.particle_density))))
            rows.append((fam, "group size 6", replace(c0, tissue=replace(base.tissue, group_size=6))))
            rows.append((fam, "all faces", replace(c0, fingers=TissueFingerConfig(faces="all"))))
    if tissue == "v4":
        # the same tissue with its material solved across the groups (SimConfig.material_solve
        # "global"): the coupling rule's world steps only, over the same densities
        fam = "tissue, global solve"
        sim_g = replace(base.sim, material_solve="global")
        cg = replace(base, sim=sim_g)
        rows.append((fam, "default", cg))
        for n in (iters if not quick else ()):
            rows.append((fam, f"{n} iterations", replace(cg, sim=replace(sim_g, iterations=n))))
        for f in dens:
            rows.append((fam, f"density x{f:g}", replace(cg, tissue=_at_density(base.tissue, f * base.tissue.particle_density))))
    return rows


def pareto(speed: np.ndarray, err: np.ndarray) -> np.ndarray:
    """Indices of the points no other point beats on both (faster and smaller error), by speed."""
    ok = np.isfinite(speed) & np.isfinite(err)
    idx = [i for i in np.flatnonzero(ok) if not any(
        speed[j] >= speed[i] and err[j] <= err[i] and (speed[j] > speed[i] or err[j] < err[i]) for j in np.flatnonzero(ok)
    )]  # fmt: skip
    return np.array(sorted(idx, key=lambda i: speed[i]), dtype=int)


def order(xs, errs) -> float:
    """Slope of log(error) against log(x) by least squares (the convergence order)."""
    x, e = np.log(np.asarray(xs, float)), np.log(np.asarray(errs, float))
    ok = np.isfinite(x) & np.isfinite(e)
    return float(np.polyfit(x[ok], e[ok], 1)[0]) if ok.sum() >= 2 else math.nan


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="a few settings (smoke run)")
    parser.add_argument("--no-bound", action="store_true", help="skip the hold-bound bisections (the slow part)")
    parser.add_argument("--tiny", action="store_true", help="the CI smoke run: a point per method, a cheaper reference")
    parser.add_argument("--only", default="", help="comma-separated method families to run (e.g. fem,segmented)")
    parser.add_argument("--merge", action="store_true",
                        help="keep the other rows of an existing methods.csv in --out (replacing those re-run) and redraw")
    parser.add_argument("--fem-fine", action="store_true", help="also the fine FEM pads (their grasp: ~40 min)")
    parser.add_argument("--tissue", choices=TISSUES, default="v4",
                        help="the tissue every soft point starts from: the v4 ids' (default) or the v3 ids'")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    rows = settings(args.quick, args.tiny, args.tissue, args.fem_fine)
    if args.only:
        wanted = set(args.only.split(","))
        unknown = wanted - {fam for fam, _, _ in rows}
        if unknown:
            raise SystemExit(f"--only: unknown method families {sorted(unknown)}; known: {sorted({f for f, _, _ in rows})}")
        rows = [r for r in rows if r[0] in wanted]
    base = base_scene(args.tissue)
    k = 2 if args.tiny else 4
    ref_cfg = replace(base, tissue=_at_density(base.tissue, k * base.tissue.particle_density),
                      sim=replace(base.sim, iterations=4 * k, dt=base.sim.dt / k))  # fmt: skip
    reference = None
    if any(isinstance(cfg, SceneConfig) and cfg.fingers == "tissue" for _, _, cfg in rows):  # the converged run only the tissue is compared with
        scene = GraspScene(ref_cfg)
        try:
            reference = run_grasp(scene, PLAN, trace=True).trace
        finally:
            scene.close()
    results = []
    print(f"{'method':<22}{'setting':<16}{'particles':>9}{'steps/s':>9}{'x real':>7}{'held':>6}"
          f"{'pen mm':>8}{'hand mm':>8}{'pose mm':>8}{'bound %':>8}")  # fmt: skip
    for fam, label, cfg in rows:
        if not isinstance(cfg, SceneConfig):  # a MuJoCo peer
            row = dict(method=fam, setting=label, **measure_mujoco(cfg, bound=not args.no_bound))
        else:
            tissue_like = cfg.fingers == "tissue"
            row = dict(method=fam, setting=label, **measure(cfg, bound=not args.no_bound,
                                                              reference=reference if tissue_like else None))  # fmt: skip
        results.append(row)
        print(f"{fam:<22}{label:<16}{row['particles']:>9}{row['steps_per_s']:>9.0f}{row['realtime']:>7.1f}"
              f"{str(row['held']):>6}{row['penetration_mm']:>8.3f}{row['in_hand_mm']:>8.3f}"
              f"{row['pose_rms_mm']:>8.3f}{row['bound_err_pct']:>8.2f}", flush=True)  # fmt: skip
    args.out.mkdir(parents=True, exist_ok=True)
    if args.merge and (args.out / "methods.csv").exists():
        done = {(r["method"], r["setting"]) for r in results}
        old = [_parse(r) for r in csv.DictReader(open(args.out / "methods.csv"))]
        results = [r for r in old if (r["method"], r["setting"]) not in done] + results
    with open(args.out / "methods.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(results[0]))
        w.writeheader()
        w.writerows(results)

    def sweep(prefix: str, key):
        pts = [(key(r), r["pose_rms_mm"]) for r in results if r["method"] == "tissue, thesis"
               and (r["setting"].startswith(prefix) or r["setting"] == "default")]  # fmt: skip
        return zip(*pts, strict=True) if pts else ((), ())

    it_x, it_e = sweep("", lambda r: int(r["setting"].split()[0]) if r["setting"].endswith("iterations") else 3)
    dt_x, dt_e = sweep("dt/", lambda r: 1.0 / int(r["setting"][3:]) if r["setting"].startswith("dt/") else 1.0)
    de_x, de_e = sweep("density", lambda r: float(r["setting"][9:]) ** -0.5 if r["setting"].startswith("density") else 1.0)
    print(f"convergence order of the pose error (tissue, thesis): iterations {order(it_x, it_e):+.2f}, "
          f"dt {order(dt_x, dt_e):+.2f}, particle spacing {order(de_x, de_e):+.2f}")  # fmt: skip
    chart(results, args.out / "methods.png")
    print(f"wrote {args.out / 'methods.csv'} and {args.out / 'methods.png'}")


def _parse(row: dict) -> dict:
    """A methods.csv row with its numbers and flags back as numbers and flags."""
    out = dict(row)
    for k, v in row.items():
        if k in ("method", "setting"):
            continue
        out[k] = v == "True" if v in ("True", "False") else (int(v) if k == "particles" else float(v))
    return out


def chart(results: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    metrics = [("penetration_mm", "deepest penetration [mm]"), ("in_hand_mm", "in-hand motion, lift + hold [mm]"),
               ("pose_rms_mm", "RMS cylinder position vs converged run [mm]"),
               ("bound_err_pct", "|hold-bound error| [%]")]  # fmt: skip
    families = sorted({r["method"] for r in results})
    markers = dict(zip(families, "o^sDvP*Xh<>", strict=False))
    fig, axes = plt.subplots(2, 2, figsize=(12, 9))
    speed = np.array([r["steps_per_s"] for r in results])
    for ax, (key, title) in zip(axes.ravel(), metrics, strict=True):
        err = np.array([abs(r[key]) for r in results], dtype=float)
        # log axis: exact zeros (FEM nodes never inside the cylinder) at the floor; NaN (not
        # measured: the rigid kinds' pose error, the FEM pads' bound) stays off the panel
        err = np.where(np.isnan(err), np.nan, np.where(err > 0, err, np.nan if key == "pose_rms_mm" else 1e-3))
        ax.set_title(title)
        if not np.isfinite(err).any():  # e.g. the bound with --no-bound
            ax.text(0.5, 0.5, "not measured in this run", ha="center", va="center", transform=ax.transAxes)
            continue
        for fam in families:
            sel = np.array([r["method"] == fam for r in results])
            ax.scatter(speed[sel], err[sel], marker=markers[fam], label=fam, s=40)
        front = pareto(speed, err)
        if len(front):
            ax.plot(speed[front], err[front], "k--", lw=1, label="Pareto front")
        for i, r in enumerate(results):
            if r["method"] == "preset" and np.isfinite(err[i]):
                ax.annotate(r["setting"], (speed[i], err[i]), fontsize=7, xytext=(3, 3), textcoords="offset points")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("whole-world physics steps/s")
        ax.grid(True, which="both", alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("Speed against accuracy, every method, one run (scripted grasp, 3 N per finger)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
