"""Analytic collision shapes and the ellipsoid support radius (numba, float64).

A shape is described in its own frame: plane = the half-space z <= 0; sphere (radius); box (half
extents); cylinder and capsule along z (radius, half height), as in pybullet; cone, a frustum along
z (bottom radius, top radius, half height); elliptic, an elliptic cylinder along z (semi-axis along
x, semi-axis along y, half height); hull, a convex polyhedron given by its face planes.
``shape_distance`` gives the signed distance of a point from the surface (negative inside) and the
outward unit normal at the nearest surface point, so one projection rule serves every shape.

A world's shapes keep their dimensions in one (S, K) table, K >= 3 (``Colliders.shape_params``):
every kind but the hull uses columns 0-2 (the rest zeros); a hull's row is
[plane count, bounding radius, 0, n0x, n0y, n0z, d0, n1x, ...] (``hull_params`` builds it).
``shape_distance_of`` is the one call the kernels make on a shape of the table, whatever its kind.
"""

from __future__ import annotations

import functools
import math

import numba as nb
import numpy as np

SHAPE_PLANE = 0
SHAPE_SPHERE = 1
SHAPE_BOX = 2
SHAPE_CYLINDER = 3
SHAPE_CAPSULE = 4
SHAPE_CONE = 5
SHAPE_ELLIPTIC = 6
SHAPE_HULL = 7
SHAPE_CODES = {"plane": SHAPE_PLANE, "sphere": SHAPE_SPHERE, "box": SHAPE_BOX, "cylinder": SHAPE_CYLINDER,
               "capsule": SHAPE_CAPSULE, "cone": SHAPE_CONE, "elliptic": SHAPE_ELLIPTIC,
               "hull": SHAPE_HULL}  # fmt: skip
HULL_HEADER = 3
"""Columns of a hull's params row before its planes: plane count, bounding radius, 0."""
HULL_PLANE = 4
"""Columns per plane of a hull's params row: unit outward normal (3) and offset."""

jit = nb.njit(cache=True, inline="always")


@jit
def basic_shape_distance(kind, params, p):
    """``shape_distance`` of the first five kinds (plane, sphere, box, cylinder, capsule; any other
    code is read as a capsule). The kernels compile this alone for a world of only these kinds
    (``shape_distance_of``), the code they always ran: the recorded trajectories replay to the bit.
    """
    px, py, pz = p
    if kind == SHAPE_PLANE:
        return pz, 0.0, 0.0, 1.0
    if kind == SHAPE_SPHERE:
        d = math.sqrt(px * px + py * py + pz * pz)
        if d < 1e-12:
            return -params[0], 0.0, 0.0, 1.0
        return d - params[0], px / d, py / d, pz / d
    if kind == SHAPE_BOX:
        hx, hy, hz = params[0], params[1], params[2]
        dx = abs(px) - hx
        dy = abs(py) - hy
        dz = abs(pz) - hz
        if dx > 0.0 or dy > 0.0 or dz > 0.0:
            # Outside: nearest point is the clamp of p onto the box.
            ex = max(dx, 0.0) * (1.0 if px >= 0.0 else -1.0)
            ey = max(dy, 0.0) * (1.0 if py >= 0.0 else -1.0)
            ez = max(dz, 0.0) * (1.0 if pz >= 0.0 else -1.0)
            d = math.sqrt(ex * ex + ey * ey + ez * ez)
            return d, ex / d, ey / d, ez / d
        # Inside: leave through the nearest face.
        if dx >= dy and dx >= dz:
            return dx, (1.0 if px >= 0.0 else -1.0), 0.0, 0.0
        if dy >= dz:
            return dy, 0.0, (1.0 if py >= 0.0 else -1.0), 0.0
        return dz, 0.0, 0.0, (1.0 if pz >= 0.0 else -1.0)
    if kind == SHAPE_CYLINDER:
        r, hh = params[0], params[1]
        rho = math.sqrt(px * px + py * py)
        if rho > 1e-12:
            ux, uy = px / rho, py / rho
        else:
            ux, uy = 1.0, 0.0
        dr = rho - r
        dz = abs(pz) - hh
        sz = 1.0 if pz >= 0.0 else -1.0
        if dr > 0.0 and dz > 0.0:
            d = math.sqrt(dr * dr + dz * dz)
            return d, ux * dr / d, uy * dr / d, sz * dz / d
        if dr > 0.0:
            return dr, ux, uy, 0.0
        if dz > 0.0:
            return dz, 0.0, 0.0, sz
        if dr >= dz:
            return dr, ux, uy, 0.0
        return dz, 0.0, 0.0, sz
    # capsule: distance to the segment on z minus the radius
    r, hh = params[0], params[1]
    cz = min(max(pz, -hh), hh)
    ex, ey, ez = px, py, pz - cz
    d = math.sqrt(ex * ex + ey * ey + ez * ez)
    if d < 1e-12:
        return -r, 1.0, 0.0, 0.0
    return d - r, ex / d, ey / d, ez / d


