"""One table of everything the tissue must keep as it is refined: per particle density, the pad's
compression, strip width and shear against the finite-element reference, the grasp's hold bound
and lowest friction against Coulomb, the loads at which the first contact and the whole strip
slide, the torsional lever against the squeeze, and the rim push, each with its observed order.

    PYTHONPATH=. python benchmarks/convergence_table.py [--material continuum] [--law contact]
        [--hourglass 1] [--layers 1 | auto | 1,1,2,4] [--densities 4000,16000,64000,256000]
        [--rows rig,slip,env,lever,rim] [--material-solve global]

Every row is measured at the default dt (1/240 s) and iterations (3) with one material
(``--material``: TissueConfig.group_energy; ``--law``: TissueConfig.friction_law; ``--hourglass``:
TissueConfig.hourglass_stiffness) and only the discretisation changed: the particle density and
the element layers through the pad's thickness (``--layers``: TissueConfig.layers, one count for
every density, one per density, or ``auto``: the count that keeps a layer about as thick as the
particle spacing, max(1, round(extrude / spacing)), 1 / 1 / 2 / 4 at 4,000 ... 256,000 per m^2,
so that the groups keep their shape as the tissue is refined). The rows and their references:

- ``rig`` (spatial_convergence.PadRig, one pad, its core held, gravity off): compression under
  1 / 3 / 6 N and the strip's pressure-weighted RMS half-width under 3 N against the plane-strain
  reference at nu 0 (the continuum the continuum group energy discretises; pad_reference.py), the
  tangential compliance of one pad at 3 N against the 3-D reference, frictionless for the normal
  loads and with the default friction (mu 0.9) for the tangential one. The same compliance also
  against the 3-D reference about the pad as the cylinder compressed it, pulled with Coulomb's law
  at every node (pad_reference.partial_slip_3d's ``indentation``; see coulomb_compliance): under
  3 N the layer is compressed by up to 36 %, and the continuum energy's shear modulus across a
  layer compressed to a stretch s is G 2 s / (1 + s), a property of the material at finite strain
  that linear elasticity lacks; and the strip's edges slip before the rig's second hold, which a
  stuck strip lacks.
- ``band`` (spatial_convergence.tangential_at, same rig): the tangential compliance at 2 / 2.5 / 3 /
  3.5 / 4 N against that compressed Coulomb reference at each load: the mean error and its spread.
  At one load the error depends on where the reference's strip edge falls between two particle
  columns (it jumps as the next column starts to touch); over the band that quantisation averages
  out.
- ``slip`` (partial_slip.ramp, same rig, pressed to 3 N and driven along the cylinder's axis): the
  Q / mu P at which the first contact slides (Cattaneo-Mindlin: at once, 0) and at which the whole
  strip does (Coulomb: 1).
- ``env`` (grasp_checks, SoftGraspEasy-v3's scripted grasp, 3 N per finger, aligned): the heaviest
  cylinder held over 2 mu F / (g + a), a the palm's peak acceleration at that mass, and the lowest
  friction scale that lifts 0.1 kg over m (g + a) / (2 mu F) (both 1 for Coulomb on a flat pad;
  the contacts' summed normal force on the wrapped pad is also printed, mu sum N / (g + a)); each
  also with a the cylinder's own peak acceleration, which is what the friction must carry (the
  palm's peak can be a transient the cylinder never feels: 2.55 against 1.39 m/s^2 with two
  layers at 64,000 per m^2).
- ``lever`` (contact_patch.measure, the same grasp at 1 and at 6 N per finger): the torsional lever
  of the tissue's patch, sum N_i |r_i - c| / N, mean over the hold and both fingers; no external
  reference (its self-convergence is what the rigid peer's coefficient relies on).
- ``rim`` (rim_creep.episode, SoftGrasp-v3 aimed 4 cm above the centre, the pads' upper 2 cm above
  the rim, 0.2 kg at half friction, no noise, ``--seeds`` episodes): the median over episodes of
  the largest downward push of the tissue's contacts on the cylinder's top and rim [N]; 0 is the
  continuum's (a smooth pad on a sharp edge carries no point load), so it should fall with the
  spacing.

Printed: each row per density, its relative error against its reference and the observed order
between successive densities (each refines the spacing by 2: log2 of the ratio of successive
errors); CSV to ``--out``/convergence_table{suffix}.csv. One process, one thread. A measurement: no
timing, no assertions.
"""

