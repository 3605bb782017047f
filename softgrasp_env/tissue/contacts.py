"""Contacts of the tissue: particle against rigid shape (two-way), particle against its own core
(inner), particle against particle of another body.

Each ellipsoid particle is treated as a sphere of its support radius along the contact normal
(Mueller & Chentanez 2011 sec. 5). Candidates are collected once per step against the predicted
rigid poses; every Gauss-Seidel iteration then projects them, the correction split by generalised
inverse masses so a rigid body receives the opposite one (Mueller et al. 2020 sec. 3.3). The
multipliers accumulated here (lambda, a positional impulse [kg m]) bound the friction
(friction.py).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from .collision import (
    SHAPE_BOX,
    SHAPE_CAPSULE,
    SHAPE_CONE,
    SHAPE_CYLINDER,
    SHAPE_ELLIPTIC,
    SHAPE_HULL,
    SHAPE_PLANE,
    SHAPE_SPHERE,
    shape_distance_of,
    support_radius,
)
from .jit import KERNEL
from .rigid import generalized_inv_mass, rigid_apply, shape_world_pose
from .rotation import qconj, qrotate

# Contacts: one row per (particle, shape) candidate; `inner` rows are a particle against its own
# core (thesis 5.1.2 inner collisions: centre must stay outside, no friction).
_NO_RIGID = -1


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _shape_query(s, p, shape_kind, shape_params, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q, more_kinds):
    """Signed distance of world point p from shape s and the world outward normal (``more_kinds``:
    collision.shape_distance_of)."""
    sx, sq = shape_world_pose(s, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q)
    d = (p[0] - sx[0], p[1] - sx[1], p[2] - sx[2])
    pl = qrotate(qconj(sq), d)
    dist, nx, ny, nz = shape_distance_of(shape_kind[s], shape_params, s, pl, more_kinds)
    n = qrotate(sq, (nx, ny, nz))
    return dist, n


# Slack [m] added to bounding radii so that rounding can never reject a true candidate.
_BOUND_SLACK = 1e-9


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _bounding_radius(kind, p0, p1, p2, more_kinds):
    """Radius of a sphere about the shape origin that holds the whole shape (inf for the plane),
    from the first three columns of its params row. The kinds after the capsule only where
    ``more_kinds`` is not None (collision.shape_distance_of: for None, numba drops the branch and
    the code is the one the first five kinds always had)."""
    if more_kinds is not None:
        if kind > SHAPE_CAPSULE:
            return _more_bounding_radius(kind, p0, p1, p2)
    if kind == SHAPE_PLANE:
        return np.inf
    if kind == SHAPE_SPHERE:
        return p0
    if kind == SHAPE_BOX:
        return math.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
    if kind == SHAPE_CYLINDER:
        return math.sqrt(p0 * p0 + p1 * p1)
    return p0 + p1  # capsule


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _more_bounding_radius(kind, p0, p1, p2):
    """_bounding_radius of the kinds after the capsule; inf (never culled) for a code that is no
    shape."""
    if kind == SHAPE_CONE or kind == SHAPE_ELLIPTIC:
        # cone (r_bottom, r_top, hh): its wider rim; elliptic (a, b, hh): the rim at its major axis
        r = max(p0, p1)
        return math.sqrt(r * r + p2 * p2)
    if kind == SHAPE_HULL:
        return p1  # its row keeps the farthest corner's distance in column 1
    return np.inf


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _shape_poses(shape_kind, shape_params, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q, pose, more_kinds):
    """pose[s] = world position (0:3), orientation (3:7) and bounding radius (7) of every shape, once
    per pass over all particles instead of once per particle (same expressions as _shape_query)."""
    for s in range(shape_kind.shape[0]):
        sx, sq = shape_world_pose(s, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q)
        for a in range(3):
            pose[s, a] = sx[a]
        for a in range(4):
            pose[s, 3 + a] = sq[a]
        pose[s, 7] = _bounding_radius(shape_kind[s], shape_params[s, 0], shape_params[s, 1], shape_params[s, 2],
                                      more_kinds)  # fmt: skip
        pose[s, 7] += _BOUND_SLACK


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _far_from_shape(s, p, reach, pose):
    """True if point p is certainly farther than ``reach`` from shape s: its signed distance is at
    least |p - origin| - bounding radius (the shape lies inside its bounding sphere)."""
    dx = p[0] - pose[s, 0]
    dy = p[1] - pose[s, 1]
    dz = p[2] - pose[s, 2]
    lim = pose[s, 7] + reach
    return dx * dx + dy * dy + dz * dz > lim * lim


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _shape_query_at(s, p, shape_kind, shape_params, pose, more_kinds):
    """_shape_query with the shape's world pose taken from ``pose`` (see _shape_poses)."""
    sx = (pose[s, 0], pose[s, 1], pose[s, 2])
    sq = (pose[s, 3], pose[s, 4], pose[s, 5], pose[s, 6])
    d = (p[0] - sx[0], p[1] - sx[1], p[2] - sx[2])
    pl = qrotate(qconj(sq), d)
    dist, nx, ny, nz = shape_distance_of(shape_kind[s], shape_params, s, pl, more_kinds)
    n = qrotate(sq, (nx, ny, nz))
    return dist, n


