"""Does a layered pad shear as the continuum does? A flat rigid punch pressed into the tissue's pad
and stuck to it, then moved along the face: the pad's tangential compliance and how far each
particle layer travels, against the finite-element reference with the same stuck strip.

    PYTHONPATH=. python benchmarks/layer_shear.py [--densities 64000] [--layers 1,2,4] [--no-reference] [--linear]

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

``--linear`` solves the same punches on the discrete energy itself (linear_shear: its Hessian
about the rest state, the stuck strip held, no solver, no press): the discretisation alone, at
layer counts the rig cannot afford (eight layers at 1,024,000 per m^2 in a minute).
"""

from __future__ import annotations

import argparse

import numpy as np

from benchmarks.partial_slip import contacts
from benchmarks.spatial_convergence import RAMP_SPEED, PadRig
from softgrasp_env.presets import v4_tissue
from softgrasp_env.tissue.builder import CoreShape, build_combined_body

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


def discrete_hessian(model):
    """(3N, 3N) sparse, the Hessian of the tissue's discrete energy (the continuum group energy and its
    hourglass term, builder.continuum_groups) about the rest state [N/m], from the model's own rest
    data: what the solver's static equilibrium is, with no dynamics, contacts or iterations.

    Group g, members j with b_j = A_qq^-1 m_j q_j and k = 2 G V_g (g_cont column 6): the energy
    (k / 2) ||sym(sum_j u_j b_j^T)||^2 (G V ||F - R||^2 for a small displacement u: R takes the
    skew part) has the blocks (k / 2) ((b_j . b_k) I + b_k b_j^T); the hourglass term
    (beta / 2) sum_i m_i ||r_i||^2, r_i = sum_k (delta_ik - w_k - b_k . q_i) u_k (w_k = m_k / M the
    fit centre's weights), the blocks beta (P^T diag(m) P)_jk I."""
    import scipy.sparse as sp

    off, mem, rest = model.group_offsets, model.group_members, model.group_rest_offset
    cont = model.group_continuum
    rows, cols, vals = [], [], []
    eye = np.eye(3)
    for g in range(off.shape[0] - 1):
        e = slice(int(off[g]), int(off[g + 1]))
        j = mem[e].astype(np.int64)
        m = model.particle_mass[j]
        q = rest[e]
        ainv = cont[g, [[0, 1, 2], [1, 3, 4], [2, 4, 5]]]
        b = (m[:, None] * q) @ ainv
        n = j.shape[0]
        dots = b @ b.T
        block = 0.5 * cont[g, 6] * (np.kron(dots, eye) + np.einsum("ka,jb->jakb", b, b).reshape(3 * n, 3 * n))
        if cont[g, 7] > 0.0:
            p = np.eye(n) - (m / m.sum())[None, :] - q @ b.T
            block += cont[g, 7] * np.kron(p.T @ (m[:, None] * p), eye)
        idx = (3 * j[:, None] + np.arange(3)).ravel()
        rows.append(np.repeat(idx, 3 * n))
        cols.append(np.tile(idx, 3 * n))
        vals.append(block.ravel())
    size = 3 * model.particle_count
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(size, size))


def linear_shear(density: float, layers: int, half_width: float) -> dict:
    """The punch of ``shear`` on the discrete energy itself: the static equilibrium of
    discrete_hessian with the core's particles held, the surface particles with |y| <= half_width
    stuck to the punch and moved along the axis, every other particle free. No press, no contact
    law, no solver: what the discretisation gives, layer counts the rig cannot afford included.
    Returns what ``shear`` does (the touching columns: the stuck ones)."""
    import scipy.sparse.linalg as spla

    from softgrasp_env.scene import SceneConfig

    tissue = v4_tissue(layers=layers, particle_density=density)
    hx, hy, hz = SceneConfig().finger_half_extents
    model = build_combined_body(CoreShape("box", half_extents=(hx, hy, hz)), tissue, faces=("+x",))
    x = model.particle_rest_x
    layer = np.rint((x[:, 0] - hx) / (tissue.extrude / layers)).astype(int)
    stuck = (layer == layers) & (np.abs(x[:, 1]) <= half_width)
    held = np.repeat((layer == 0) | stuck, 3)
    travel = 1e-4
    u = np.zeros(3 * model.particle_count)
    u[3 * np.flatnonzero(stuck) + 2] = travel
    h = discrete_hessian(model)
    free = ~held
    u[free] = spla.spsolve(h[free][:, free].tocsc(), -(h[free][:, held] @ u[held]))
    force = float((h @ u)[3 * np.flatnonzero(stuck) + 2].sum())
    uz = u[2::3] / travel
    mid = (np.abs(x[:, 2]) < 0.5 * hz) & (np.abs(x[:, 1]) < 0.01)
    profile = {int(k): float(uz[mid & (layer == k)].mean()) for k in np.unique(layer[mid])}
    return {"compliance": travel / force, "columns": np.unique(np.round(np.abs(x[stuck, 1]), 4)), "profile": profile}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--densities", default="64000")
    parser.add_argument("--layers", default="1,2,4")
    parser.add_argument("--no-reference", action="store_true", help="skip the finite-element reference (scikit-fem)")
    parser.add_argument("--linear", action="store_true", help="the discrete energy's static equilibrium, not the rig")
    args = parser.parse_args(argv)
    run = linear_shear if args.linear else shear
    for density in (float(d) for d in args.densities.split(",")):
        for name, half in HALF_WIDTHS.items():
            for layers in (int(v) for v in args.layers.split(",")):
                r = run(density, layers, half)
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