from __future__ import annotations

import argparse
import csv
import math
import time
from pathlib import Path

import numpy as np

from softgrasp_env.config import FRICTION_LAWS, GROUP_ENERGIES, MATERIAL_SOLVES, SimConfig, TissueConfig

OUT = Path(__file__).resolve().parent / "out"
DENSITIES = (4_000.0, 16_000.0, 64_000.0, 256_000.0)
ROWS = ("rig", "band", "slip", "env", "lever", "rim")
SPLIT_ROWS = {"hold": "env", "friction": "env"}
"""Rows that run one half of another: ``hold`` the env row's hold bound, ``friction`` its lowest
friction (two processes can then take the two bisections side by side)."""
BAND_LOADS = (2.0, 2.5, 3.0, 3.5, 4.0)
"""The normal loads of the tangential band [N]."""
LEVER_FORCES = (1.0, 6.0)
"""The squeezes per finger at which the torsional lever is read [N]."""


def measure(density: float, rows, *, material: str, law: str, layers: int, seeds: int, hourglass: float = 0.0,
            hold_bracket: tuple[float, float] = (0.05, 1.5), friction_bracket: tuple[float, float] = (0.05, 1.0),
            solve: str = "groups", report=print) -> dict:  # fmt: skip
    """Every row in ``rows`` at one density; keys as in the CSV. The brackets are where the env
    row's bisections start (kg; friction scale), widened inside 0.05-1.5 kg / 0.05-1 if they do not
    straddle. ``solve``: SimConfig.material_solve, in every row (the world steps its rule asks)."""
    tissue = TissueConfig(group_energy=material, friction_law=law, layers=layers, particle_density=density,
                          hourglass_stiffness=hourglass)  # fmt: skip
    sim = SimConfig(material_solve=solve)
    kind = {"fingers": "tissue", "material_solve": solve}
    out: dict[str, float] = {"density": density, "layers": layers}
    tic = time.perf_counter()
    if "rig" in rows:
        from benchmarks.spatial_convergence import measure_tissue

        r = measure_tissue(density, material=material, layers=layers, law=law, hourglass=hourglass, sim=sim)
        out.update({key: r[key] for key in ("compression_1N", "compression_3N", "compression_6N", "width_3N",
                                            "compliance", "particles", "substeps")})  # fmt: skip
        out["compliance_compressed"] = r["compliance"]
    if "band" in rows:
        from benchmarks.spatial_convergence import tangential_at

        refs = band_references()
        errors = [tangential_at(density, load, material=material, layers=layers, law=law, hourglass=hourglass,
                                sim=sim) / refs[load] - 1.0 for load in BAND_LOADS]  # fmt: skip
        out["band_mean"] = float(np.mean(errors))
        out["band_spread"] = float(np.max(errors) - np.min(errors))
    if "slip" in rows:
        from benchmarks.partial_slip import ramp

        r = ramp(density, material=material, law=law, layers=layers, hourglass=hourglass, report=lambda *a: None,
                 sim=sim)  # fmt: skip
        out["first_slide"] = math.nan if r["first_slide"] is None else r["first_slide"]
        out["gross_slide"] = math.nan if r["gross"] is None else r["gross"]
    if "env" in rows or "hold" in rows:
        from benchmarks.grasp_checks import hold_bound

        h = hold_bound(kind, "v3", tissue=tissue, bracket=hold_bracket, report=report)
        out["hold_bound"] = math.nan if h is None else h["mass"]
        out["hold_ratio"] = math.nan if h is None else h["mass"] / h["coulomb"]
        out["hold_ratio_press"] = math.nan if h is None else h["mass"] / h["coulomb_press"]
        out["hold_ratio_cylinder"] = math.nan if h is None else h["mass"] / h["coulomb_cylinder"]
    if "env" in rows or "friction" in rows:
        from benchmarks.grasp_checks import lowest_friction

        f = lowest_friction(kind, "v3", tissue=tissue, bracket=friction_bracket, report=report)
        out["lowest_friction"] = math.nan if f is None else f["scale"]
        out["friction_ratio"] = math.nan if f is None else f["scale"] / f["coulomb"]
        out["friction_ratio_cylinder"] = math.nan if f is None else f["scale"] / f["coulomb_cylinder"]
    if "lever" in rows:
        from benchmarks.contact_patch import GRASPS
        from benchmarks.contact_patch import measure as patch

        for force in LEVER_FORCES:
            figs = patch(GRASPS["aligned (default)"], tissue=tissue, finger_force=force, material_solve=solve)
            levers = [f["lever"].mean() for f in figs if f]
            out[f"lever_{force:g}N"] = float(np.mean(levers)) if levers else math.nan
    if "rim" in rows:
        import gymnasium as gym

        from benchmarks.rim_creep import KINDS, episode

        env = gym.make(KINDS["tissue"], tissue=tissue, material_solve=solve)
        try:
            pushes = [episode(env, 0.04, 0.11, 0.0, s, {"cylinder_mass": 0.2, "friction_scale": 0.5})[3]
                      for s in range(1000, 1000 + seeds)]  # fmt: skip
        finally:
            env.close()
        out["rim_push"] = float(np.median(pushes))
    out["seconds"] = time.perf_counter() - tic
    report(f"{density:>9,.0f}/m^2, {layers} layer(s), done in {out['seconds']:.0f} s: "
           + ", ".join(f"{k} {v:.5g}" for k, v in out.items() if k not in ("density", "seconds")))  # fmt: skip
    return out