@nb.njit(**KERNEL)
def collect_contacts(
    xp, x0, radii, p_body, attached, body_core_shape, shape_kind, shape_params, shape_rigid, shape_local_x,
    shape_local_q, rig_x, rig_q, margin, c_particle, c_shape, c_inner, pose, more_kinds,
):  # fmt: skip
    """Candidate (particle, shape) contacts for this step: within the particle's largest radius plus
    how far it moves plus a margin. A particle meets its own core only as an inner contact (outer
    particles; attached ones are tied to the core anyway). Returns the count (or the number
    needed, if larger than the buffers). Shapes are posed once, and a particle far outside a
    shape's bounding sphere skips the exact query (the candidates are the same). ``more_kinds``:
    collision.shape_distance_of."""
    n = xp.shape[0]
    ns = shape_kind.shape[0]
    cap = c_particle.shape[0]
    count = 0
    _shape_poses(shape_kind, shape_params, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q, pose, more_kinds)
    for i in range(n):
        rmax = max(radii[i, 0], max(radii[i, 1], radii[i, 2]))
        mv = math.sqrt((xp[i, 0] - x0[i, 0]) ** 2 + (xp[i, 1] - x0[i, 1]) ** 2 + (xp[i, 2] - x0[i, 2]) ** 2)
        own = body_core_shape[p_body[i]]
        p = (xp[i, 0], xp[i, 1], xp[i, 2])
        for s in range(ns):
            inner = s == own
            if inner and attached[i]:
                continue
            reach = mv + margin if inner else rmax + mv + margin
            if _far_from_shape(s, p, reach, pose):
                continue
            dist, _ = _shape_query_at(s, p, shape_kind, shape_params, pose, more_kinds)
            if dist < reach:
                if count < cap:
                    c_particle[count] = i
                    c_shape[count] = s
                    c_inner[count] = inner
                count += 1
    return count


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _radius_and_move(xp, x0, radii, i):
    """Particle i's largest radius and how far it moves this step [m]."""
    rmax = max(radii[i, 0], max(radii[i, 1], radii[i, 2]))
    return rmax, math.sqrt((xp[i, 0] - x0[i, 0]) ** 2 + (xp[i, 1] - x0[i, 1]) ** 2 + (xp[i, 2] - x0[i, 2]) ** 2)


# Most grid cells the pair search bins one body's particles into; beyond it the cells grow (a
# bound on memory when the overlap box is large and the particles small).
_MAX_CELLS_PER_PARTICLE = 4


def pair_scratch_sizes(particles: int, bodies: int) -> tuple[int, int]:
    """(int32 entries, float64 entries) of the scratch collect_pairs needs for ``particles``
    particles in ``bodies`` bodies: per overlap, four lists of at most one entry per particle and
    a cell table of at most _MAX_CELLS_PER_PARTICLE + 27 cells per particle, twice; per body its
    box and reach."""
    return (4 + 2 * _MAX_CELLS_PER_PARTICLE) * particles + 2 * 28, 7 * bodies


