"""Does a layered pad shear as the continuum does? A flat rigid punch pressed into the tissue's pad
and stuck to it, then moved along the face: the pad's tangential compliance and how far each
particle layer travels, against the finite-element reference with the same stuck strip.

    PYTHONPATH=. python benchmarks/layer_shear.py [--densities 64000] [--layers 1,2,4] [--no-reference]

The rig is spatial_convergence.PadRig with ``punch``: one finger's inner face of tissue (the v4
material: the continuum energy, hourglass control 1, Coulomb per contact) pressed ``PRESS`` by a
box whose flat side is as wide as the strip (``HALF_WIDTHS``: the whole face, and the 3 N contact
strip's 11.3 mm), with friction ``MU`` so that nothing slides, then moved along the cylinder's axis
by 0.1 and 0.3 mm with a hold at each: the compliance is 0.2 mm over the change in the axial
load. Under the whole-face punch the continuum shears the layer uniformly, so the particle layers
at depth d travel d / h of the punch's travel (the middle half of the face, away from its edges).
The reference (pad_reference.tangential_compliance_3d, nu 0) holds the strip |y| <= a stuck; the
tissue's strip is its touching particle columns, so the reference is printed at the last touching
column's |y| and half a spacing further out (where the discrete strip's edge may sit).
One process, one thread; about a minute at 64,000 per m^2 (with the reference).
"""

from __future__ import annotations

import argparse

import numpy as np

from benchmarks.partial_slip import contacts
from benchmarks.spatial_convergence import RAMP_SPEED, PadRig
from softgrasp_env.presets import v4_tissue

PRESS = 0.5e-3
"""How far the punch presses into the pad [m] before it is moved along the face."""
MU = 10.0
"""Friction between punch and pad: high enough that no contact slides."""
HALF_WIDTHS = {"whole face": 0.025, "3 N strip": 0.0113}
"""The punch's half-width across the face [m]: wider than the face (20 mm), and the frictionless
cylinder's contact half-width under 3 N (pad_reference)."""


def shear(density: float, layers: int, half_width: float) -> dict:
    """One pad, one punch: its tangential compliance [m/N], the touching columns' |y| [m], and the
    particle layers' travel over the punch's (layer, 0 at the core -> mean fraction, over the
    middle half of the face)."""
    tissue = v4_tissue(layers=layers)
    rig = PadRig(density, tissue=tissue, friction=MU, punch=half_width)
    rig.move_to(PRESS)
    rig.hold()
    rig.move_to(PRESS, axial=-1e-4, speed=RAMP_SPEED / 2)
    first = rig.hold()
    before = rig.state.particle_x.copy()
    rig.move_to(PRESS, axial=-3e-4, speed=RAMP_SPEED / 2)
    second = rig.hold()
    after = rig.state.particle_x
    _, _, y = contacts(rig)
    layer = np.rint((before[:, 0] - rig.face_x) / (tissue.extrude / layers)).astype(int)  # 0 at the core
    travel = (after[:, 2] - before[:, 2]) / -2e-4
    mid = (np.abs(before[:, 2]) < 0.25 * rig.face_height) & (np.abs(before[:, 1]) < 0.01)
    profile = {int(k): float(travel[mid & (layer == k)].mean()) for k in np.unique(layer[mid])}
    return {"compliance": 2e-4 / float(second[2] - first[2]), "columns": np.unique(np.round(np.abs(y), 4)),
            "profile": profile}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--densities", default="64000")
    parser.add_argument("--layers", default="1,2,4")
    parser.add_argument("--no-reference", action="store_true", help="skip the finite-element reference (scikit-fem)")
    args = parser.parse_args(argv)
    for density in (float(d) for d in args.densities.split(",")):
        for name, half in HALF_WIDTHS.items():
            for layers in (int(v) for v in args.layers.split(",")):
                r = shear(density, layers, half)
                layers_travel = " / ".join(f"{v:.3f}" for v in r["profile"].values())
                print(f"{density:>9,.0f}/m^2, {layers} layer(s), punch: {name}: {r['compliance'] * 1e3:.4f} mm/N; "
                      f"layers travel {layers_travel} of the punch (uniform shear: evenly from 0 to 1)")  # fmt: skip
            if not args.no_reference:
                from benchmarks.pad_reference import default_pad, tangential_compliance_3d

                pad = default_pad()
                last = float(r["columns"].max())
                spacing = 1.0 / np.sqrt(density)
                ends = [min(a, 0.0195) for a in (last, last + 0.5 * spacing)]
                refs = ", ".join(f"a {a * 1e3:.1f} mm: {tangential_compliance_3d(pad, a, 0.0) * 1e3:.4f}" for a in ends)
                print(f"   reference, the strip |y| <= a stuck: {refs} mm/N")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
