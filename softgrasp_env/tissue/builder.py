"""Build tissue: sample a core's surface (attached particles), extrude (outer particles), and form
the implicit shape-matching groups (thesis 5.1.1 and 5.2.1; Mueller & Chentanez 2011 sec. 4).

Everything here runs once per scene and is plain numpy.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Literal

import numba as nb
import numpy as np

from ..config import TissueConfig, kinetic_friction
from .model import CONTINUUM_COLUMNS, TissueModel

ShapeKind = Literal["box", "cylinder", "capsule", "sphere"]
SHAPE_KINDS: tuple[str, ...] = ("box", "cylinder", "capsule", "sphere")
ExtrudeDirection = Literal["normal", "radial"]


@dataclass(frozen=True)
class CoreShape:
    """Geometry of a rigid core in its centre-of-mass frame. Cylinders and capsules lie along z
    (pybullet's convention). Only the fields of the chosen kind are used."""

    kind: ShapeKind
    half_extents: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Box half extents [m]."""
    radius: float = 0.0
    """Sphere, cylinder and capsule radius [m]."""
    half_height: float = 0.0
    """Half length of a cylinder, or of a capsule's straight part [m]."""

    def __post_init__(self) -> None:
        if self.kind not in SHAPE_KINDS:
            raise ValueError(f"CoreShape.kind must be one of {SHAPE_KINDS}, got {self.kind!r}")
        if self.kind == "box":
            if len(self.half_extents) != 3 or not all(math.isfinite(h) and h > 0.0 for h in self.half_extents):
                raise ValueError(f"CoreShape.half_extents must be 3 positive lengths, got {self.half_extents!r}")
        else:
            if not (math.isfinite(self.radius) and self.radius > 0.0):
                raise ValueError(f"CoreShape.radius must be > 0 for a {self.kind}, got {self.radius!r}")
            if self.kind in ("cylinder", "capsule") and not (math.isfinite(self.half_height) and self.half_height > 0.0):
                raise ValueError(f"CoreShape.half_height must be > 0 for a {self.kind}, got {self.half_height!r}")

    @property
    def area(self) -> float:
        """Surface area [m^2]."""
        if self.kind == "box":
            a, b, c = self.half_extents
            return 8.0 * (a * b + b * c + a * c)
        r, h = self.radius, self.half_height
        if self.kind == "sphere":
            return 4.0 * math.pi * r * r
        if self.kind == "cylinder":
            return 2.0 * math.pi * r * (2.0 * h) + 2.0 * math.pi * r * r
        return 2.0 * math.pi * r * (2.0 * h) + 4.0 * math.pi * r * r


def core_shape_from_bullet(client, body: int, link: int = -1) -> tuple[CoreShape, np.ndarray, np.ndarray]:
    """Read a pybullet body's (single) collision shape: returns the shape and its local pose
    (position, quaternion) relative to the link's centre-of-mass frame."""
    import pybullet as p

    data = client.getCollisionShapeData(body, link)
    if len(data) != 1:
        raise ValueError(f"body {body} link {link} must have exactly one collision shape, has {len(data)}")
    _, _, geom, dims, _, pos, orn = data[0]
    if geom == p.GEOM_BOX:
        shape = CoreShape("box", half_extents=tuple(0.5 * float(d) for d in dims))
    elif geom == p.GEOM_SPHERE:
        shape = CoreShape("sphere", radius=float(dims[0]))
    elif geom == p.GEOM_CYLINDER:
        shape = CoreShape("cylinder", radius=float(dims[1]), half_height=0.5 * float(dims[0]))
    elif geom == p.GEOM_CAPSULE:
        shape = CoreShape("capsule", radius=float(dims[1]), half_height=0.5 * float(dims[0]))
    else:
        raise ValueError(f"body {body} link {link}: collision geometry type {geom} is not a supported core")
    return shape, np.asarray(pos, dtype=np.float64), np.asarray(orn, dtype=np.float64)


# --- surface sampling ----------------------------------------------------------------------------


def _grid(n_u: int, n_v: int) -> tuple[np.ndarray, np.ndarray]:
    u = (np.arange(n_u) + 0.5) / n_u * 2.0 - 1.0
    v = (np.arange(n_v) + 0.5) / n_v * 2.0 - 1.0
    uu, vv = np.meshgrid(u, v, indexing="ij")
    return uu.ravel(), vv.ravel()


def _count(length: float, spacing: float, minimum: int = 1) -> int:
    return max(minimum, int(round(length / spacing)))


def _fibonacci_sphere(n: int, upper_half_only: bool = False) -> np.ndarray:
    """n nearly even unit directions (golden-angle spiral); on the z >= 0 half if asked."""
    i = np.arange(n) + 0.5
    z = 1.0 - i / n if upper_half_only else 1.0 - 2.0 * i / n
    rho = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    phi = math.pi * (3.0 - math.sqrt(5.0)) * i
    return np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=1)