@jit
def shape_distance(kind, params, p):
    """Signed distance of local point ``p`` (3-tuple) from a shape, and the outward unit normal.

    ``params``: sphere (r, -, -); box (hx, hy, hz); cylinder/capsule (r, half height, -); cone
    (bottom radius, top radius, half height); elliptic (semi-axis x, semi-axis y, half height).
    Returns (distance, nx, ny, nz) in the shape frame. A hull needs its whole row
    (``hull_distance``, or ``shape_distance_of`` for a world's table): here it, and any code that
    is no shape, gives a NaN distance.
    """
    if kind == SHAPE_CONE:
        return _cone_distance(params[0], params[1], params[2], p[0], p[1], p[2])
    if kind == SHAPE_ELLIPTIC:
        dr, ux, uy = _ellipse_distance(params[0], params[1], p[0], p[1])
        return _with_caps(dr, ux, uy, p[2], params[2])
    if kind < SHAPE_PLANE or kind > SHAPE_CAPSULE:
        return math.nan, 0.0, 0.0, 1.0  # the hull (hull_distance) or no shape at all
    return basic_shape_distance(kind, params, p)


# --- cone frustum ---------------------------------------------------------------------------------


@jit
def _segment_2d(qr, qz, ar, az, br, bz):
    """Nearest point of the segment a-b to q in the (rho, z) half-plane: (squared distance, t, cr,
    cz), t in [0, 1] its parameter from a (0 for a segment of no length)."""
    er = br - ar
    ez = bz - az
    l2 = er * er + ez * ez
    t = 0.0
    if l2 > 0.0:
        t = min(max(((qr - ar) * er + (qz - az) * ez) / l2, 0.0), 1.0)
    cr = ar + t * er
    cz = az + t * ez
    dr = qr - cr
    dz = qz - cz
    return dr * dr + dz * dz, t, cr, cz


@jit
def _cone_distance(r1, r2, hh, px, py, pz):
    """Signed distance and outward normal of a cone frustum along z: radius r1 at z = -hh, r2 at
    z = +hh (either may be the larger, one may be 0). A solid of revolution is nearest to a point
    in the point's own half-plane through the axis, so the distance is the 2D one in (rho, z) to
    the three segments its section's boundary is made of (the bottom disc's radius, the slanted
    side, the top disc's radius; the axis is inside), signed by an inside test."""
    rho = math.sqrt(px * px + py * py)
    if rho > 1e-12:
        ux, uy = px / rho, py / rho
    else:
        ux, uy = 1.0, 0.0  # on the axis: any radial direction
    # outward normals of the three segments in (rho, z); the side's is its direction (r2 - r1,
    # 2 hh) turned by -90 degrees
    ls = math.sqrt(4.0 * hh * hh + (r1 - r2) * (r1 - r2))
    sr, sz = 2.0 * hh / ls, (r1 - r2) / ls
    d2, t, cr, cz = _segment_2d(rho, pz, 0.0, -hh, r1, -hh)  # bottom
    fr, fz = 0.0, -1.0
    d2s, ts, crs, czs = _segment_2d(rho, pz, r1, -hh, r2, hh)  # side
    if d2s < d2:
        d2, t, cr, cz, fr, fz = d2s, ts, crs, czs, sr, sz
    d2t, tt, crt, czt = _segment_2d(rho, pz, r2, hh, 0.0, hh)  # top
    if d2t < d2:
        d2, t, cr, cz, fr, fz = d2t, tt, crt, czt, 0.0, 1.0
    d = math.sqrt(d2)
    # inside: |z| <= hh and rho <= r(z) = (r1 (hh - z) + r2 (hh + z)) / (2 hh)
    inside = abs(pz) <= hh and 2.0 * hh * rho <= r1 * (hh - pz) + r2 * (hh + pz)
    # The nearest point inside a segment has the segment's normal (q - c is along it, and the face
    # normal is exact where the difference would lose digits); at a rim or the tip the direction is
    # from the nearest point to q (outside) or back (inside), unless q is on it.
    if (0.0 < t < 1.0) or d <= 1e-12:
        nr, nz = fr, fz
    elif inside:
        nr, nz = (cr - rho) / d, (cz - pz) / d
    else:
        nr, nz = (rho - cr) / d, (pz - cz) / d
    return (-d if inside else d), nr * ux, nr * uy, nz