@nb.njit(**KERNEL)
def collect_pairs(xp, x0, radii, body_off, margin, pair_i, pair_j, grid, boxes):
    """Candidate particle pairs between different tissue bodies (the two fingers can touch): i of
    the lower body and j of the higher within their reaches plus the margin. Only the particles in
    the overlap of the bodies' bounding boxes (grown by the reaches) can pair; the higher body's are
    binned on a uniform grid of cells at least one pair's reach wide, so each particle of the lower
    body tests only the 27 cells about it: cost linear in the particles and the pairs found, where
    testing every pair in the overlap grew as its square (the fingers closed face to face). Rows
    are ordered by i, then j (the order the Gauss-Seidel pass projects them in, as the exhaustive
    search gave it). ``grid`` (int32) and ``boxes`` (float64) are scratch of the sizes
    pair_scratch_sizes gives: nothing is allocated per call. Returns the count (or the number
    needed, if larger than the buffers)."""
    nb_ = body_off.shape[0] - 1
    n = xp.shape[0]
    cap = pair_i.shape[0]
    count = 0
    lo = boxes[0 : 3 * nb_].reshape((nb_, 3))
    hi = boxes[3 * nb_ : 6 * nb_].reshape((nb_, 3))
    reach = boxes[6 * nb_ : 7 * nb_]
    for b in range(nb_):
        reach[b] = 0.0
        for a in range(3):
            lo[b, a] = np.inf
            hi[b, a] = -np.inf
        for i in range(body_off[b], body_off[b + 1]):
            rmax, mv = _radius_and_move(xp, x0, radii, i)
            reach[b] = max(reach[b], rmax + mv)
            for a in range(3):
                lo[b, a] = min(lo[b, a], xp[i, a])
                hi[b, a] = max(hi[b, a], xp[i, a])
    # the lists, each at most one entry per particle, then the cell table's two columns
    inside = grid[0:n]
    cell_of = grid[n : 2 * n]
    binned = grid[2 * n : 3 * n]
    found = grid[3 * n : 4 * n]
    cells = grid[4 * n :]
    half = cells.shape[0] // 2
    for b1 in range(nb_):
        for b2 in range(b1 + 1, nb_):
            pad = reach[b1] + reach[b2] + margin
            ox0 = max(lo[b1, 0], lo[b2, 0]) - pad
            oy0 = max(lo[b1, 1], lo[b2, 1]) - pad
            oz0 = max(lo[b1, 2], lo[b2, 2]) - pad
            ox1 = min(hi[b1, 0], hi[b2, 0]) + pad
            oy1 = min(hi[b1, 1], hi[b2, 1]) + pad
            oz1 = min(hi[b1, 2], hi[b2, 2]) + pad
            if ox0 > ox1 or oy0 > oy1 or oz0 > oz1:
                continue
            # b2's particles inside the overlap box (any pair has both ends in it: a j outside it is
            # farther than pad from every particle of b1, and pad bounds every pair's reach)
            m = 0
            for j in range(body_off[b2], body_off[b2 + 1]):
                if ox0 <= xp[j, 0] <= ox1 and oy0 <= xp[j, 1] <= oy1 and oz0 <= xp[j, 2] <= oz1:
                    inside[m] = j
                    m += 1
            if m == 0:
                continue
            # cells as wide as the widest pair reach (and a hair more, so rounding cannot put two
            # partners two cells apart), grown until there are few enough of them
            h = pad * (1.0 + 1e-9)
            while True:
                dx = max(1, int((ox1 - ox0) / h) + 1)
                dy = max(1, int((oy1 - oy0) / h) + 1)
                dz = max(1, int((oz1 - oz0) / h) + 1)
                total = dx * dy * dz
                if total <= _MAX_CELLS_PER_PARTICLE * m + 27:
                    break
                h *= 2.0
            # counting sort of the inside particles by cell; stable, so each cell lists its
            # particles in increasing index
            start = cells[0 : total + 1]
            fill = cells[half : half + total]
            start[:] = 0
            for k in range(m):
                j = inside[k]
                cx = min(dx - 1, int((xp[j, 0] - ox0) / h))
                cy = min(dy - 1, int((xp[j, 1] - oy0) / h))
                cz = min(dz - 1, int((xp[j, 2] - oz0) / h))
                c = (cx * dy + cy) * dz + cz
                cell_of[k] = c
                start[c + 1] += 1
            for c in range(total):
                start[c + 1] += start[c]
            for c in range(total):  # a loop, not fill[:] = start[:total]: that copies through a temporary
                fill[c] = start[c]
            for k in range(m):
                binned[fill[cell_of[k]]] = inside[k]
                fill[cell_of[k]] += 1
            for i in range(body_off[b1], body_off[b1 + 1]):
                if not (ox0 <= xp[i, 0] <= ox1 and oy0 <= xp[i, 1] <= oy1 and oz0 <= xp[i, 2] <= oz1):
                    continue
                ri, mi = _radius_and_move(xp, x0, radii, i)
                cx = min(dx - 1, int((xp[i, 0] - ox0) / h))
                cy = min(dy - 1, int((xp[i, 1] - oy0) / h))
                cz = min(dz - 1, int((xp[i, 2] - oz0) / h))
                nf = 0
                for gx in range(max(0, cx - 1), min(dx, cx + 2)):
                    for gy in range(max(0, cy - 1), min(dy, cy + 2)):
                        for gz in range(max(0, cz - 1), min(dz, cz + 2)):
                            c = (gx * dy + gy) * dz + gz
                            for k in range(start[c], start[c + 1]):
                                j = binned[k]
                                d2 = (xp[i, 0] - xp[j, 0]) ** 2 + (xp[i, 1] - xp[j, 1]) ** 2 + (xp[i, 2] - xp[j, 2]) ** 2
                                rj, mj = _radius_and_move(xp, x0, radii, j)
                                lim = ri + mi + rj + mj + margin
                                if d2 < lim * lim:
                                    # insertion into the sorted list of i's partners (a few)
                                    at = nf
                                    while at > 0 and found[at - 1] > j:
                                        found[at] = found[at - 1]
                                        at -= 1
                                    found[at] = j
                                    nf += 1
                for k in range(nf):
                    if count < cap:
                        pair_i[count] = i
                        pair_j[count] = found[k]
                    count += 1
    return count


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def clear_multipliers(count, lam, lam_t):
    """Zero the normal and tangential multipliers of the first ``count`` rows (a new step)."""
    for c in range(count):
        lam[c] = 0.0
        lam_t[c] = 0.0