BOX_FACES: tuple[str, ...] = ("+x", "-x", "+y", "-y", "+z", "-z")
"""The faces of a box core, by outward normal in its frame."""


def _check_faces(shape: CoreShape, faces) -> frozenset[str] | None:
    if faces is None:
        return None
    if shape.kind != "box":
        raise ValueError(f"faces can be chosen for a box core only, got a {shape.kind}")
    chosen = frozenset(faces)
    if not chosen or not chosen <= set(BOX_FACES):
        raise ValueError(f"faces must be a non-empty subset of {BOX_FACES}, got {tuple(faces)!r}")
    return chosen


def sample_surface(shape: CoreShape, spacing: float, *, faces=None,
                   min_rows: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """Points spread evenly over the surface at about ``spacing``: (points, outward normals, area
    each point stands for). Areas sum to the surface area exactly. ``faces`` (box cores only:
    names from BOX_FACES) keeps those faces and leaves the rest bare; ``min_rows``: the fewest rows
    along each side of a box's face (TissueConfig.min_rows)."""
    if not spacing > 0.0:
        raise ValueError(f"spacing must be > 0, got {spacing!r}")
    chosen = _check_faces(shape, faces)
    pts, nrm, area = [], [], []
    if shape.kind == "box":
        h = np.asarray(shape.half_extents, dtype=np.float64)
        for axis in range(3):
            u_ax, v_ax = [a for a in range(3) if a != axis]
            n_u = _count(2 * h[u_ax], spacing, minimum=min_rows)
            n_v = _count(2 * h[v_ax], spacing, minimum=min_rows)
            uu, vv = _grid(n_u, n_v)
            for sign in (1.0, -1.0):
                if chosen is not None and f"{'+' if sign > 0 else '-'}{'xyz'[axis]}" not in chosen:
                    continue
                p = np.zeros((uu.size, 3))
                p[:, axis] = sign * h[axis]
                p[:, u_ax] = uu * h[u_ax]
                p[:, v_ax] = vv * h[v_ax]
                n = np.zeros_like(p)
                n[:, axis] = sign
                pts.append(p)
                nrm.append(n)
                area.append(np.full(uu.size, 4.0 * h[u_ax] * h[v_ax] / uu.size))
    elif shape.kind == "sphere":
        n = _count(shape.area, spacing * spacing, minimum=4)
        d = _fibonacci_sphere(n)
        pts.append(d * shape.radius)
        nrm.append(d)
        area.append(np.full(n, shape.area / n))
    else:  # cylinder or capsule: a side wall along z plus caps (flat discs or hemispheres)
        r, hh = shape.radius, shape.half_height
        n_z = _count(2 * hh, spacing)
        n_t = _count(2 * math.pi * r, spacing, minimum=3)
        theta = (np.arange(n_t) + 0.5) * 2 * math.pi / n_t
        z = ((np.arange(n_z) + 0.5) / n_z * 2 - 1) * hh
        tt, zz = np.meshgrid(theta, z, indexing="ij")
        d = np.stack([np.cos(tt.ravel()), np.sin(tt.ravel()), np.zeros(tt.size)], axis=1)
        pts.append(d * r + np.stack([np.zeros(tt.size), np.zeros(tt.size), zz.ravel()], axis=1))
        nrm.append(d)
        area.append(np.full(tt.size, 2 * math.pi * r * 2 * hh / tt.size))
        for sign in (1.0, -1.0):
            if shape.kind == "cylinder":
                # Concentric rings of equal-area cells: spacing holds along and across the rings.
                n_r = _count(r, spacing)
                for k in range(n_r):
                    r0, r1 = r * k / n_r, r * (k + 1) / n_r
                    rho = 0.5 * (r0 + r1)
                    m = _count(2 * math.pi * rho, spacing)
                    phi = (np.arange(m) + 0.5 * (k % 2)) * 2 * math.pi / m
                    p = np.stack([rho * np.cos(phi), rho * np.sin(phi), np.full(m, sign * hh)], axis=1)
                    pts.append(p)
                    nrm.append(np.tile([0.0, 0.0, sign], (m, 1)))
                    area.append(np.full(m, math.pi * (r1 * r1 - r0 * r0) / m))
            else:
                m = _count(2 * math.pi * r * r, spacing * spacing, minimum=2)
                d = _fibonacci_sphere(m, upper_half_only=True)
                d[:, 2] *= sign
                pts.append(d * r + np.array([0.0, 0.0, sign * hh]))
                nrm.append(d)
                area.append(np.full(m, 2 * math.pi * r * r / m))
    return np.concatenate(pts), np.concatenate(nrm), np.concatenate(area)


# --- orientations and groups ----------------------------------------------------------------------


def quat_z_to(n: np.ndarray) -> np.ndarray:
    """(K, 4) shortest-arc quaternions turning +z onto each unit vector of ``n`` (K, 3)."""
    n = np.asarray(n, dtype=np.float64)
    out = np.empty((n.shape[0], 4))
    # q = [z x n, 1 + z . n] normalised; the antipodal case (n = -z) takes a half turn about x.
    out[:, 0] = -n[:, 1]
    out[:, 1] = n[:, 0]
    out[:, 2] = 0.0
    out[:, 3] = 1.0 + n[:, 2]
    # Only an (almost) exact -z lacks a defined shortest arc; test the unnormalised quaternion's
    # length, not 1 + z.n, so directions a few 1e-5 rad off -z still get their own arc.
    anti = np.linalg.norm(out, axis=1) < 1e-12
    out[anti] = [1.0, 0.0, 0.0, 0.0]
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def build_groups(
    rest_x: np.ndarray, mass: np.ndarray, partner: np.ndarray, group_size: int, *, layer: np.ndarray | None = None,
    others: int | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Implicit groups (thesis 5.2.1): particle i, its partner(s), and its nearest others by rest
    distance until the group holds ``group_size`` particles (fewer only if the body is smaller);
    ties go to the lower index.

    ``partner``: (N,) one partner per particle, or (N, P) a list per particle, -1 for none (the
    particles directly below and above it through the thickness: build_combined_body with
    TissueConfig.layers > 1). ``layer``: (N,) int, if given the nearest others are taken from i's
    own layer only, so that a group spans one layer spacing across the thickness however fine the
    spacing along the surface (None: from every particle, the two-layer pad's rule). ``others``: if
    given, each group holds exactly this many nearest others after its partners, whatever its
    partner count (``group_size`` is then unused and the groups' sizes vary: _layered).

    The nearest neighbours come from a uniform grid (_nearest_in_grid): time and memory grow with
    the particle count, not its square (an all-pairs distance table needed 574 GiB at 160,000
    particles). Returns CSR (offsets, members, rest offsets from each group's rest centre of mass).
    """
    rest_x = np.ascontiguousarray(rest_x, dtype=np.float64)
    n = rest_x.shape[0]
    if n < 2:
        raise ValueError(f"a tissue body needs at least 2 particles, got {n}")
    partner = np.asarray(partner, dtype=np.int32)
    if partner.ndim == 1:
        partner = partner[:, None]
    if partner.shape[0] != n or partner.ndim != 2:
        raise ValueError(f"partner must be (N,) or (N, P) with N = {n}, got shape {partner.shape}")
    partner = np.ascontiguousarray(partner)
    size = min(group_size, n) if others is None else min(1 + partner.shape[1] + others, n)
    cap = size if others is None else others
    members = np.full((n, size), -1, dtype=np.int32)
    members[:, 0] = np.arange(n, dtype=np.int32)
    layer = np.zeros(n, dtype=np.int32) if layer is None else np.ascontiguousarray(layer, dtype=np.int32)
    if layer.shape != (n,):
        raise ValueError(f"layer must be (N,) with N = {n}, got shape {layer.shape}")
    cell, order, starts, dims, lo = _cell_grid(rest_x, size)
    _nearest_in_grid(rest_x, partner, layer, cell, order, starts, dims, lo, members, cap)
    # CSR over the filled slots (every slot unless ``others`` leaves some: groups of varying size)
    filled = members >= 0
    offsets = np.concatenate([[0], np.cumsum(filled.sum(axis=1))]).astype(np.int32)
    safe = np.where(filled, members, 0)
    m = np.where(filled, mass[safe], 0.0)
    com = (m[:, :, None] * rest_x[safe]).sum(axis=1) / m.sum(axis=1)[:, None]
    rest_offset = (rest_x[safe] - com[:, None, :])[filled]
    return offsets, members[filled].astype(np.int32), np.ascontiguousarray(rest_offset)


def _cell_grid(x: np.ndarray, per_cell: int) -> tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A uniform grid over the points holding about ``per_cell`` of them per occupied cell: (cell
    size, point indices sorted by cell, CSR starts per cell (flat index), cells per axis, lower
    corner). Empty space costs one int per cell; the cell count is capped near the point count."""
    lo = x.min(axis=0)
    extent = np.maximum(x.max(axis=0) - lo, 1e-12)
    n = x.shape[0]
    # Surface tissue fills a 2-D sheet of the box: size cells for the sheet, then cap the count.
    h = max(float(np.sqrt(extent.prod() ** (2.0 / 3.0) * per_cell / n)), float(extent.max()) / 1e4, 1e-9)
    dims = np.maximum(1, np.ceil(extent / h).astype(np.int64))
    while int(dims.prod()) > 8 * n + 64:
        h *= 1.5
        dims = np.maximum(1, np.ceil(extent / h).astype(np.int64))
    ijk = np.minimum(((x - lo) / h).astype(np.int64), dims - 1)
    flat = (ijk[:, 0] * dims[1] + ijk[:, 1]) * dims[2] + ijk[:, 2]
    order = np.argsort(flat, kind="stable").astype(np.int64)
    starts = np.searchsorted(flat[order], np.arange(int(dims.prod()) + 1)).astype(np.int64)
    return h, order, starts, dims, lo


@nb.njit(cache=True)
def _is_partner(partner, i, j):
    for t in range(partner.shape[1]):
        if partner[i, t] == j:
            return True
    return False


@nb.njit(cache=True)
def _nearest_in_grid(x, partner, layer, cell, order, starts, dims, lo, members, cap):
    """members[i, 1:] = the partners of i (partner[i, :], -1 skipped, in order), then the nearest
    other points of i's own layer (``layer``) by distance, ties to the lower index, at most ``cap``
    of them (the slots left stay as they are). Rings of cells
    around i's cell are searched outward until the nearest candidates found are closer than any
    point the next ring could add (ring s holds every point within s cell sizes)."""
    n = x.shape[0]
    size = members.shape[1]
    cand_d = np.empty(n)
    cand_j = np.empty(n, dtype=np.int64)
    for i in range(n):
        k = 1
        for t in range(partner.shape[1]):
            p = partner[i, t]
            if p >= 0 and k < size:
                members[i, k] = p
                k += 1
        need = min(size - k, cap)
        if need <= 0:
            continue
        ci = np.empty(3, dtype=np.int64)
        for a in range(3):
            ci[a] = min(int((x[i, a] - lo[a]) / cell), dims[a] - 1)
        count = 0
        ring = 0
        while True:
            # the cells at Chebyshev distance exactly `ring` from i's cell
            for gx in range(max(ci[0] - ring, 0), min(ci[0] + ring, dims[0] - 1) + 1):
                for gy in range(max(ci[1] - ring, 0), min(ci[1] + ring, dims[1] - 1) + 1):
                    for gz in range(max(ci[2] - ring, 0), min(ci[2] + ring, dims[2] - 1) + 1):
                        if max(abs(gx - ci[0]), abs(gy - ci[1]), abs(gz - ci[2])) != ring:
                            continue
                        c = (gx * dims[1] + gy) * dims[2] + gz
                        for t in range(starts[c], starts[c + 1]):
                            j = order[t]
                            if j == i or layer[j] != layer[i] or _is_partner(partner, i, j):
                                continue
                            d = (x[j, 0] - x[i, 0]) ** 2 + (x[j, 1] - x[i, 1]) ** 2 + (x[j, 2] - x[i, 2]) ** 2
                            cand_d[count] = d
                            cand_j[count] = j
                            count += 1
            covered = ring * cell
            done = ring >= max(dims[0], max(dims[1], dims[2]))
            if count >= need:
                # the need-th smallest distance so far: final once the searched rings cover it
                sel = np.argsort(cand_d[:count])
                if cand_d[sel[need - 1]] <= covered * covered or done:
                    break
            elif done:
                break
            ring += 1
        # the `need` nearest, ties to the lower index (as a stable sort of all distances would)
        best_d = cand_d[:count].copy()
        best_j = cand_j[:count].copy()
        for _ in range(min(need, count)):
            m = 0
            for t in range(1, count):
                if best_d[t] < best_d[m] or (best_d[t] == best_d[m] and best_j[t] < best_j[m]):
                    m = t
            members[i, k] = best_j[m]
            k += 1
            best_d[m] = np.inf
            best_j[m] = n


def _single_body_model(
    rest_x: np.ndarray,
    rest_q: np.ndarray,
    radii: np.ndarray,
    mass: np.ndarray,
    partner: np.ndarray,
    attached: np.ndarray,
    tissue: TissueConfig,
    *,
    group_partner: np.ndarray | None = None,
    layer: np.ndarray | None = None,
    group_volume: np.ndarray | None = None,
    others: int | None = None,
) -> TissueModel:
    """The model of one body; ``partner`` is the model's particle_partner, ``group_partner`` and
    ``layer`` (default: ``partner``, none) what build_groups puts in each group, ``group_volume``
    (default: from the members' masses) each group's volume for the continuum energy
    (continuum_groups), ``others`` build_groups' (None: groups of tissue.group_size)."""
    offsets, members, rest_offset = build_groups(rest_x, mass, partner if group_partner is None else group_partner,
                                                 tissue.group_size, layer=layer, others=others)  # fmt: skip
    n = rest_x.shape[0]
    kappa = group_kappa(offsets, members, rest_offset, mass, tissue.shear_modulus, tissue.mass_density)
    cont = None
    if tissue.group_energy == "continuum":
        cont, kappa = continuum_groups(offsets, members, rest_offset, mass, tissue.shear_modulus, tissue.mass_density,
                                       tissue.hourglass_stiffness, group_volume)  # fmt: skip
    return TissueModel(
        particle_rest_x=np.ascontiguousarray(rest_x, dtype=np.float64),
        particle_rest_q=np.ascontiguousarray(rest_q, dtype=np.float64),
        particle_radii=np.ascontiguousarray(radii, dtype=np.float64),
        particle_mass=np.ascontiguousarray(mass, dtype=np.float64),
        particle_inv_mass=1.0 / np.ascontiguousarray(mass, dtype=np.float64),
        particle_body=np.zeros(n, dtype=np.int32),
        particle_partner=partner.astype(np.int32),
        particle_attached=attached.astype(np.bool_),
        group_offsets=offsets,
        group_members=members,
        group_rest_offset=rest_offset,
        body_particle_offsets=np.array([0, n], dtype=np.int32),
        body_core_shape=np.array([-1], dtype=np.int32),
        body_friction=np.array([[tissue.friction_static, kinetic_friction(tissue)]]),
        group_kappa=kappa,
        body_max_deviation=np.array([tissue.max_deviation]),
        body_contact_cone=np.array([tissue.contact_cone]),
        body_contact_law=np.array([tissue.friction_law == "contact"]),
        group_continuum=cont,
    )


def group_kappa(offsets: np.ndarray, members: np.ndarray, rest_offset: np.ndarray, mass: np.ndarray, modulus: float,
                density: float) -> np.ndarray:  # fmt: skip
    """(N,) each implicit group's stiffness per unit mass kappa = G / (rho l^2) [1/s^2], l its mass-
    weighted radius of gyration at rest, l^2 = sum m_j |x_bar_j - c_bar|^2 / sum m_j.

    Why: shape matching is the gradient of E = sum_j k_j |x_j - g_j|^2 / 2 (the fit R, c minimises
    it), and a group strained by e moves its members by about e l from their goals; with
    k_j = G V_j / l^2 (V_j = m_j / rho the member's volume) its energy is G e^2 sum V_j, a
    material's shear energy. So k_j / m_j = G / (rho l^2) is the same for every member: the
    projection conserves momentum, and kappa is the squared angular frequency of a shear wave
    across the group, sqrt(G / rho) / l. The constant of order one this leaves out is measured,
    not assumed (the package's documentation, Results: the v3 physics, gives the pad's compression
    and shear under load)."""
    n = offsets.shape[0] - 1
    out = np.empty(n)
    for i in range(n):
        e = slice(int(offsets[i]), int(offsets[i + 1]))
        m = mass[members[e]]
        l2 = float((m * (rest_offset[e] ** 2).sum(axis=1)).sum() / m.sum())
        out[i] = modulus / (density * l2)
    return out


PINV_RTOL = 1e-6
"""Eigenvalues of a group's rest second moment A_qq below this fraction of its largest are taken as
zero (continuum_groups: a planar or collinear group's A_qq^+ is its pseudo-inverse)."""


def continuum_groups(offsets: np.ndarray, members: np.ndarray, rest_offset: np.ndarray, mass: np.ndarray,
                     modulus: float, density: float, hourglass: float = 0.0,
                     volume: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The continuum group energy's rest data (TissueConfig.group_energy "continuum";
    compliant.continuum_groups): ((N, CONTINUUM_COLUMNS) [A_qq^+ (xx, xy, xz, yy, yz, zz), 2 G V,
    beta, A_qq (xx, xy, xz, yy, yz, zz)], (N,) kappa).

    E_g = G V_g ||F - R||_F^2 with F = A_pq A_qq^-1, A_pq = sum_j m_j (x_j - c) q_j^T and
    A_qq = sum_j m_j q_j q_j^T (q_j the rest offsets; the least-squares deformation gradient of
    the group, Mueller et al. 2005). For a small strain F - R is the strain eps, so E_g is
    V_g mu eps:eps, linear elasticity with mu = G and lambda = 0 (nu = 0), whatever the group's
    shape. V_g = sum_j V_j / n_j, V_j = m_j / rho a member's volume and n_j the groups it is in:
    every particle's volume counted once over the groups; or ``volume`` (N,) [m^3], each group's
    own, given (a layered pad's: _layered).

    kappa, the largest stiffness per unit mass of the group's Hessian (the world's substep rule,
    compliant.substeps_for): with R held, d^2 E / dx_j dx_k = 2 G V (b_j . b_k) I, b_j = A_qq^-1 m_j
    q_j, and M^-1/2 H M^-1/2 has the eigenvalues of 2 G V sum_j b_j b_j^T / m_j (3 x 3).

    ``hourglass`` (TissueConfig.hourglass_stiffness, h): the energy above sees only the affine part
    of a group's motion, so a pattern that the groups' overlapping fits average away (a member
    ahead of its fit, its neighbours behind: a checkerboard across the surface) costs little, and a
    layered pad's free surface goes ragged under shear. The term E_h = (beta / 2) sum_j m_j ||x_j - c - F q_j||^2
    penalises each member's miss from the group's affine fit (hourglass control, as for
    under-integrated finite elements: Flanagan & Belytschko 1981), beta = h G V / tr(A_qq), the
    strain energy h G V ||r||^2 / l^2 of a miss r in a group of radius of gyration l. It is zero for
    every affine motion, so it leaves a smooth field's energy alone as the groups shrink (the
    miss of a smooth field falls as l^2). Its Hessian per unit mass is at most beta: kappa + beta."""
    n = offsets.shape[0] - 1
    mem = members.astype(np.int64)
    share = 1.0 / np.bincount(mem, minlength=mass.shape[0]).astype(np.float64)  # 1 / n_j
    vol = mass / density
    cont = np.zeros((n, CONTINUUM_COLUMNS))
    kappa = np.empty(n)
    for i in range(n):
        e = slice(int(offsets[i]), int(offsets[i + 1]))
        j = mem[e]
        m = mass[j]
        q = rest_offset[e]
        aqq = (m[:, None, None] * q[:, :, None] * q[:, None, :]).sum(axis=0)
        w, v = np.linalg.eigh(aqq)
        inv = np.where(w > PINV_RTOL * w.max(), 1.0 / np.where(w > 0.0, w, 1.0), 0.0)
        ainv = (v * inv) @ v.T
        k2 = 2.0 * modulus * (float((vol[j] * share[j]).sum()) if volume is None else float(volume[i]))
        b = (m[:, None] * q) @ ainv
        kappa[i] = k2 * float(np.linalg.eigvalsh((b[:, :, None] * b[:, None, :] / m[:, None, None]).sum(axis=0)).max())
        beta = hourglass * 0.5 * k2 / float(np.trace(aqq))
        kappa[i] += beta
        cont[i] = (ainv[0, 0], ainv[0, 1], ainv[0, 2], ainv[1, 1], ainv[1, 2], ainv[2, 2], k2, beta,
                   aqq[0, 0], aqq[0, 1], aqq[0, 2], aqq[1, 1], aqq[1, 2], aqq[2, 2])  # fmt: skip
    return cont, kappa


BYTES_PER_PARTICLE = 3200
"""What one particle costs in memory, model, state and solver scratch together [bytes], group
members excluded (measured: about 2.4 kB at the defaults; rounded up)."""
BYTES_PER_GROUP_MEMBER = 100
"""Per member of a particle's group: its index, rest offset and packed rest data [bytes]."""


def memory_estimate(particle_count: int, group_size: int) -> int:
    """Bytes a tissue of ``particle_count`` particles in groups of ``group_size`` needs to build
    and step (linear in the particle count)."""
    return int(particle_count) * (BYTES_PER_PARTICLE + int(group_size) * BYTES_PER_GROUP_MEMBER)


def _available_bytes() -> int | None:
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):  # not POSIX: no check
        return None


def check_fits(particle_count: int, group_size: int, *, what: str) -> None:
    """Raise ValueError before building if the tissue cannot fit in the memory free now."""
    need = memory_estimate(particle_count, group_size)
    free = _available_bytes()
    if free is not None and need > free:
        raise ValueError(
            f"{what}: {particle_count:,} particles would need about {need / 2**30:.1f} GiB, but only "
            f"{free / 2**30:.1f} GiB of memory is free; lower TissueConfig.particle_density"
        )


def build_combined_body(
    shape: CoreShape,
    tissue: TissueConfig,
    *,
    shape_offset: np.ndarray | None = None,
    extrude_direction: ExtrudeDirection = "normal",
    faces=None,
) -> TissueModel:
    """Tissue for one combined body (thesis 5.2.1), in the core's centre-of-mass frame.

    Attached particles are spread over the core surface at ``tissue.particle_density`` per m^2; each gets
    an outer partner ``tissue.extrude`` further out. The thesis pushes outer particles along the
    direction from the core's centre of mass (``extrude_direction="radial"``). For elongated
    cores that sends the tissue of a long face sideways (on an 8 x 20 x 30 mm finger the outer
    particle at a face corner moves 75 % along the face, not away from it), so the default is the
    surface normal, which equals the radial direction on a sphere.
    ``shape_offset`` is the shape centre's position in the centre-of-mass frame (pybullet's
    collision-shape frame); the shape's axes must be those of that frame. ``faces`` (box cores:
    names from BOX_FACES) covers only those faces: tissue where contact can happen, the rest of
    the core bare (it still meets the world through pybullet's own contacts).

    With ``tissue.layers`` = L > 1 each column has L + 1 particles, at depths k extrude / L along
    the same direction, stored layer by layer (k = 0, the attached ones, first; k = L, the outer
    contact surface, last); see _layered for their masses, radii and groups. particle_partner
    pairs each attached particle with its column's outer one (the surface and its core spot, as
    with one layer) and is -1 for the inner layers.
    """
    if extrude_direction not in ("normal", "radial"):
        raise ValueError(f"extrude_direction must be 'normal' or 'radial', got {extrude_direction!r}")
    offset = np.zeros(3) if shape_offset is None else np.asarray(shape_offset, dtype=np.float64)
    layers = tissue.layers
    check_fits((layers + 1) * int(math.ceil(shape.area * tissue.particle_density)),
               tissue.group_size + (3 if layers > 1 else 0),
               what="combined body")  # fmt: skip
    pts, nrm, area = sample_surface(shape, tissue.spacing, faces=faces, min_rows=tissue.min_rows)
    pts = pts + offset
    if extrude_direction == "radial":
        d = pts / np.maximum(np.linalg.norm(pts, axis=1, keepdims=True), 1e-12)
    else:
        d = nrm
    if layers > 1:
        return _layered(pts, d, area, tissue)
    k = pts.shape[0]
    outer = pts + tissue.extrude * d
    rest_x = np.concatenate([pts, outer])
    # Each attached/outer pair stands for a prism of tissue (area x extrude); half the mass each.
    m_pair = tissue.mass_density * area * tissue.extrude
    mass = np.concatenate([0.5 * m_pair, 0.5 * m_pair])
    tangential = tissue.radius_scale * np.sqrt(area)
    radii = np.stack([tangential, tangential, np.full(k, tissue.normal_radius)], axis=1)
    radii = np.concatenate([radii, radii])
    rest_q = np.concatenate([quat_z_to(d), quat_z_to(d)])
    partner = np.concatenate([np.arange(k, 2 * k), np.arange(k)])
    attached = np.concatenate([np.ones(k, bool), np.zeros(k, bool)])
    return _single_body_model(rest_x, rest_q, radii, mass, partner, attached, tissue)


INNER_NORMAL_RADIUS = 0.25
"""An inner layer's ellipsoid radius along the surface normal, as a fraction of the layer spacing
extrude / layers [-] (capped at TissueConfig.normal_radius): see _layered."""


def _layered(pts: np.ndarray, d: np.ndarray, area: np.ndarray, tissue: TissueConfig) -> TissueModel:
    """build_combined_body with L = tissue.layers > 1 particle layers through the thickness.

    - **Positions**: column c's particle of layer k at pts[c] + (k extrude / L) d[c], k = 0 .. L,
      stored at index k K + c (K columns).
    - **Masses and volumes**: the column's prism, area x extrude x mass_density, is shared equally
      by its L + 1 particles; each group's volume (the continuum energy's V_g) is its centre's share
      of the prism by the trapezoid rule, half a slice (area x extrude / L) at the two end layers
      and a whole slice inside. Why not the trapezoid's masses too: a group's fit weighs its
      members by mass (the least-squares F, Mueller et al. 2005), and a uniform stress must be in
      balance at every inner particle (the patch test; for particle methods, the integration
      constraint: Chen, Wu, Yoon & You 2001). Per column, the groups' shares through the
      thickness, sum_g V_g b_gj . d (b_gj = A_qq^-1 m_j q_j, d the normal), must be -area at the
      core, 0 at each inner particle and +area at the surface. With half masses at the end layers
      the group of a particle next to one leans toward its far side, the shares are about
      -0.92 / -0.16 / 0 / +0.16 / +0.92 of the area with four layers, and a uniformly sheared pad
      shears in an S instead (its layers travel 0 / 0.29 / 0.50 / 0.71 / 1 of the surface's
      travel). With equal masses every group's fit through the thickness is symmetric, and the
      trapezoid's volumes make the shares -1 / 0 / ... / 0 / +1. The column's mass and its centre
      of mass are the trapezoid's; the mass's spread through the thickness is not (a lumped mass,
      converging as L grows).
    - **Radii**: the attached and outer layers' as with one layer. Contacts are collected for every
      particle that comes within its support radius of a rigid shape (contacts.collect_contacts),
      so an inner particle with the surface's normal radius (3 mm, as much as the layer spacing or
      more) would meet the cylinder as a second surface, 8 / L mm under the first: the
      confound of the hand-built layered pads (the documentation's spatial-convergence page). An inner
      particle's radius along the normal is INNER_NORMAL_RADIUS of the layer spacing (0.5 mm at
      L = 4), so it lies inside the slice it stands for and is reached only where the cylinder
      has pushed through the layers above it. Along the surface it keeps the surface's radius
      (radius_scale x spacing), which closes the gaps between columns should the surface be
      pierced.
    - **Groups**: particle i, the particles directly below and above it in its column (its
      partners for build_groups), then its group_size nearest others of its own layer (the default
      8: on the sampled grid the two whole rings around it, four along the grid's axes and four
      diagonal). A group so spans one layer spacing across the thickness (two for an inner layer)
      and about one particle spacing along the surface, at every density: with neighbours taken
      from every layer the groups of a fine pad would be columns again, and the continuum energy's
      F an average across the thickness (the two-layer pad's limit). Whole rings, so that a group
      inside the face is symmetric along it, as the masses make it across the thickness: filled to
      a fixed size instead (8 members in all, so 5 or 6 of the layer's 8 nearest, ties to the
      lower index), the groups leaned one way, a uniform stress was out of balance along the face
      (the shares of the columns from the face's side edge 1.46 / -0.74 / +0.24 / 0 / -0.24 of a
      column's side area with four layers at 256,000 per m^2, against 1 / 0 / 0 / 0 / 0) and the
      pad came out 4.5 % too compliant under a whole-face shear however fine.
    """
    layers = tissue.layers
    k = pts.shape[0]
    h = tissue.extrude / layers
    depth = np.arange(layers + 1) * h
    rest_x = (pts[None, :, :] + depth[:, None, None] * d[None, :, :]).reshape(-1, 3)
    # Equal masses through the thickness, the trapezoid's volumes for the groups (docstring).
    mass = np.tile(tissue.mass_density * area * tissue.extrude / (layers + 1), layers + 1)
    weight = np.ones(layers + 1)
    weight[0] = weight[-1] = 0.5
    group_volume = (weight[:, None] * (area * h)[None, :]).ravel()
    tangential = tissue.radius_scale * np.sqrt(area)
    normal = np.full(layers + 1, min(tissue.normal_radius, INNER_NORMAL_RADIUS * h))
    normal[0] = normal[-1] = tissue.normal_radius
    radii = np.stack([np.tile(tangential, layers + 1), np.tile(tangential, layers + 1), np.repeat(normal, k)], axis=1)
    rest_q = np.tile(quat_z_to(d), (layers + 1, 1))
    col = np.arange(k)
    layer = np.repeat(np.arange(layers + 1), k)
    partner = np.full((layers + 1) * k, -1)
    partner[col] = layers * k + col  # attached <-> outer: the surface particle and its core spot
    partner[layers * k + col] = col
    # build_groups' partners: the particle above (outward first, as the attached one's outer
    # partner with one layer), then the one below; -1 where the column ends.
    idx = np.arange((layers + 1) * k)
    above = np.where(layer < layers, idx + k, -1)
    below = np.where(layer > 0, idx - k, -1)
    group_partner = np.stack([above, below], axis=1)
    attached = layer == 0
    return _single_body_model(rest_x, rest_q, radii, mass, partner, attached, tissue, group_partner=group_partner,
                              layer=layer, group_volume=group_volume, others=tissue.group_size)  # fmt: skip


def surface_particles(model: TissueModel) -> np.ndarray:
    """(N,) bool: the free particles that are the pad's contact surface, each paired with its core
    spot (particle_partner >= 0 and not attached): the outer particles of build_combined_body at
    any TissueConfig.layers; none of a free block."""
    return ~model.particle_attached & (model.particle_partner >= 0)


def build_free_block(
    half_extents: tuple[float, float, float],
    tissue: TissueConfig,
    *,
    spacing: float | None = None,
) -> TissueModel:
    """A free block of tissue (no core): a lattice of spherical particles filling the box, centred
    at the origin. Used for the solver's own tests (momentum, rest, recovery, friction ramp)."""
    h = np.asarray(half_extents, dtype=np.float64)
    if h.shape != (3,) or (h <= 0).any():
        raise ValueError(f"half_extents must be 3 positive lengths, got {half_extents!r}")
    s = tissue.spacing if spacing is None else float(spacing)
    if not s > 0:
        raise ValueError(f"spacing must be > 0, got {spacing!r}")
    counts = [_count(2 * hh, s) for hh in h]
    check_fits(int(np.prod(counts)), tissue.group_size, what="free block")
    axes = [((np.arange(c) + 0.5) / c * 2 - 1) * hh for hh, c in zip(h, counts, strict=True)]
    g = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    n = g.shape[0]
    cell = float(np.prod(2 * h)) / n
    mass = np.full(n, tissue.mass_density * cell)
    radius = 0.5 * cell ** (1.0 / 3.0)
    radii = np.full((n, 3), radius)
    rest_q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    return _single_body_model(g, rest_q, radii, mass, np.full(n, -1), np.zeros(n, bool), tissue)