# --- elliptic cylinder ----------------------------------------------------------------------------

_ELLIPSE_NEWTON = 40
"""Most Newton steps for the ellipse's nearest point. They converge quadratically near the root,
and from far below it (a point next to the evolute's cusp on the major axis, x ~ (a^2 - b^2) / a,
y ~ 0) each step grows u = t + b^2 by about 1.5; the 1e-12 b band about the axis (_ELLIPSE_AXIS)
bounds how far below the root it starts. Measured over points swept to within 1e-16 of the cusp
and 1e-12 b of the axis: at most 28 steps at a:b = 2, 31 at 10, 35 at 100, 38 at 1000, and
about 5 on average (7 at the 99th percentile) over random points at a:b = 1.5 to 3."""
_ELLIPSE_AXIS = 1e-12
"""A point within this fraction of the minor semi-axis of the major axis is taken as on it (its
closed form): the distance is 1-Lipschitz, so that moves it by at most 1e-12 b."""


@jit
def _ellipse_quadrant(a, b, x, y):
    """Nearest point (x0, y0) of the ellipse (x/a)^2 + (y/b)^2 = 1, a > b, to the first-quadrant
    point (x, y), and t with (x, y) = (x0, y0) + t (x0 / a^2, y0 / b^2): t < 0 inside.

    The nearest point is (a^2 x / (t + a^2), b^2 y / (t + b^2)) with t the root of
    f(t) = (a x / (t + a^2))^2 + (b y / (t + b^2))^2 - 1 (Eberly, "Distance from a point to an
    ellipse, an ellipsoid, or a hyperellipsoid", Geometric Tools 2013, sec. 2). For y > 0, f is
    convex and decreasing on t > -b^2, and f >= 0 at t = -b^2 + b y and at -a^2 + a x, f <= 0 at
    -b^2 + sqrt(a^2 x^2 + b^2 y^2): Newton from the larger lower bound climbs to the root without
    overshoot. It runs in u = t + b^2 (the nearest point's y0 = b^2 y / u): near the major axis u
    is tiny, and t + b^2 formed from t would keep none of its digits."""
    a2 = a * a
    b2 = b * b
    e2 = a2 - b2
    ax = a * x
    if y <= _ELLIPSE_AXIS * b:
        # on the major axis: inside the evolute's cusp (a x < a^2 - b^2) the nearest points are off
        # the axis, (a^2 x / e2, +-b sqrt(1 - (x0 / a)^2)) at t = -b^2; else the vertex (a, 0)
        if ax < e2:
            x0 = a2 * x / e2
            w = x0 / a
            return x0, b * math.sqrt(max(1.0 - w * w, 0.0)), -b2
        return a, 0.0, ax - a2
    by = b * y
    u = max(by, ax - e2)
    u_hi = math.sqrt(ax * ax + by * by)
    for _ in range(_ELLIPSE_NEWTON):
        ex = ax / (u + e2)
        ey = by / u
        f = ex * ex + ey * ey - 1.0
        if f <= 0.0:
            break
        fp = 2.0 * (ex * ex / (u + e2) + ey * ey / u)  # -f'
        un = min(u + f / fp, u_hi)
        if not un > u:
            break  # no progress: converged to rounding
        u = un
    return a2 * x / (u + e2), b2 * y / u, u - b2