_COULOMB: dict[float, float] = {}


def coulomb_compliance(load: float) -> float:
    """The compressed 3-D reference's tangential compliance at ``load`` [N] read as the rig reads the
    tissue's [m/N]: Coulomb's law at every strip node at the default friction (mu 0.9), the pad the
    cylinder compressed (pad_reference.partial_slip_3d with the plane-strain model's indentation and
    pressure at nu 0), the secant between the two holds (U = SHEAR load / 6 and SHEAR load / 2,
    spatial_convergence.tangential_at's). A coarse mesh, 4 mm along the face and 1 mm across the
    strip: about 16 s per load, where the 2 mm one takes over 15 min; computed once per load."""
    if load not in _COULOMB:
        from benchmarks.pad_reference import LayerModel, default_pad, partial_slip_3d
        from benchmarks.spatial_convergence import SHEAR
        from softgrasp_env.config import TissueConfig

        pad = default_pad()
        model = LayerModel(pad, 0.0)
        delta, contact = model.indentation(load)
        ramp = partial_slip_3d(pad, model.y, contact["pressure"], TissueConfig().friction_static, element=4e-3,
                               across=1e-3, indentation=delta)  # fmt: skip
        u1, u2 = SHEAR * load / 6.0, SHEAR * load / 2.0
        if u2 >= ramp["U"][-1]:
            raise RuntimeError(f"the reference slid entirely before the rig's second hold at {load} N")
        q1, q2 = np.interp([u1, u2], ramp["U"], ramp["Q"])
        _COULOMB[load] = (u2 - u1) / (q2 - q1)
    return _COULOMB[load]


def band_references() -> dict[float, float]:
    """coulomb_compliance at each of BAND_LOADS [m/N]."""
    return {load: coulomb_compliance(load) for load in BAND_LOADS}


def observed_orders(values: list[float], ref: float) -> list[float]:
    """log2 of the ratio of successive errors |value - ref| (the spacing halves per density)."""
    e = [abs(v - ref) for v in values]
    return [math.log2(a / b) if a > 0 and b > 0 and math.isfinite(a / b) else math.nan
            for a, b in zip(e, e[1:], strict=False)]  # fmt: skip


def self_orders(values: list[float]) -> list[float]:
    """log2 of the ratio of successive changes (no reference: self-convergence)."""
    d = [abs(b - a) for a, b in zip(values, values[1:], strict=False)]
    return [math.log2(a / b) if a > 0 and b > 0 and math.isfinite(a / b) else math.nan
            for a, b in zip(d, d[1:], strict=False)]  # fmt: skip


