"""Partial slip of the tissue's pad under a growing tangential load, against Cattaneo-Mindlin and
the finite-element reference.

    PYTHONPATH=. python benchmarks/partial_slip.py [--densities 4000,16000,64000] [--material continuum]
        [--law contact] [--layers 1,2,4] [--hourglass 1] [--friction 0.3] [--reference anti-plane | 3d]

The rig is the convergence benchmark's (spatial_convergence.PadRig: one finger's inner face of
tissue, its core fixed, the scene's 3 cm cylinder standing upright, moved kinematically), with the
default friction (mu 0.9, one coefficient) and the friction law ``--law``. The cylinder is pressed to
3 N, then driven down its own axis at ``SPEED`` until the whole contact slides. Every step gives the
axial load Q and the normal load P the cylinder feels, and each tissue contact's mode at the end of
the step (the solver's stick/slide state: a contact stuck, or slid, within its own cone under
``friction_law="contact"``; under the patch law the patch's mode for all its contacts).

Printed per density, at Q / mu P = 0.1 ... 0.95 (the first step at or above each): the share of
the contacts' normal load that sticks (also per band, BANDS), the stick zone's half-width c over
the contact's half-width a (the farthest touching contact from the strip's centre line, across the
strip): c is the |y| within which the contacts carry the sticking share of the normal load, read
off their cumulative load (the farthest sticking contact alone is quantised to the few columns
across the strip), and the two textbook curves for a line contact under a tangential load along it
(the shear traction in the stick zone, the slip zones at the edges where it reaches mu p):
c / a = (1 - Q / mu P)^(1/2) for a Hertzian (elliptic) pressure on an elastic half-space
(Cattaneo 1938, Mindlin 1949; Johnson 1985, sec. 7.2), and (1 - Q / mu P)^(1/3) for a parabolic
pressure on a thin elastic layer, whose shear traction in the stick zone is uniform (a layer of
tangential springs; the pad's contact half-width is 0.9 to 1.8 times its thickness, between the
two). c / a is also given over the middle half of the face's height alone (away from its free
ends), and the stick share over the face's trailing half (the upper one: the cylinder moves down,
away from it) and over its leading half. Also printed: the tangential compliance (dU / dQ over the
first and the last stretch) and the load at which the first contact slides and at which all of
them do. ``--reference`` adds the
finite-element pad's stick share and c / a at the same Q / mu P (``reference``: Coulomb's law at
every node, pad_reference.LayerModel.partial_slip and partial_slip_3d), the curve for this pad's
own pressure profile and thickness; the 3-D pad also with the normal forces its pull changes (the
pull's couple presses the face's trailing end and lifts its leading one).
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from benchmarks.spatial_convergence import PadRig
from softgrasp_env.config import SimConfig, TissueConfig

SPEED = 2e-3
"""How fast the cylinder is driven down its axis [m/s]: slow enough that the pad's damping force
(SimConfig.damping 300/s) is a few per cent of the friction."""
LEVELS = (0.1, 0.25, 0.5, 0.75, 0.9, 0.95)
PRESS = 3.0
"""The normal load [N]."""


BANDS = ("centre", "middle", "edges")
"""The strip cut across its width into thirds of its half-width a (|y| / a in [0, 1/3), [1/3, 2/3),
[2/3, 1]): the stick share is also printed per band, the centre's and the edges' side by side. In
Cattaneo-Mindlin the slip zones grow in from the edges, so the edges' share falls first."""

WINDOW = 12
"""Steps over which a contact's slip is judged (12 steps: 0.1 mm of the cylinder's travel)."""
STICK = 0.2
"""A contact sticks over the window while its particle follows the cylinder's axial travel within
this fraction of that travel; the solver's own stick/slide flag of a single step is not used,
because a contact at its cone alternates between sticking one step and sliding (and stopping) the
next."""


def contacts(rig: PadRig) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The tissue contacts with the cylinder after the last step: (particle, normal multiplier,
    position across the strip [m])."""
    lc = rig.solver.last_contacts()
    n = lc.count
    keep = ~lc.inner[:n] & (lc.normal_lambda[:n] > 0.0) & (lc.shape[:n] == 1)
    particles = lc.particle[:n][keep].copy()
    y = rig.state.particle_x[particles, 1] - rig.col.rigid_x[1, 1]
    return particles, lc.normal_lambda[:n][keep].copy(), y


def stick_zone(lam: np.ndarray, y: np.ndarray, stuck: np.ndarray) -> tuple[float, float]:
    """(share, c / a): the sticking contacts' share of the normal load, and the |y| within which the
    contacts carry that share (between contacts, linearly, off their cumulative load) over the
    outermost contact's |y|."""
    total = float(lam.sum())
    a = float(np.abs(y).max())
    share = float(lam[stuck].sum() / total)
    if a <= 0.0:
        return share, 0.0
    order = np.argsort(np.abs(y))
    cum = np.concatenate(([0.0], np.cumsum(lam[order]) / total))
    return share, float(np.interp(share, cum, np.concatenate(([0.0], np.abs(y)[order])))) / a