@jit
def _ellipse_distance(a, b, px, py):
    """Signed 2D distance of (px, py) from the ellipse of semi-axes a (along x) and b (along y),
    and the outward unit normal (nx, ny) at the nearest point. A circle (a == b) takes the
    cylinder's expressions."""
    if a == b:
        rho = math.sqrt(px * px + py * py)
        if rho > 1e-12:
            return rho - a, px / rho, py / rho
        return -a, 1.0, 0.0
    # the first quadrant (the ellipse's symmetry), the major axis along the first coordinate
    x, y = abs(px), abs(py)
    if a > b:
        x0, y0, t = _ellipse_quadrant(a, b, x, y)
        gx, gy = x0 / (a * a), y0 / (b * b)
    else:
        y0, x0, t = _ellipse_quadrant(b, a, y, x)
        gx, gy = x0 / (a * a), y0 / (b * b)
    # (x0 / a^2, y0 / b^2) is the outward normal at the nearest point, and p - nearest = t times it
    g = math.sqrt(gx * gx + gy * gy)
    nx = gx / g if px >= 0.0 else -gx / g
    ny = gy / g if py >= 0.0 else -gy / g
    return t * g, nx, ny


@jit
def _with_caps(dr, ux, uy, pz, hh):
    """A prism's signed distance from the signed 2D distance dr of its section (outward unit
    normal (ux, uy)) and its caps at z = +-hh, combined as the cylinder's: outside both the
    distance to the rim, sqrt(dr^2 + dz^2), else the larger of the two."""
    dz = abs(pz) - hh
    sz = 1.0 if pz >= 0.0 else -1.0
    if dr > 0.0 and dz > 0.0:
        d = math.sqrt(dr * dr + dz * dz)
        return d, ux * dr / d, uy * dr / d, sz * dz / d
    if dr > 0.0:
        return dr, ux, uy, 0.0
    if dz > 0.0:
        return dz, 0.0, 0.0, sz
    if dr >= dz:
        return dr, ux, uy, 0.0
    return dz, 0.0, 0.0, sz


# --- convex hull ----------------------------------------------------------------------------------


@jit
def hull_distance(row, p):
    """Signed distance of local point ``p`` from a convex polyhedron and its normal, from the
    polyhedron's params ``row`` ([count, bounding radius, 0, n0x, n0y, n0z, d0, ...]; inside
    where n . p <= d for every plane): the largest n . p - d, with that plane's normal.

    Exact inside and on the surface, and outside wherever the nearest surface point lies inside a
    face (p is in the prism over the face). Outside near an edge or a corner the true distance is
    larger (the nearest point is on the edge or the corner, not on a plane): there this is a lower
    bound, and p - d n lies on the face's plane but off the face. It errs on the safe side: a
    particle of support radius r is kept outside the planes pushed out by r, a polyhedron with
    sharp edges where the exact offset surface is rounded, so it stops short of an edge of exterior
    angle phi by up to r (1 / cos(phi / 2) - 1) - a gap, never an overlap (1.2e-3 r at the edges of
    a 64-sided prism, 0.41 r at a box's right-angled edge; at a corner more)."""
    px, py, pz = p
    best = -np.inf
    bx, by, bz = 0.0, 0.0, 1.0
    for k in range(int(row[0])):
        o = HULL_HEADER + HULL_PLANE * k
        s = row[o] * px + row[o + 1] * py + row[o + 2] * pz - row[o + 3]
        if s > best:
            best = s
            bx, by, bz = row[o], row[o + 1], row[o + 2]
    return best, bx, by, bz


@jit
def shape_distance_of(kind, shape_params, s, p, more_kinds):
    """``shape_distance`` of shape ``s`` of a world's (S, K) params table: a hull reads its whole
    row, every other kind its first three columns. The one call every kernel makes on a world's
    shape.

    ``more_kinds`` is None when every shape of the world is one of the first five kinds (the
    switch ``more_kinds_of`` gives), True otherwise. None is a type of its own, so numba compiles
    the kernels once for each and the test on it is settled when they compile: for None they hold
    the code they had before the cone, the elliptic cylinder and the hull (``basic_shape_distance``)
    and the recorded trajectories replay to the bit. With the hull's branch always present they
    did not (the first difference at step 5 of the recorded SoftGraspEasy-v3/random): any code added to what the
    kernels inline can move LLVM's choices of which multiply-adds to fuse (jit.py: fastmath
    "contract")."""
    if more_kinds is None:
        return basic_shape_distance(kind, (shape_params[s, 0], shape_params[s, 1], shape_params[s, 2]), p)
    if kind == SHAPE_HULL:
        return hull_distance(shape_params[s], p)
    return shape_distance(kind, (shape_params[s, 0], shape_params[s, 1], shape_params[s, 2]), p)


