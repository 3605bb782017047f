"""Slip felt before it happens: how far ahead of gross slip the taxels warn, per finger kind.

    PYTHONPATH=. python benchmarks/slip_warning.py [--kinds tissue,peer,rigid] [--rates 1,2,4]
        [--squeezes 2,3,4] [--frictions 0.7,0.9,1.1] [--csv docs/results/slip_warning.csv]

The scripted grasp holds the default cylinder, then the cylinder is made heavier at a rate [N/s]
until it slides 1 mm in the grip beyond the pads' own shear (accuracy.shear_under_load): gross
slip, at the slip load. Every two physics steps the pads' 4 x 4 taxels are read and the detector
(fingers/tactile.py ``slip_warning``: on either pad, at least 10 % of the pressure on taxels whose
traction is at least 0.9 mu times their pressure - the sliding annulus of Cattaneo and Mindlin's
partial slip) says whether part of the grip slides. The warning is the detector's last
uninterrupted run of "on" that lasts into gross slip. Its lead: the load between the warning and
gross slip, as a share of the slip load, and as time at the ramp's rate. The detector missed the
slip (lead 0) when it is off at gross slip, or when that run began far from slip (below half the
slip load, where the grip holds with twice the margin it needs: a detector on there warns of
nothing, and the rigid pads' saturated contact points keep it on from the hold); "on far from
slip" counts the runs where it was on anywhere below half the slip load (false alarms).

A second detector on the same readings does not need mu (fingers/tactile.py ``shear_lag_warning``:
on either pad, the least sheared of the pressed taxels lags the most sheared by at least 25 %
along the pad's mean shear - the slip annulus falling behind the stick zone); its columns are
prefixed ``lag_``. It reads the tissue's shear, which rigid pads do not have.

The band: ramp rates x squeezes per finger x friction coefficients (mu_s = mu_k, the mu detector
told the true mu). Kinds: ``tissue`` the v4 soft pads (Coulomb per contact: partial slip; the
soft ids' v4), ``tissue_global`` the same tissue solved globally (the soft ids' v5), ``peer`` the
rigid fingers with torsional friction (pybullet's contact points binned onto the same taxels),
``rigid`` the bare rigid twin.
"""

from __future__ import annotations

import argparse
import csv
import itertools
from dataclasses import replace
from pathlib import Path

import numpy as np

from softgrasp_env.accuracy import shear_under_load
from softgrasp_env.config import SimConfig
from softgrasp_env.fingers import TorsionalRigidConfig
from softgrasp_env.fingers.tactile import SHEAR_LAG, SLIP_RATIO, SLIP_SHARE, shear_lag_warning, slip_warning
from softgrasp_env.presets import v4_tissue
from softgrasp_env.scene import GraspScene, SceneConfig

ROOT = Path(__file__).resolve().parents[1]
KINDS = {"tissue": lambda: SceneConfig(tissue=v4_tissue()),
         "tissue_global": lambda: SceneConfig(tissue=v4_tissue(), sim=SimConfig(material_solve="global")),
         "peer": lambda: SceneConfig(fingers=TorsionalRigidConfig()),
         "rigid": lambda: SceneConfig(fingers="rigid")}  # fmt: skip
EVERY = 2
"""Physics steps between taxel readings."""


FAR = 0.5
"""Below this share of the slip load the grip holds with twice the margin it needs: a detector on
there tells nothing about the coming slip (a false alarm, or a detector that is always on)."""


def warning_lead(load: np.ndarray, warn: np.ndarray, slip_load: float) -> tuple[float, bool]:
    """(the load at which the warning that lasts into gross slip began - ``slip_load`` when the
    detector is off at slip or was already on far from it (below FAR of the slip load, where it
    warns of nothing); whether it was on anywhere far from slip)."""
    far = bool(np.any(warn & (load < FAR * slip_load)))
    if not warn.size or not warn[-1]:
        return slip_load, far
    start = len(warn) - 1
    while start > 0 and warn[start - 1]:
        start -= 1
    return (slip_load if load[start] < FAR * slip_load else float(load[start])), far