def ramp(density: float, *, material: str = "shape_matching", law: str = "contact", layers: int = 1,
         hourglass: float = 0.0, friction: float | None = None, speed: float = SPEED, report=print,
         sim: SimConfig | None = None) -> dict:  # fmt: skip
    """Press to PRESS, then drive the cylinder down its axis until every contact slides. Returns
    the rows (Q / mu P, stick share, c / a) and the summary figures. ``layers``: TissueConfig.layers;
    ``hourglass``: TissueConfig.hourglass_stiffness; ``friction``: mu (TissueConfig's default if None);
    ``speed``: the cylinder's axial speed [m/s]; ``sim``: the solver's settings (PadRig)."""
    tissue = TissueConfig(group_energy=material, friction_law=law, layers=layers, hourglass_stiffness=hourglass)
    rig = PadRig(density, tissue=tissue, friction=friction, sim=sim)
    mu = rig.tissue.friction_static
    c, _ = rig.press_to(PRESS, guess=2e-3)
    rows, u0 = [], rig.axial
    first_slide = gross = None
    v = np.array([0.0, 0.0, -speed])
    history: list[tuple[np.ndarray, float]] = []  # the particles' and the cylinder's axial positions
    loads: list[tuple[float, float]] = []
    for _ in range(round(0.02 / (speed * rig.sim.dt))):  # at most 20 mm
        f = rig.step(v)
        history.append((rig.state.particle_x[:, 2].copy(), rig.axial))
        loads.append((abs(float(f[2])), float(f[0])))
        if len(history) <= WINDOW:
            continue
        particles, lam, y = contacts(rig)
        if lam.size == 0:
            continue
        (z0, c0), (z1, c1) = history[-1 - WINDOW], history[-1]
        follow = (z1[particles] - z0[particles]) / (c1 - c0)  # 1: moves with the cylinder
        stuck = follow >= 1.0 - STICK
        q, p = np.mean(loads[-WINDOW:], axis=0)
        ratio = q / (mu * p)
        a = float(np.abs(y).max())
        share, c_load = stick_zone(lam, y, stuck)
        band = np.minimum((np.abs(y) / a * len(BANDS)).astype(int), len(BANDS) - 1) if a > 0 else np.zeros(y.size, int)
        bands = tuple(float(lam[stuck & (band == b)].sum() / max(lam[band == b].sum(), 1e-300)) for b in range(len(BANDS)))
        # the same over the middle half of the face's height, away from its free ends, where the
        # pad shears as the anti-plane reference's pad of infinite length
        z = rig.state.particle_x[particles, 2]  # the core's centre is the origin
        mid = np.abs(z) <= 0.25 * rig.face_height
        c_mid = stick_zone(lam[mid], y[mid], stuck[mid])[1] if mid.any() else math.nan
        # the face's two halves along the pull: the cylinder moves down, away from the upper
        # (trailing) end, whose contacts the pull's couple presses harder (partial_slip_3d)
        up = z > 0.0
        halves = tuple(float(lam[stuck & h].sum() / max(lam[h].sum(), 1e-300)) for h in (up, ~up))
        rows.append((ratio, share, c_load, u0 - rig.axial, q, bands, c_mid) + halves)
        if first_slide is None and not stuck.all():
            first_slide = ratio
        if not stuck.any():
            gross = ratio
            break
    out = {"density": density, "particles": rig.particle_count, "rows": rows, "first_slide": first_slide,
           "gross": gross, "compression": c}  # fmt: skip
    u = np.array([r[3] for r in rows])
    qq = np.array([r[4] for r in rows])
    if len(rows) > 4:
        k = max(2, len(rows) // 5)
        out["compliance_start"] = float(np.polyfit(qq[:k], u[:k], 1)[0])
    report(f"{density:>9,.0f}/m^2 ({rig.particle_count} particles, {material}, law {law}): pressed {c * 1e3:.2f} mm; "
           f"first contact slides at Q/muP {first_slide if first_slide is None else round(first_slide, 3)}, all at "
           f"{gross if gross is None else round(gross, 3)}")  # fmt: skip
    report("   Q/muP   stick share (centre middle edges; trailing leading)   c/a (all, mid-height)   (1-Q/muP)^1/2   "
           "(1-Q/muP)^1/3")  # fmt: skip
    out["levels"] = {}
    for level in LEVELS:
        hit = next((r for r in rows if r[0] >= level), None)
        if hit is None:
            continue
        out["levels"][level] = {"ratio": hit[0], "share": hit[1], "c_over_a": hit[2], "bands": hit[5],
                                "c_over_a_mid": hit[6], "trailing": hit[7], "leading": hit[8]}  # fmt: skip
        report(f"   {hit[0]:5.3f}   {hit[1]:9.3f}   ({hit[5][0]:.2f} {hit[5][1]:.2f} {hit[5][2]:.2f}; {hit[7]:.2f} "
               f"{hit[8]:.2f})   {hit[2]:6.3f} "
               f"{hit[6]:6.3f}   {math.sqrt(max(0.0, 1 - hit[0])):11.3f}   {max(0.0, 1 - hit[0]) ** (1 / 3):11.3f}")  # fmt: skip
    return out


COUPLED_MESH = dict(element=4e-3, across=1e-3)
"""The coupled 3-D reference's mesh [m] (along x and z, across the strip): the coarse one. On the
Goodman model it gives the stick share within 0.5 % of the 2 mm / 0.5 mm mesh at every level."""


def reference(mu: float, *, load: float = PRESS, full: bool = True) -> dict:
    """The finite-element reference's partial slip at ``load`` (benchmarks/pad_reference.py, nu 0,
    Coulomb's law at every node): the anti-plane pad of infinite length ("anti_plane") and, with
    ``full``, the 3-D pad of the face's length under Goodman's approximation ("3d", 2 mm elements,
    0.5 mm across the strip; about 4 minutes) and with the normal forces the pull changes
    ("3d_coupled": partial_slip_3d's ``goodman`` False, COUPLED_MESH; about 5 minutes). Each maps
    LEVELS to (stick share, c / a). Under Goodman's approximation neither depends on mu; coupled,
    the pull's couple grows with mu."""
    from benchmarks.pad_reference import LayerModel, at_ratios, default_pad, partial_slip_3d

    pad = default_pad()
    model = LayerModel(pad, 0.0)
    _, c = model.indentation(load)
    ramps = {"anti_plane": model.partial_slip(c["f"], mu)}
    if full:
        ramps["3d"] = partial_slip_3d(pad, model.y, c["pressure"], mu)
        ramps["3d_coupled"] = partial_slip_3d(pad, model.y, c["pressure"], mu, goodman=False, **COUPLED_MESH)
    return {name: dict(zip(LEVELS, zip(at_ratios(r, LEVELS, "share"), at_ratios(r, LEVELS), strict=True), strict=True))
            for name, r in ramps.items()}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--densities", default="4000,16000,64000")
    parser.add_argument("--material", default="shape_matching", choices=["shape_matching", "continuum"])
    parser.add_argument("--law", default="contact", choices=["contact", "patch"])
    parser.add_argument("--layers", default="1", help="TissueConfig.layers per density, a comma list (one for all)")
    parser.add_argument("--hourglass", type=float, default=0.0, help="TissueConfig.hourglass_stiffness")
    parser.add_argument("--friction", type=float, default=None, help="mu (TissueConfig's default if not given)")
    parser.add_argument("--reference", choices=["none", "anti-plane", "3d"], default="none",
                        help="also print the finite-element reference's stick share and c/a (needs scikit-fem; "
                             "'3d' adds the pad of finite length, Goodman's and coupled, about 10 minutes)")  # fmt: skip
    args = parser.parse_args(argv)
    densities = [float(d) for d in args.densities.split(",")]
    layers = [int(v) for v in args.layers.split(",")]
    if len(layers) not in (1, len(densities)):
        parser.error(f"--layers gives {len(layers)} counts for {len(densities)} densities")
    layers = layers * len(densities) if len(layers) == 1 else layers
    for d, n in zip(densities, layers, strict=True):
        ramp(d, material=args.material, law=args.law, layers=n, hourglass=args.hourglass, friction=args.friction)
    if args.reference != "none":
        mu = args.friction if args.friction is not None else TissueConfig().friction_static
        ref = reference(mu, full=args.reference == "3d")
        print(f"reference (finite elements, nu 0, {PRESS:g} N):   Q/muP   stick share   c/a")
        for name, rows in ref.items():
            for level, (share, c) in rows.items():
                print(f"   {name:>10}   {level:5.2f}   {share:11.3f}   {c:5.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