def more_kinds_of(shape_kind: np.ndarray) -> bool | None:
    """The kernels' ``more_kinds`` switch for a world's shape codes (``shape_distance_of``): None
    when all are plane, sphere, box, cylinder or capsule, else True."""
    return True if shape_kind.size and int(shape_kind.max()) > SHAPE_CAPSULE else None


@jit
def support_radius(q, radii, n):
    """Extent of an ellipsoid with orientation ``q`` and semi-axes ``radii`` along unit ``n``:
    sqrt(n^T R diag(r^2) R^T n) (Mueller & Chentanez 2011 sec. 5, ellipsoid collision)."""
    x, y, z, w = q
    # R^T n via the conjugate rotation.
    ux, uy, uz, ww = -x, -y, -z, w
    tx = 2.0 * (uy * n[2] - uz * n[1])
    ty = 2.0 * (uz * n[0] - ux * n[2])
    tz = 2.0 * (ux * n[1] - uy * n[0])
    lx = n[0] + ww * tx + (uy * tz - uz * ty)
    ly = n[1] + ww * ty + (uz * tx - ux * tz)
    lz = n[2] + ww * tz + (ux * ty - uy * tx)
    return math.sqrt((radii[0] * lx) ** 2 + (radii[1] * ly) ** 2 + (radii[2] * lz) ** 2)