def references(rows) -> dict[str, float]:
    """The row keys with an external reference, and its value."""
    refs = {"first_slide": 0.0, "gross_slide": 1.0, "hold_ratio": 1.0, "hold_ratio_press": 1.0, "hold_ratio_cylinder": 1.0,
            "friction_ratio_cylinder": 1.0, "band_mean": 0.0, "band_spread": 0.0,
            "friction_ratio": 1.0, "rim_push": 0.0}  # fmt: skip
    if "rig" in rows:
        from benchmarks.pad_reference import default_pad, reference

        ref = {(r["nu"], r["load"]): r for r in reference(default_pad(), loads=(1.0, 3.0, 6.0))}
        refs.update({f"compression_{f:g}N": ref[(0.0, f)]["delta"] for f in (1.0, 3.0, 6.0)})
        refs["width_3N"] = ref[(0.0, 3.0)]["width"]
        refs["compliance"] = ref[(0.0, 3.0)]["compliance"]
        refs["compliance_compressed"] = coulomb_compliance(3.0)
    return refs


TITLES = {
    "compression_1N": ("compression, 1 N [mm]", 1e3), "compression_3N": ("compression, 3 N [mm]", 1e3),
    "compression_6N": ("compression, 6 N [mm]", 1e3), "width_3N": ("RMS half-width, 3 N [mm]", 1e3),
    "compliance": ("tangential compliance, one pad [mm/N]", 1e3),
    "compliance_compressed": ("... against the compressed pad pulled with Coulomb at every node [mm/N]", 1e3),
    "band_mean": ("tangential over 2-4 N against the compressed Coulomb ref: mean error", 1.0),
    "band_spread": ("... its spread (largest - smallest error)", 1.0),
    "first_slide": ("first contact slides at Q / mu P", 1.0), "gross_slide": ("whole strip slides at Q / mu P", 1.0),
    "hold_bound": ("hold bound [kg]", 1.0), "hold_ratio": ("hold bound / (2 mu F / (g + a))", 1.0),
    "hold_ratio_press": ("hold bound / (mu sum N / (g + a))", 1.0),
    "hold_ratio_cylinder": ("hold bound / (2 mu F / (g + a_cylinder))", 1.0),
    "lowest_friction": ("lowest friction that lifts 0.1 kg [x default]", 1.0),
    "friction_ratio": ("lowest friction / (m (g + a) / 2 mu F)", 1.0),
    "friction_ratio_cylinder": ("lowest friction / (m (g + a_cylinder) / 2 mu F)", 1.0),
    "lever_1N": ("torsional lever at 1 N [mm]", 1e3), "lever_6N": ("torsional lever at 6 N [mm]", 1e3),
    "rim_push": ("rim push, median [N]", 1.0),
}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--material", choices=GROUP_ENERGIES, default="shape_matching")
    parser.add_argument("--law", choices=FRICTION_LAWS, default="patch")
    parser.add_argument("--layers", default="1", help="one count, one per density (comma-separated) or 'auto'")
    parser.add_argument("--hourglass", type=float, default=0.0, help="TissueConfig.hourglass_stiffness")
    parser.add_argument("--densities", default=",".join(f"{d:.0f}" for d in DENSITIES))
    parser.add_argument("--rows", default=",".join(ROWS),
                        help=f"comma-separated, of {', '.join(ROWS + tuple(SPLIT_ROWS))}")  # fmt: skip
    parser.add_argument("--hold-bracket", default="0.05,1.5", help="kg: where the hold bound's bisection starts")
    parser.add_argument("--friction-bracket", default="0.05,1", help="where the lowest friction's bisection starts")
    parser.add_argument("--seeds", type=int, default=3, help="episodes of the rim row (seeds 1000, ...)")
    parser.add_argument("--material-solve", choices=MATERIAL_SOLVES, default="groups",
                        help="SimConfig.material_solve in every row")  # fmt: skip
    parser.add_argument("--out", type=Path, default=OUT)
    ns = parser.parse_args(argv)
    rows = ns.rows.split(",")
    bad = [r for r in rows if r not in ROWS + tuple(SPLIT_ROWS)]
    if bad:
        parser.error(f"--rows: {bad} not among {ROWS + tuple(SPLIT_ROWS)}")
    brackets = {}
    for name, text, (lo_limit, hi_limit) in (("hold", ns.hold_bracket, (0.05, 1.5)),
                                             ("friction", ns.friction_bracket, (0.05, 1.0))):  # fmt: skip
        try:
            lo, hi = (float(v) for v in text.split(","))
        except ValueError:
            parser.error(f"--{name}-bracket must be two comma-separated numbers, got {text!r}")
        if not lo_limit <= lo < hi <= hi_limit:
            parser.error(f"--{name}-bracket must be increasing inside {lo_limit:g}-{hi_limit:g}, got {text!r}")
        brackets[name] = (lo, hi)
    try:
        densities = [float(d) for d in ns.densities.split(",")]
    except ValueError:
        parser.error(f"--densities must be comma-separated numbers, got {ns.densities!r}")
    if not all(math.isfinite(d) and d > 0 for d in densities):
        parser.error(f"--densities must be positive, got {densities}")
    if ns.seeds < 1:
        parser.error(f"--seeds must be >= 1, got {ns.seeds}")
    if ns.layers == "auto":
        layers = [TissueConfig(particle_density=d).auto_layers for d in densities]
    else:
        try:
            layers = [int(v) for v in ns.layers.split(",")]
        except ValueError:
            parser.error(f"--layers must be 'auto' or comma-separated integers, got {ns.layers!r}")
        layers = layers * len(densities) if len(layers) == 1 else layers
        if len(layers) != len(densities):
            parser.error(f"--layers: {len(layers)} counts for {len(densities)} densities")
    for n in set(layers):  # a clear error for a bad mix before any work
        TissueConfig(group_energy=ns.material, friction_law=ns.law, layers=n, hourglass_stiffness=ns.hourglass)
    print(f"material {ns.material}, hourglass {ns.hourglass:g}, friction law {ns.law}, layers {ns.layers} "
          f"({', '.join(map(str, layers))}), material solve {ns.material_solve}; dt 1/240 s, 3 iterations; 1 process, "
          "1 thread", flush=True)  # fmt: skip
    refs = references(rows)
    results = [measure(d, rows, material=ns.material, law=ns.law, layers=n, seeds=ns.seeds, hourglass=ns.hourglass,
                       hold_bracket=brackets["hold"], friction_bracket=brackets["friction"], solve=ns.material_solve)
               for d, n in zip(densities, layers, strict=True)]  # fmt: skip
    print()
    table = []
    for key, (title, scale) in TITLES.items():
        if key not in results[0]:
            continue
        vals = [r[key] for r in results]
        ref = refs.get(key)
        line = f"{title:<48}" + "".join(f"{v * scale:>10.4g}" for v in vals)
        if ref is not None:
            errs = [(v - ref) / ref if ref else v - ref for v in vals]
            line += f"   ref {ref * scale:.4g}; error " + " ".join(
                f"{e:+.1%}" if ref else f"{e * scale:+.3g}" for e in errs)  # fmt: skip
            line += "; order " + " ".join(f"{o:+.2f}" for o in observed_orders(vals, ref))
        else:
            errs = [math.nan] * len(vals)
            line += "; self-order " + " ".join(f"{o:+.2f}" for o in self_orders(vals))
        print(line)
        for r, v, e in zip(results, vals, errs, strict=True):
            table.append((key, f"{r['density']:.0f}", r["layers"], f"{v:.6g}", "" if ref is None else f"{ref:.6g}",
                          f"{e:.6g}"))  # fmt: skip
    print("densities: " + ", ".join(f"{r['density']:.0f} ({r['layers']} layer{'s' if r['layers'] > 1 else ''})"
                                    for r in results))  # fmt: skip
    ns.out.mkdir(parents=True, exist_ok=True)
    suffix = (f"_{ns.material}_{ns.law}" + ("" if ns.hourglass == 0 else f"_h{ns.hourglass:g}")
              + ("" if ns.layers == "1" else f"_L{ns.layers.replace(',', '-')}")
              + ("" if ns.material_solve == "groups" else f"_{ns.material_solve}"))  # fmt: skip
    if set(rows) <= set(SPLIT_ROWS):  # one half of the env row: its own file, so the halves can run side by side
        suffix += "_" + "-".join(rows)
    path = ns.out / f"convergence_table{suffix}.csv"
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["quantity", "density_per_m2", "layers", "value", "reference", "relative_error"])
        w.writerows(table)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
