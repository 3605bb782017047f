"""How the pads shear under a tangential load up to slip, against Cattaneo-Mindlin.

    PYTHONPATH=. python benchmarks/incipient_slip.py [--rate 2.0] [--fingers tissue,rigid,rigid_torsion]

The scripted grasp holds the default cylinder (3 N per finger, mu_s 0.9), then the cylinder is made
heavier at ``--rate`` N/s until it slips 1 mm on the pads (accuracy.shear_under_load). Per kind:
the load at slip against Coulomb's 2 mu_s F, the taxels' traction against the load, and the pads'
shear (the pressure-weighted mean over their loaded taxels) against the load.

Cattaneo-Mindlin (Johnson, Contact Mechanics, sec. 7.2): under a growing tangential load T a
Hertzian contact keeps a stick core that shrinks as T nears mu N, the annulus around it slipping,
so the tangential displacement softens, delta = delta_1 [1 - (1 - T / mu N)^(2/3)], and reaches
1.5 x the small-load stiffness' line at slip (for a line contact, as a cylinder's on a pad, the
same kind of softening, logarithmic). The line "at slip / linear" says how the pads compare: 1.0
for a pad that sticks everywhere until the patch as a whole lets go. The tissue's friction decides
per patch (tissue/friction.py: a pad breaks loose at mu_s as a whole, the patch-level Coulomb that
makes the hold bound exact), so it has no slipping annulus by construction: its shear before slip
is the elastic layer's alone; ``tissue-contact`` is the tissue with Coulomb's law at every contact
(friction_law "contact"), whose strip slips in from its edges. Writes docs/results/incipient_slip.png
with matplotlib.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from softgrasp_env.accuracy import shear_under_load
from softgrasp_env.config import TissueConfig
from softgrasp_env.scene import GraspScene, SceneConfig

ROOT = Path(__file__).resolve().parents[1]


NEAR_SLIP = 0.95
"""Share of the way to the slip load up to which the shear is read as before slip: the patch lets
go over the last few samples (the 1 mm criterion comes after the break)."""


def linearity(load: np.ndarray, shear: np.ndarray, slip_load: float) -> tuple[float, float]:
    """(small-load compliance d shear / d load [m/N], the shear at NEAR_SLIP of the way to slip
    over that line's value there): the compliance fitted over the first fifth of the way."""
    t0 = load[0]
    early = load <= t0 + 0.2 * (slip_load - t0)
    slope = float(np.polyfit(load[early], shear[early], 1)[0])
    before = load <= t0 + NEAR_SLIP * (slip_load - t0)
    at_slip = float(shear[before][-1] - shear[0])
    return slope, at_slip / (slope * (load[before][-1] - t0)) if slope > 0 else float("nan")


def scene_config(kind: str) -> SceneConfig:
    """The scene of a finger kind, or of ``tissue-contact``: the tissue with Coulomb's law at every
    contact (TissueConfig.friction_law "contact")."""
    if kind == "tissue-contact":
        return SceneConfig(fingers="tissue", tissue=TissueConfig(friction_law="contact"))
    return SceneConfig(fingers=kind)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rate", type=float, default=2.0, help="growth of the cylinder's weight [N/s]")
    parser.add_argument("--fingers", default="tissue,tissue-contact,rigid,rigid_torsion",
                        help="finger kinds; tissue-contact: the tissue with friction_law='contact'")
    parser.add_argument("--plot", type=Path, default=ROOT / "docs" / "results" / "incipient_slip.png")
    ns = parser.parse_args(argv)
    if not ns.rate > 0:
        parser.error(f"--rate must be > 0, got {ns.rate}")
    records = {}
    print(f"weight grown at {ns.rate:g} N/s from 0.1 kg; 3 N per finger, mu_s 0.9: Coulomb's slip load 2 mu_s F = 5.40 N")
    print(f"{'fingers':<15}{'slip load [N]':>14}{'vs Coulomb':>12}{'traction/load':>15}{'compliance':>14}"
          f"{'at slip / linear':>18}")  # fmt: skip
    for kind in ns.fingers.split(","):
        scene = GraspScene(scene_config(kind))
        try:
            rec = shear_under_load(scene, rate=ns.rate)
            mu, force = scene.config.tissue.friction_static, scene.config.finger_force
        finally:
            scene.close()
        records[kind] = rec
        bound = 2.0 * mu * force
        before = rec.load <= rec.load[0] + NEAR_SLIP * (rec.slip_load - rec.load[0])
        ratio = float(np.max(np.abs(rec.traction[before] / rec.load[before] - 1.0)))
        slope, lin = linearity(rec.load, rec.shear, rec.slip_load) if kind.startswith("tissue") else (0.0, float("nan"))
        print(f"{kind:<15}{rec.slip_load:>14.3f}{rec.slip_load / bound - 1:>+12.1%}{ratio:>14.2%} "
              f"{slope * 1e3:>10.3f} mm/N{lin:>18.3f}")  # fmt: skip
    cfg = SceneConfig()
    face = 4.0 * cfg.finger_half_extents[1] * cfg.finger_half_extents[2]
    layer = cfg.tissue.extrude / (2.0 * cfg.tissue.shear_modulus * face)
    print(f"traction/load: the largest gap up to {NEAR_SLIP:.0%} of the way to slip; compliance: the pads' mean shear "
          f"per N of load at small loads (two elastic layers of the pad's depth {cfg.tissue.extrude * 1e3:g} mm over "
          f"the whole face, G {cfg.tissue.shear_modulus:g} Pa: h / (2 G A) = {layer * 1e3:.3f} mm/N); at slip / linear: "
          f"the shear at {NEAR_SLIP:.0%} of the way to slip over the small-load line's (Cattaneo-Mindlin's circular "
          "contact: 1.5 at slip)")  # fmt: skip
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot")
        return 0
    rec = records.get("tissue")
    if rec is None:
        return 0
    slope, _ = linearity(rec.load, rec.shear, rec.slip_load)
    t = np.linspace(rec.load[0], rec.slip_load, 100)
    # Cattaneo-Mindlin's shape with the same small-load compliance and the same slip load:
    # delta = delta_1 [1 - (1 - u)^(2/3)], u the share of the way to slip, d delta / du = 2/3 delta_1 at 0
    span = rec.slip_load - rec.load[0]
    delta1 = 1.5 * slope * span
    u = (t - rec.load[0]) / span
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(rec.load, (rec.shear - rec.shear[0]) * 1e3, ".", label="tissue pads (taxels), the patch law")
    if "tissue-contact" in records:
        other = records["tissue-contact"]
        ax.plot(other.load, (other.shear - other.shear[0]) * 1e3, ".", label="tissue pads, Coulomb per contact")
    ax.plot(t, delta1 * (1 - (1 - u) ** (2 / 3)) * 1e3, "--", label="Cattaneo-Mindlin shape (same compliance)")
    ax.axvline(rec.slip_load, color="grey", lw=0.8)
    ax.set_xlabel("tangential load on the pads [N]")
    ax.set_ylabel("shear since the hold began [mm]")
    ax.set_title("Shear before slip: 3 N per finger, mu_s 0.9")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    ns.plot.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(ns.plot, dpi=100)
    print(f"wrote {ns.plot}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