@nb.njit(cache=True)
def shape_distance_array(kind: int, params: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Array front end for tests: returns [distance, nx, ny, nz]. ``params``: the kind's three, or a
    hull's whole row."""
    if kind == SHAPE_HULL:
        d, nx, ny, nz = hull_distance(params, (p[0], p[1], p[2]))
    else:
        d, nx, ny, nz = shape_distance(kind, (params[0], params[1], params[2]), (p[0], p[1], p[2]))
    out = np.empty(4)
    out[0] = d
    out[1] = nx
    out[2] = ny
    out[3] = nz
    return out


# --- a hull's params row (plain numpy, once per scene) --------------------------------------------

HULL_MIN_PLANES = 4
"""Fewest planes that bound a solid (a tetrahedron)."""
_UNIT_TOL = 1e-9
"""How far a plane normal's length may be from 1."""
_FIT_TOL = 1e-8
"""How far outside its planes a vertex may lie, and how far the polyhedron's corners may reach
past the bounding radius, relative to max(radius, 1 m): meshes merge coplanar faces within 1e-9
of (n, d), which puts their vertices up to ~2e-9 (1 + |v|) off the merged plane."""


def _polyhedron_corners(normals: np.ndarray, offsets: np.ndarray, tol: float) -> np.ndarray:
    """(C, 3) corners of {x : n_k . x <= d_k for all k}: the intersections of three planes that
    lie inside all the others (within ``tol``), by Cramer's rule (x = (d_i n_j x n_k + d_j n_k x n_i
    + d_k n_i x n_j) / n_i . (n_j x n_k)). Every plane triple is tried: a one-off cost, P^3 / 6
    solves and as many P-plane checks (a 66-plane prism: 46,000 triples, milliseconds)."""
    p = normals.shape[0]
    jj, kk = np.triu_indices(p, k=1)
    corners = [np.zeros((0, 3))]
    for a in range(p - 2):
        sel = jj > a
        b, c = jj[sel], kk[sel]
        bc = np.cross(normals[b], normals[c])
        ca = np.cross(normals[c], normals[a])
        ab = np.cross(normals[a], normals[b])
        det = bc @ normals[a]
        ok = np.abs(det) > 1e-12
        x = (offsets[a] * bc + offsets[b, None] * ca + offsets[c, None] * ab)[ok] / det[ok, None]
        inside = (x @ normals.T - offsets[None, :]).max(axis=1, initial=-np.inf) <= tol
        corners.append(x[inside])
    return np.concatenate(corners)


def _check_planes(normals: np.ndarray, offsets: np.ndarray, radius: float | None, what: str) -> float:
    """Validate a hull's planes (unit normals, a bounded solid with volume, inside ``radius`` of
    the origin if given); returns the farthest corner's distance from the origin."""
    p = normals.shape[0]
    if p < HULL_MIN_PLANES:
        raise ValueError(f"{what}: a hull needs at least {HULL_MIN_PLANES} planes to bound a solid, got {p}")
    if not (np.isfinite(normals).all() and np.isfinite(offsets).all()):
        raise ValueError(f"{what}: the planes must be finite")
    length = np.linalg.norm(normals, axis=1)
    bad = np.flatnonzero(np.abs(length - 1.0) > _UNIT_TOL)
    if bad.size:
        raise ValueError(f"{what}: plane normals must be unit vectors; plane {bad[0]} has length {length[bad[0]]!r}")
    # Bounded: no direction u with n_k . u <= 0 for every k. Such directions form a cone; with
    # normals of rank 3 its extreme rays are along n_i x n_j (two active planes), so trying +-
    # every cross product finds one if there is any.
    if np.linalg.matrix_rank(normals, tol=1e-9) < 3:
        raise ValueError(f"{what}: the plane normals lie in a plane; the hull would be unbounded")
    cross = np.cross(normals[:, None, :], normals[None, :, :]).reshape(-1, 3)
    size = np.linalg.norm(cross, axis=1)
    cross = cross[size > 1e-9] / size[size > 1e-9, None]
    reach = cross @ normals.T  # (pairs, planes)
    if (reach.max(axis=1) <= 1e-12).any() or ((-reach).max(axis=1) <= 1e-12).any():
        raise ValueError(f"{what}: the planes do not close around a solid (it is unbounded in some direction)")
    scale = max(float(np.abs(offsets).max()), 1.0 if radius is None else max(radius, 1.0))
    corners = _polyhedron_corners(normals, offsets, _FIT_TOL * scale)
    if corners.shape[0] < 4 or np.linalg.matrix_rank(corners - corners.mean(axis=0), tol=1e-12) < 3:
        raise ValueError(f"{what}: the planes enclose no solid (their inside is empty or flat)")
    far = float(np.linalg.norm(corners, axis=1).max())
    if radius is not None and far > radius + _FIT_TOL * max(radius, 1.0):
        raise ValueError(f"{what}: the planes bound a solid reaching {far!r} m from the origin, beyond the bounding "
                         f"radius {radius!r} m (a face plane missing?)")  # fmt: skip
    return far


def hull_params(vertices: np.ndarray, planes: np.ndarray | None = None) -> tuple[float, ...]:
    """The params row of a convex polyhedron (``SHAPE_HULL``) in its shape frame:
    [plane count, bounding radius, 0, n0x, n0y, n0z, d0, n1x, ...].

    ``vertices`` (V, 3): its corners (a mesh's points, all on or inside the planes). ``planes``
    (P, 4): its face planes [nx, ny, nz, d], unit outward normal n, inside where n . x <= d (one
    per face: coplanar triangles merged); None computes them from the vertices' convex hull
    (scipy's qhull). The bounding radius is the farthest vertex's distance from the frame's
    origin (the contacts' broad phase skips points farther than it plus their reach).

    Raises ValueError for a non-unit normal, a vertex outside a plane, a plane that touches no
    vertex (not a face of their hull), fewer than four planes, or planes that do not close into a
    solid within the vertices' reach (a face missing)."""
    v = np.asarray(vertices, dtype=np.float64)
    if v.ndim != 2 or v.shape[1] != 3 or v.shape[0] < 4:
        raise ValueError(f"hull_params: vertices must be (V, 3) with V >= 4, got shape {v.shape}")
    if not np.isfinite(v).all():
        raise ValueError("hull_params: vertices must be finite")
    if planes is None:
        planes = _hull_planes(v)
    pl = np.asarray(planes, dtype=np.float64)
    if pl.ndim != 2 or pl.shape[1] != 4:
        raise ValueError(f"hull_params: planes must be (P, 4) rows [nx, ny, nz, d], got shape {pl.shape}")
    radius = float(np.linalg.norm(v, axis=1).max())
    far = _check_planes(pl[:, :3], pl[:, 3], None, "hull_params")
    tol = _FIT_TOL * max(radius, 1.0)
    gap = v @ pl[:, :3].T - pl[None, :, 3]  # (V, P): > 0 outside a plane
    worst = np.unravel_index(int(np.argmax(gap)), gap.shape)
    if gap[worst] > tol:
        raise ValueError(f"hull_params: vertex {worst[0]} lies {gap[worst]:.3g} m outside plane {worst[1]} (normals must "
                         f"point outward, and every vertex lie on or inside every plane)")  # fmt: skip
    off = (-gap).min(axis=0)
    loose = np.flatnonzero(off > tol)
    if loose.size:
        raise ValueError(f"hull_params: plane {loose[0]} touches none of the vertices (the nearest is {off[loose[0]]:.3g} m "
                         f"inside it): not a face of their hull")  # fmt: skip
    if far > radius + tol:
        raise ValueError(f"hull_params: the planes bound a solid reaching {far!r} m from the origin, beyond the farthest "
                         f"vertex at {radius!r} m (a face plane missing?)")  # fmt: skip
    # the larger of the two (equal within rounding): the broad phase must hold the planes' solid
    radius = max(radius, far)
    n = pl[:, :3] / np.linalg.norm(pl[:, :3], axis=1)[:, None]
    d = pl[:, 3] / np.linalg.norm(pl[:, :3], axis=1)
    row = [float(pl.shape[0]), radius, 0.0]
    for k in range(pl.shape[0]):
        row.extend((float(n[k, 0]), float(n[k, 1]), float(n[k, 2]), float(d[k])))
    return tuple(row)


def _hull_planes(v: np.ndarray) -> np.ndarray:
    """(P, 4) distinct face planes of the convex hull of ``v`` (qhull triangulates a face into
    facets of the same plane: merged here)."""
    try:
        from scipy.spatial import ConvexHull
    except ImportError as e:  # scipy is an optional dependency (the 'reference' extra)
        raise ValueError("hull_params: computing the planes from the vertices needs scipy; pass planes=") from e
    eq = ConvexHull(v).equations  # [n, o] with n . x + o <= 0 inside, n unit
    planes: list[np.ndarray] = []
    for n0, n1, n2, o in eq:
        row = np.array([n0, n1, n2, -o])
        if not any(np.abs(row - q).max() < 1e-9 for q in planes):
            planes.append(row)
    return np.array(planes)


@functools.lru_cache(maxsize=256)
def check_hull_row(row: tuple[float, ...], what: str = "hull") -> None:
    """Raise ValueError unless ``row`` is a valid hull params row (``hull_params``'s layout, unit
    normals, planes that close into a solid within its bounding radius). Cached: a scene passes
    the same rows each time it is built."""
    n = len(row)
    if n < HULL_HEADER + HULL_PLANE * HULL_MIN_PLANES:
        raise ValueError(f"{what}: a hull's params row has {HULL_HEADER} header values and {HULL_PLANE} per plane, at "
                         f"least {HULL_MIN_PLANES} planes; got {n} values")  # fmt: skip
    a = np.asarray(row, dtype=np.float64)
    if not np.isfinite(a).all():
        raise ValueError(f"{what}: the params row must be finite")
    count, radius = a[0], a[1]
    if count != int(count) or n != HULL_HEADER + HULL_PLANE * int(count):
        raise ValueError(f"{what}: the row says {float(a[0])!r} planes, which needs {HULL_HEADER} + {HULL_PLANE} x that many "
                         f"values; got {n} (build it with hull_params)")  # fmt: skip
    if not radius > 0.0 or a[2] != 0.0:
        raise ValueError(f"{what}: column 1 (the bounding radius) must be > 0 and column 2 zero, got {float(radius)!r} and "
                         f"{float(a[2])!r}")  # fmt: skip
    planes = a[HULL_HEADER:].reshape(-1, HULL_PLANE)
    _check_planes(planes[:, :3], planes[:, 3], float(radius), what)