# The contact and friction kernels below each loop over all their rows: one compiled call per
# Gauss-Seidel iteration. Called once per row instead, as numba-inlined bodies in _step, the same
# arithmetic ran at half the speed (the grasp's 124 contacts: 18 us against 9 us a pass).
@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def contact_reach(c, c_particle, c_shape, c_inner, xp, qp, radii, shape_kind, shape_params, shape_rigid, shape_local_x,
                  shape_local_q, rig_x, rig_q, rig_move, shape_pose, more_kinds):  # fmt: skip
    """Contact c's geometry now: (particle i, rigid slot r, i's position p, its signed distance
    from the shape, the outward normal n, its reach along n (the ellipsoid's support radius; 0 for
    an inner contact, which keeps only the centre outside its own core)). Its penetration is
    reach - distance."""
    # unsigned indices: no negative-index wraparound per access (as in the group solve)
    i = np.uint64(c_particle[c])
    s = np.uint64(c_shape[c])
    p = (xp[i, 0], xp[i, 1], xp[i, 2])
    r = shape_rigid[s]
    if r >= 0 and rig_move[r]:
        dist, n = _shape_query(s, p, shape_kind, shape_params, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q,
                               more_kinds)  # fmt: skip
    else:
        # Static shapes and bodies that do not move inside the solve keep the pose the contacts were
        # collected at (_shape_poses): the same numbers without re-posing the shape per contact.
        dist, n = _shape_query_at(s, p, shape_kind, shape_params, shape_pose, more_kinds)
    if c_inner[c]:
        rn = 0.0
    else:
        rn = support_radius((qp[i, 0], qp[i, 1], qp[i, 2], qp[i, 3]), (radii[i, 0], radii[i, 1], radii[i, 2]), n)
    return i, r, p, dist, n, rn


@nb.njit(**KERNEL)
def project_shape_contacts(
    count, c_particle, c_shape, c_inner, c_lambda, c_normal, c_rn, xp, qp, radii, inv_mass, shape_kind, shape_params,
    shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move,
    imp_lin, imp_ang, dt, shape_pose, more_kinds,
):  # fmt: skip
    """Non-penetration of an ellipsoid particle and a rigid shape (Mueller & Chentanez 2011 sec. 5:
    the ellipsoid is treated as a sphere of its support radius along the contact normal), split by
    generalised inverse masses so the body receives the opposite correction (Mueller et al. 2020
    sec. 3.3). Inner contacts keep only the particle centre outside its own core (radius 0)."""
    for c in range(count):
        i, r, p, dist, n, rn = contact_reach(c, c_particle, c_shape, c_inner, xp, qp, radii, shape_kind, shape_params,
                                             shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q, rig_move,
                                             shape_pose, more_kinds)  # fmt: skip
        pen = rn - dist
        if pen <= 0.0:
            continue
        c_normal[c, 0] = n[0]
        c_normal[c, 1] = n[1]
        c_normal[c, 2] = n[2]
        c_rn[c] = rn  # the particle's reach along n: friction acts at x - rn n, the contact point
        wp = inv_mass[i]
        wb = 0.0
        rx = ry = rz = 0.0
        if r >= 0:
            # lever arm to the shape's surface point under the particle
            rx = p[0] - dist * n[0] - rig_x[r, 0]
            ry = p[1] - dist * n[1] - rig_x[r, 1]
            rz = p[2] - dist * n[2] - rig_x[r, 2]
            if rig_move[r]:
                wb = generalized_inv_mass(r, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rx, ry, rz, n[0], n[1], n[2])
        dl = pen / (wp + wb)
        c_lambda[c] += dl
        xp[i, 0] += wp * dl * n[0]
        xp[i, 1] += wp * dl * n[1]
        xp[i, 2] += wp * dl * n[2]
        if r >= 0:
            rigid_apply(r, rx, ry, rz, -dl * n[0], -dl * n[1], -dl * n[2], rig_move[r], dt, rig_x, rig_q,
                        rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin, imp_ang)  # fmt: skip