def measure(kind: str, rate: float, squeeze: float, mu: float) -> dict[str, float | str]:
    base = KINDS[kind]()
    cfg = replace(base, finger_force=squeeze, tissue=replace(base.tissue, friction_static=mu, friction_kinetic=None))
    scene = GraspScene(cfg)
    try:
        rec = shear_under_load(scene, rate=rate, every=EVERY, rows=4, cols=4, max_load=3.0 * mu * squeeze)
    finally:
        scene.close()
    row: dict[str, float | str] = {"kind": kind, "rate_N_s": rate, "squeeze_N": squeeze, "mu": mu,
                                   "coulomb_N": 2.0 * mu * squeeze, "slip_load_N": rec.slip_load}  # fmt: skip
    for prefix, warn in (("", slip_warning(rec.fields, mu)), ("lag_", shear_lag_warning(rec.fields))):
        start, far = warning_lead(rec.load, warn, rec.slip_load)
        lead = rec.slip_load - start
        row |= {f"{prefix}warning_load_N": start, f"{prefix}lead_share": lead / rec.slip_load,
                f"{prefix}lead_s": lead / rate, f"{prefix}on_far_from_slip": far}  # fmt: skip
    return row | {"samples": len(rec.load)}


def _floats(text: str) -> list[float]:
    return [float(v) for v in text.split(",") if v]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--kinds", default="tissue,peer,rigid")
    parser.add_argument("--rates", default="1,2,4", help="growth of the cylinder's weight [N/s]")
    parser.add_argument("--squeezes", default="2,3,4", help="finger force [N]")
    parser.add_argument("--frictions", default="0.7,0.9,1.1", help="mu_s = mu_k")
    parser.add_argument("--csv", type=Path, default=None, help="write every run's row here")
    ns = parser.parse_args(argv)
    kinds = ns.kinds.split(",")
    for k in kinds:
        if k not in KINDS:
            parser.error(f"--kinds: {k!r} is not one of {tuple(KINDS)}")
    rates, squeezes, frictions = _floats(ns.rates), _floats(ns.squeezes), _floats(ns.frictions)
    if not all(v > 0 for v in rates + squeezes + frictions):
        parser.error("rates, squeezes and frictions must be > 0")
    print(f"detectors: mu, either pad with >= {SLIP_SHARE:.0%} of its pressure on taxels at >= {SLIP_RATIO:g} mu; "
          f"lag, either pad's shear lag >= {SHEAR_LAG:g}; "
          f"{len(rates)} rates x {len(squeezes)} squeezes x {len(frictions)} frictions per kind")  # fmt: skip
    rows = []
    for kind in kinds:
        for rate, squeeze, mu in itertools.product(rates, squeezes, frictions):
            row = measure(kind, rate, squeeze, mu)
            rows.append(row)
            print(f"{kind:<7} {rate:>4g} N/s {squeeze:>4g} N mu {mu:<4g} slip {row['slip_load_N']:6.2f} N "
                  f"({row['slip_load_N'] / row['coulomb_N']:.2f} x Coulomb), warned at {row['warning_load_N']:6.2f} N: "
                  f"lead {row['lead_share']:6.1%} of the load, {row['lead_s'] * 1e3:6.0f} ms; "
                  f"{'on far from slip' if row['on_far_from_slip'] else 'quiet far from slip'}; lag detector: lead "
                  f"{row['lag_lead_share']:6.1%}, {row['lag_lead_s'] * 1e3:6.0f} ms, "
                  f"{'on far from slip' if row['lag_on_far_from_slip'] else 'quiet far from slip'}", flush=True)  # fmt: skip
    print()
    print("| detector | kind | runs | warned (lead >= 20 % of the load or >= 100 ms) | lead, share of the slip load: median "
          "(min - max) | lead time [ms]: median (min - max) | missed | on far from slip |")
    print("|---|---|---|---|---|---|---|---|")
    for (p, name), kind in itertools.product((("", "mu"), ("lag_", "shear lag")), kinds):
        mine = [r for r in rows if r["kind"] == kind]
        share = np.array([r[f"{p}lead_share"] for r in mine])
        ms = np.array([r[f"{p}lead_s"] for r in mine]) * 1e3
        ok = sum(1 for r in mine if r[f"{p}lead_share"] >= 0.2 or r[f"{p}lead_s"] >= 0.1)
        missed = sum(1 for r in mine if r[f"{p}lead_share"] == 0.0)
        far = sum(1 for r in mine if r[f"{p}on_far_from_slip"])
        print(f"| {name} | {kind} | {len(mine)} | {ok} | {np.median(share):.0%} ({share.min():.0%} - {share.max():.0%}) | "
              f"{np.median(ms):.0f} ({ms.min():.0f} - {ms.max():.0f}) | {missed} | {far} |")
    if ns.csv is not None:
        ns.csv.parent.mkdir(parents=True, exist_ok=True)
        with open(ns.csv, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(rows[0]))
            writer.writeheader()
            for r in rows:
                writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
        print(f"wrote {ns.csv}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