@nb.njit(**KERNEL)
def project_pairs(count, pair_i, pair_j, pair_lambda, pair_normal, xp, qp, radii, inv_mass):
    """Two ellipsoids of different bodies, each approximated by its support radius along the line
    of centres (Mueller & Chentanez 2011 sec. 5), separated with inverse-mass weights."""
    for k in range(count):
        i = pair_i[k]
        j = pair_j[k]
        dx = xp[i, 0] - xp[j, 0]
        dy = xp[i, 1] - xp[j, 1]
        dz = xp[i, 2] - xp[j, 2]
        d = math.sqrt(dx * dx + dy * dy + dz * dz)
        if d < 1e-12:
            continue
        n = (dx / d, dy / d, dz / d)
        ri = support_radius((qp[i, 0], qp[i, 1], qp[i, 2], qp[i, 3]), (radii[i, 0], radii[i, 1], radii[i, 2]), n)
        rj = support_radius((qp[j, 0], qp[j, 1], qp[j, 2], qp[j, 3]), (radii[j, 0], radii[j, 1], radii[j, 2]), n)
        pen = ri + rj - d
        if pen <= 0.0:
            continue
        wi = inv_mass[i]
        wj = inv_mass[j]
        dl = pen / (wi + wj)
        pair_lambda[k] += dl
        pair_normal[k, 0] = n[0]
        pair_normal[k, 1] = n[1]
        pair_normal[k, 2] = n[2]
        for a in range(3):
            xp[i, a] += wi * dl * n[a]
            xp[j, a] -= wj * dl * n[a]


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})  # allocates: keeps numba's runtime (jit.py)
def max_penetration(x, q, radii, p_body, attached, body_core_shape, shape_kind, shape_params, shape_rigid,
                    shape_local_x, shape_local_q, rig_x, rig_q, out, more_kinds):  # fmt: skip
    """Deepest overlap of any particle ellipsoid with a rigid shape (out[0]) and deepest intrusion
    of an outer particle's centre into its own core (out[1]) [m]. ``more_kinds``:
    collision.shape_distance_of."""
    out[0] = 0.0
    out[1] = 0.0
    pose = np.empty((shape_kind.shape[0], 8))
    _shape_poses(shape_kind, shape_params, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q, pose, more_kinds)
    for i in range(x.shape[0]):
        p = (x[i, 0], x[i, 1], x[i, 2])
        own = body_core_shape[p_body[i]]
        rmax = max(radii[i, 0], max(radii[i, 1], radii[i, 2]))
        for s in range(shape_kind.shape[0]):
            # Outside the bounding sphere by more than rmax (own core: outside it at all), the
            # overlap (intrusion) is negative and cannot raise the maximum, which starts at 0.
            if s == own:
                if attached[i] or _far_from_shape(s, p, 0.0, pose):
                    continue
                dist, _ = _shape_query_at(s, p, shape_kind, shape_params, pose, more_kinds)
                out[1] = max(out[1], -dist)
                continue
            if _far_from_shape(s, p, rmax, pose):
                continue
            dist, nrm = _shape_query_at(s, p, shape_kind, shape_params, pose, more_kinds)
            rn = support_radius((q[i, 0], q[i, 1], q[i, 2], q[i, 3]), (radii[i, 0], radii[i, 1], radii[i, 2]), nrm)
            out[0] = max(out[0], rn - dist)

