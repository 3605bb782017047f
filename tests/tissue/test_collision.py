"""Analytic shape distances and the ellipsoid support radius."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest

from softgrasp_env.sim.world import ShapeSpec, _params_table
from softgrasp_env.tissue.collision import (
    HULL_HEADER,
    HULL_PLANE,
    SHAPE_BOX,
    SHAPE_CAPSULE,
    SHAPE_CODES,
    SHAPE_CONE,
    SHAPE_CYLINDER,
    SHAPE_ELLIPTIC,
    SHAPE_HULL,
    SHAPE_PLANE,
    SHAPE_SPHERE,
    check_hull_row,
    hull_params,
    more_kinds_of,
    shape_distance_array,
    shape_distance_of,
    support_radius,
)
from softgrasp_env.tissue.contacts import _bounding_radius
from softgrasp_env.tissue.rigid import Colliders
from softgrasp_env.tissue.rotation import quat_to_matrix

S2 = math.sqrt(0.5)
S3 = math.sqrt(1.0 / 3.0)

SPHERE = (SHAPE_SPHERE, (0.5, 0.0, 0.0))
BOX = (SHAPE_BOX, (1.0, 2.0, 3.0))
CYLINDER = (SHAPE_CYLINDER, (1.0, 2.0, 0.0))
CAPSULE = (SHAPE_CAPSULE, (0.5, 1.0, 0.0))
PLANE = (SHAPE_PLANE, (0.0, 0.0, 0.0))


def dist(shape, p) -> np.ndarray:
    kind, params = shape
    return shape_distance_array(kind, np.asarray(params, dtype=np.float64), np.asarray(p, dtype=np.float64))


def check_consistent(shape, p, tol=1e-12) -> np.ndarray:
    """Unit normal, and p - d n lies on the surface."""
    out = dist(shape, p)
    d, n = out[0], out[1:]
    assert abs(np.linalg.norm(n) - 1.0) < 1e-12
    foot = np.asarray(p, dtype=np.float64) - d * n
    assert abs(dist(shape, foot)[0]) < tol
    return out


# (point, expected distance, expected normal)
CASES = {
    "plane": [
        ((3.0, -2.0, 0.7), 0.7, (0, 0, 1)),
        ((0.0, 0.0, 0.0), 0.0, (0, 0, 1)),
        ((1.0, 5.0, -0.25), -0.25, (0, 0, 1)),
    ],
    "sphere": [
        ((2.0, 0.0, 0.0), 1.5, (1, 0, 0)),
        ((0.0, -0.3, 0.4), 0.0, (0, -0.6, 0.8)),  # on the surface, |p| = 0.5
        ((0.0, 0.0, -0.1), -0.4, (0, 0, -1)),
        ((1.0, 1.0, 1.0), math.sqrt(3.0) - 0.5, (S3, S3, S3)),
        ((0.0, 0.0, 0.0), -0.5, None),  # centre: any unit normal
    ],
    "box": [
        # outside a face
        ((1.5, 0.3, -1.0), 0.5, (1, 0, 0)),
        ((0.2, -2.25, 1.0), 0.25, (0, -1, 0)),
        ((0.0, 0.0, 3.5), 0.5, (0, 0, 1)),
        # outside an edge (x and y out, z inside)
        ((2.0, 3.0, 0.5), math.sqrt(2.0), (S2, S2, 0)),
        ((-1.3, 0.0, -3.4), 0.5, (-0.6, 0, -0.8)),
        # outside a corner
        ((-2.0, 3.0, -4.0), math.sqrt(3.0), (-S3, S3, -S3)),
        # on a face, on an edge, on a corner
        ((1.0, 0.5, 0.5), 0.0, (1, 0, 0)),
        ((0.1, 2.0, -3.0), 0.0, None),
        ((1.0, -2.0, 3.0), 0.0, None),
        # inside: nearest face
        ((0.8, 0.0, 0.0), -0.2, (1, 0, 0)),
        ((-0.9, 0.0, 0.0), -0.1, (-1, 0, 0)),
        ((0.0, -1.5, 0.0), -0.5, (0, -1, 0)),
        ((0.0, 0.0, 2.7), -0.3, (0, 0, 1)),
        ((0.0, 0.0, 0.0), -1.0, None),  # centre, tied between +x and -x
    ],
    "cylinder": [
        # side, cap, rim edge
        ((3.0, 0.0, 0.5), 2.0, (1, 0, 0)),
        ((0.0, -1.5, -1.9), 0.5, (0, -1, 0)),
        ((0.3, 0.2, 2.5), 0.5, (0, 0, 1)),
        ((0.0, 0.0, -4.0), 2.0, (0, 0, -1)),
        ((2.0, 0.0, 3.0), math.sqrt(2.0), (S2, 0, S2)),
        ((0.0, -4.0, -6.0), 5.0, (0, -0.6, -0.8)),
        # on the surface
        ((0.6, 0.8, 1.0), 0.0, (0.6, 0.8, 0)),
        ((0.1, 0.1, -2.0), 0.0, (0, 0, -1)),
        ((1.0, 0.0, 2.0), 0.0, None),  # rim
        # inside: nearest of wall and caps
        ((0.9, 0.0, 0.0), -0.1, (1, 0, 0)),
        ((0.0, 0.3, 1.8), -0.2, (0, 0, 1)),
        ((0.0, 0.0, -1.5), -0.5, (0, 0, -1)),
        ((0.0, 0.0, 0.0), -1.0, None),  # on the axis: any radial direction
    ],
    "capsule": [
        ((2.0, 0.0, 0.3), 1.5, (1, 0, 0)),
        ((0.0, 0.0, 3.0), 1.5, (0, 0, 1)),
        ((0.0, 0.0, -1.25), -0.25, (0, 0, -1)),
        ((0.3, 0.0, 1.4), 0.0, (0.6, 0, 0.8)),  # on the upper hemisphere
        ((0.0, -0.5, -0.2), 0.0, (0, -1, 0)),  # on the straight part
        ((3.0, 0.0, -5.0), 4.5, (0.6, 0, -0.8)),
        ((0.0, 0.2, 0.9), -0.3, (0, 1, 0)),
        ((0.0, 0.0, 0.4), -0.5, None),  # on the axis
    ],
}
SHAPES = {"plane": PLANE, "sphere": SPHERE, "box": BOX, "cylinder": CYLINDER, "capsule": CAPSULE}


@pytest.mark.parametrize(
    "name, p, d, n",
    [(name, *case) for name, cases in CASES.items() for case in cases],
)
def test_shape_distance_analytic(name, p, d, n):
    out = check_consistent(SHAPES[name], p)
    assert out[0] == pytest.approx(d, abs=1e-12)
    if n is not None:
        assert np.abs(out[1:] - np.asarray(n, dtype=np.float64)).max() < 1e-12


def test_shape_codes_table():
    assert SHAPE_CODES == {"plane": SHAPE_PLANE, "sphere": SHAPE_SPHERE, "box": SHAPE_BOX,
                           "cylinder": SHAPE_CYLINDER, "capsule": SHAPE_CAPSULE, "cone": SHAPE_CONE,
                           "elliptic": SHAPE_ELLIPTIC, "hull": SHAPE_HULL}  # fmt: skip
    assert len(set(SHAPE_CODES.values())) == 8
    # the first five keep their codes (recorded worlds), the new ones follow them
    assert (SHAPE_PLANE, SHAPE_SPHERE, SHAPE_BOX, SHAPE_CYLINDER, SHAPE_CAPSULE) == (0, 1, 2, 3, 4)
    assert (SHAPE_CONE, SHAPE_ELLIPTIC, SHAPE_HULL) == (5, 6, 7)


def _brute_box(h, p):
    """Reference signed distance of a box."""
    q = np.abs(p) - h
    outside = np.linalg.norm(np.maximum(q, 0.0))
    inside = min(q.max(), 0.0)
    return outside + inside


def _brute_cylinder(r, hh, p):
    q = np.array([math.hypot(p[0], p[1]) - r, abs(p[2]) - hh])
    return np.linalg.norm(np.maximum(q, 0.0)) + min(q.max(), 0.0)


def _brute_capsule(r, hh, p):
    return math.sqrt(p[0] ** 2 + p[1] ** 2 + (p[2] - min(max(p[2], -hh), hh)) ** 2) - r


@pytest.mark.parametrize("name", ["sphere", "box", "cylinder", "capsule"])
def test_random_points_match_reference_and_project_onto_surface(name):
    shape = SHAPES[name]
    params = shape[1]
    rng = np.random.default_rng(42)
    pts = rng.uniform(-4.5, 4.5, size=(400, 3))
    for p in pts:
        out = check_consistent(shape, p, tol=1e-12)
        if name == "sphere":
            ref = np.linalg.norm(p) - params[0]
        elif name == "box":
            ref = _brute_box(np.array(params), p)
        elif name == "cylinder":
            ref = _brute_cylinder(params[0], params[1], p)
        else:
            ref = _brute_capsule(params[0], params[1], p)
        assert out[0] == pytest.approx(ref, abs=1e-12)
        # the normal points from the foot point toward p when outside, away when inside
        if abs(out[0]) > 1e-9:
            foot = p - out[0] * out[1:]
            assert np.dot(p - foot, out[1:]) * np.sign(out[0]) > 0.0


@pytest.mark.parametrize("name", ["sphere", "box", "cylinder", "capsule"])
def test_distance_gradient_equals_normal(name):
    """Away from ties, the normal is the gradient of the signed distance (central differences)."""
    shape = SHAPES[name]
    rng = np.random.default_rng(7)
    h = 1e-6
    checked = 0
    for p in rng.uniform(-4.5, 4.5, size=(200, 3)):
        out = dist(shape, p)
        grad = np.array([(dist(shape, p + h * e)[0] - dist(shape, p - h * e)[0]) / (2 * h) for e in np.eye(3)])
        normals = [dist(shape, p + s * h * e)[1:] for e in np.eye(3) for s in (1, -1)]
        if max(np.abs(m - out[1:]).max() for m in normals) > 1e-3:
            continue  # next to a tie (inside a box or cylinder): gradient is not defined
        assert np.abs(grad - out[1:]).max() < 1e-6
        checked += 1
    assert checked > 150


# --- support radius ------------------------------------------------------------------------------


@numba.njit
def _support_radius(q, radii, n):
    return support_radius((q[0], q[1], q[2], q[3]), (radii[0], radii[1], radii[2]), (n[0], n[1], n[2]))


def support_ref(q, radii, n):
    r = quat_to_matrix(q)
    return math.sqrt(n @ r @ np.diag(np.asarray(radii) ** 2) @ r.T @ n)


def test_support_radius_along_axes_unrotated():
    q = np.array([0.0, 0.0, 0.0, 1.0])
    radii = np.array([0.3, 0.2, 0.05])
    for axis in range(3):
        for sign in (1.0, -1.0):
            n = np.zeros(3)
            n[axis] = sign
            assert _support_radius(q, radii, n) == pytest.approx(radii[axis], abs=1e-15)


def test_support_radius_along_rotated_axes():
    """Rotated by 90 degrees about z: the ellipsoid's x axis lies along world y."""
    q = np.array([0.0, 0.0, math.sqrt(0.5), math.sqrt(0.5)])
    radii = np.array([0.3, 0.2, 0.05])
    assert _support_radius(q, radii, np.array([0.0, 1.0, 0.0])) == pytest.approx(0.3, abs=1e-15)
    assert _support_radius(q, radii, np.array([-1.0, 0.0, 0.0])) == pytest.approx(0.2, abs=1e-15)
    assert _support_radius(q, radii, np.array([0.0, 0.0, 1.0])) == pytest.approx(0.05, abs=1e-15)
    # along the particle's own axes in world coordinates, for a random orientation
    rng = np.random.default_rng(3)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    r = quat_to_matrix(q)
    for axis in range(3):
        assert _support_radius(q, radii, r[:, axis]) == pytest.approx(radii[axis], abs=1e-14)


def test_support_radius_matches_numpy_reference():
    rng = np.random.default_rng(9)
    for _ in range(300):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        radii = rng.uniform(0.01, 1.0, size=3)
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        got = _support_radius(q, radii, n)
        assert got == pytest.approx(support_ref(q, radii, n), rel=1e-12)
        assert radii.min() - 1e-12 <= got <= radii.max() + 1e-12


def test_support_radius_is_the_extent_of_the_ellipsoid():
    """The largest n . x over the ellipsoid surface (sampled densely) equals the support radius."""
    rng = np.random.default_rng(12)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    radii = np.array([0.4, 0.15, 0.07])
    r = quat_to_matrix(q)
    u = rng.normal(size=(200_000, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    surface = (u * radii) @ r.T
    for _ in range(5):
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        extent = (surface @ n).max()
        got = _support_radius(q, radii, n)
        assert extent <= got + 1e-12
        assert extent > got - 2e-3


# --- cone frustum and elliptic cylinder: exact signed distances ----------------------------------

CONES = {
    "narrowing": (1.0, 0.5, 1.0),
    "widening": (0.4, 1.2, 0.8),  # r_top > r_bottom
    "full": (1.0, 0.0, 1.5),  # r_top = 0: a full cone
    "squat": (2.0, 1.6, 0.3),
    "upside_down": (0.0, 0.8, 0.6),  # r_bottom = 0
}
ELLIPTICS = {
    "wide": (2.0, 1.0, 1.0),  # a > b
    "tall": (0.6, 1.5, 0.7),  # a < b
    "circle": (1.0, 1.0, 2.0),  # a == b
    "slender": (3.0, 0.3, 0.5),  # 10:1
}
NEW_KINDS = [(SHAPE_CONE, name, p) for name, p in CONES.items()] + [
    (SHAPE_ELLIPTIC, name, p) for name, p in ELLIPTICS.items()
]
NEW_IDS = [f"{'cone' if k == SHAPE_CONE else 'elliptic'}-{name}" for k, name, _ in NEW_KINDS]
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


def _golden_min(f, lo, hi, iters=100):
    """Smallest value of f on [lo, hi], f unimodal there (golden-section search): the reference
    minimiser, independent of the kernels' closed forms and Newton steps."""
    best = min(f(lo), f(hi))
    for _ in range(iters):
        m1, m2 = hi - _GOLDEN * (hi - lo), lo + _GOLDEN * (hi - lo)
        if f(m1) < f(m2):
            hi = m2
        else:
            lo = m1
    return min(best, f(0.5 * (lo + hi)))


def _inside(kind, params, p) -> bool:
    if kind == SHAPE_CONE:
        r1, r2, hh = params
        return abs(p[2]) <= hh and math.hypot(p[0], p[1]) <= r1 + (r2 - r1) * (p[2] + hh) / (2.0 * hh)
    a, b, hh = params
    return (p[0] / a) ** 2 + (p[1] / b) ** 2 <= 1.0 and abs(p[2]) <= hh


def _cone_reference(params, p) -> float:
    """A solid of revolution is nearest to p in p's half-plane through the axis: the distance in
    (rho, z) to the section's three boundary segments (the squared distance is convex along each),
    signed by the inside test."""
    r1, r2, hh = params
    q = (math.hypot(p[0], p[1]), p[2])
    segments = (((0.0, -hh), (r1, -hh)), ((r1, -hh), (r2, hh)), ((r2, hh), (0.0, hh)))
    d2 = min(
        _golden_min(lambda t, a=a, b=b: (a[0] + t * (b[0] - a[0]) - q[0]) ** 2 + (a[1] + t * (b[1] - a[1]) - q[1]) ** 2,
                    0.0, 1.0)
        for a, b in segments
    )  # fmt: skip
    return -math.sqrt(d2) if _inside(SHAPE_CONE, params, p) else math.sqrt(d2)


def _ellipse_reference(a, b, x, y) -> float:
    """Signed 2D distance from the ellipse: its angle sampled 2048 times, then every sampled local
    minimum of the squared distance refined by golden-section search."""
    n = 2048
    th = 2.0 * np.pi * np.arange(n) / n
    f2 = (a * np.cos(th) - x) ** 2 + (b * np.sin(th) - y) ** 2
    minima = np.flatnonzero((f2 <= np.roll(f2, 1)) & (f2 <= np.roll(f2, -1)))
    step = 2.0 * np.pi / n
    d2 = min(
        _golden_min(lambda t: (a * math.cos(t) - x) ** 2 + (b * math.sin(t) - y) ** 2, th[j] - step, th[j] + step)
        for j in minima
    )
    return -math.sqrt(d2) if (x / a) ** 2 + (y / b) ** 2 < 1.0 else math.sqrt(d2)


def _reference(kind, params, p) -> float:
    if kind == SHAPE_CONE:
        return _cone_reference(params, p)
    # a prism is the product of its section and [-hh, hh]: the distances combine as the cylinder's
    dr = _ellipse_reference(params[0], params[1], p[0], p[1])
    dz = abs(p[2]) - params[2]
    return math.hypot(max(dr, 0.0), max(dz, 0.0)) + min(max(dr, dz), 0.0)


def _surface_samples(kind, params, n_ang=360, n_len=120) -> tuple[np.ndarray, float]:
    """Points on the exact surface (3D, no symmetry used) and the sampling resolution: half the
    largest cell diagonal bounds how far any surface point is from its nearest sample."""
    th = 2.0 * np.pi * np.arange(n_ang) / n_ang
    u = np.arange(n_len + 1) / n_len
    c, s = np.cos(th), np.sin(th)
    if kind == SHAPE_CONE:
        r1, r2, hh = params
        rr, zz = r1 + (r2 - r1) * u, -hh + 2.0 * hh * u
        parts = [np.stack([np.outer(rr, c), np.outer(rr, s), np.repeat(zz[:, None], n_ang, 1)], -1)]
        cells = [math.hypot(math.hypot(r2 - r1, 2.0 * hh) / n_len, max(r1, r2) * 2.0 * np.pi / n_ang)]
        for r, z in ((r1, -hh), (r2, hh)):
            if r > 0.0:
                parts.append(np.stack([np.outer(r * u, c), np.outer(r * u, s), np.full((n_len + 1, n_ang), z)], -1))
                cells.append(math.hypot(r / n_len, r * 2.0 * np.pi / n_ang))
    else:
        a, b, hh = params
        zz = -hh + 2.0 * hh * u
        ex, ey = np.tile(a * c, (n_len + 1, 1)), np.tile(b * s, (n_len + 1, 1))
        parts = [np.stack([ex, ey, np.repeat(zz[:, None], n_ang, 1)], -1)]
        parts += [
            np.stack([np.outer(u, a * c), np.outer(u, b * s), np.full((n_len + 1, n_ang), z)], -1) for z in (-hh, hh)
        ]
        arc = max(a, b) * 2.0 * np.pi / n_ang
        cells = [math.hypot(arc, 2.0 * hh / n_len), math.hypot(arc, max(a, b) / n_len)]
    return np.concatenate([q.reshape(-1, 3) for q in parts]), 0.5 * max(cells)


def _test_points(params, seed, n) -> np.ndarray:
    """n points in the shape's bounding box (many inside) and n in a box about twice as large."""
    rmax, hh = max(params[0], params[1]), params[2]
    rng = np.random.default_rng(seed)
    tight = rng.uniform(-1.0, 1.0, (n, 3)) * [rmax, rmax, hh]
    wide = rng.uniform(-1.0, 1.0, (n, 3)) * [2.0 * rmax, 2.0 * rmax, 2.0 * hh + rmax]
    return np.vstack([tight, wide])


def _near_surface_points(kind, params, seed, n) -> np.ndarray:
    """Surface samples moved 1e-9 to 1e-3 (log-uniform) in random directions: on both sides, close."""
    samples, _ = _surface_samples(kind, params, 90, 30)
    rng = np.random.default_rng(seed)
    pick = samples[rng.integers(0, len(samples), n)]
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return pick + v * 10.0 ** rng.uniform(-9.0, -3.0, (n, 1))


@pytest.mark.parametrize("kind, name, params", NEW_KINDS, ids=NEW_IDS)
def test_new_kind_distance_is_the_nearest_of_a_dense_surface_sampling(kind, name, params):
    """The brute-force distance to points densely sampled over the whole surface in 3D (not using
    the rotational or prism symmetry the kernels use) is never below |d| and above it by at most
    the sampling resolution (measured: at most 2e-3 to 1e-2, about a third of the resolutions of
    9e-3 to 3e-2; and never below it by more than 4e-16)."""
    samples, resolution = _surface_samples(kind, params)
    pts = _test_points(params, seed=1, n=60)
    d = np.array([dist((kind, params), p)[0] for p in pts])
    sq = (samples**2).sum(axis=1)
    brute = np.array([math.sqrt(max((sq - 2.0 * samples @ p + p @ p).min(), 0.0)) for p in pts])
    gap = brute - np.abs(d)
    assert gap.min() > -1e-9  # the samples lie on the surface: none is nearer than the distance
    assert gap.max() <= resolution


@pytest.mark.parametrize("kind, name, params", NEW_KINDS, ids=NEW_IDS)
def test_new_kind_distance_sign_and_projection_are_exact(kind, name, params):
    """Against the golden-section reference: the signed distance (measured within 1.8e-15), the
    sign from the inside test, a unit normal (within 3.3e-16), and p - d n on the surface (|d|
    there at most 1.1e-15), over random points inside and outside and points within 1e-9 to 1e-3
    of the surface."""
    pts = np.vstack([_test_points(params, seed=2, n=150), _near_surface_points(kind, params, seed=3, n=150)])
    inside = outside = 0
    for p in pts:
        out = dist((kind, params), p)
        d, n = out[0], out[1:]
        ref = _reference(kind, params, p)
        assert d == pytest.approx(ref, abs=1e-13), p
        if abs(ref) > 1e-12:
            assert (d < 0.0) == _inside(kind, params, p), p
            inside += d < 0.0
            outside += d > 0.0
        assert abs(np.linalg.norm(n) - 1.0) < 1e-14
        assert abs(dist((kind, params), p - d * n)[0]) < 1e-13, p
    assert inside > 60 and outside > 150


@pytest.mark.parametrize("kind, name, params", NEW_KINDS, ids=NEW_IDS)
def test_new_kind_normal_is_the_distance_gradient(kind, name, params):
    """Away from the medial axis (where the normals of the neighbouring points agree), the normal
    is the central-difference gradient of the distance (measured within 1.1e-9: the differences'
    own rounding at h = 1e-6)."""
    h = 1e-6
    checked = 0
    pts = _test_points(params, seed=4, n=100)
    for p in pts:
        out = dist((kind, params), p)
        grad = np.array([(dist((kind, params), p + h * e)[0] - dist((kind, params), p - h * e)[0]) / (2 * h)
                         for e in np.eye(3)])  # fmt: skip
        normals = [dist((kind, params), p + s * h * e)[1:] for e in np.eye(3) for s in (1, -1)]
        if max(np.abs(m - out[1:]).max() for m in normals) > 1e-3:
            continue
        assert np.abs(grad - out[1:]).max() < 5e-9, p
        checked += 1
    assert checked > 0.9 * len(pts)


@pytest.mark.parametrize("a, b", [(2.0, 1.0), (1.0, 0.01), (0.001, 0.1), (1.0, 0.999)])
def test_elliptic_distance_next_to_the_evolute_cusp(a, b):
    """The Newton iteration's slowest start: points next to the cusp of the ellipse's evolute on
    its major axis, x ~ (a^2 - b^2) / a, just off the axis, and within the 1e-12 b band the kernel
    takes as on it (which moves the distance and the projection by at most the offset: the
    distance is 1-Lipschitz; measured up to the offset itself). The distance matches the reference
    and p - d n lies on the surface (measured within 3.7e-16 of the major semi-axis off the band)."""
    big, small = max(a, b), min(a, b)
    cusp = (big * big - small * small) / big
    shape = (SHAPE_ELLIPTIC, (a, b, 10.0 * big))  # tall: the section, not a cap, is nearest
    worst = 0.0
    for eps in [0.0, *np.geomspace(1e-15, 1e-2, 8), *(-np.geomspace(1e-15, 1e-2, 8))]:
        for off in [0.0, 5e-13, 2e-12, 1e-10, 1e-7, 1e-4]:
            along, across = cusp * (1.0 + eps), off * small
            p = np.array([along, across, 0.0]) if a > b else np.array([across, along, 0.0])
            out = dist(shape, p)
            band = across if off <= 1e-12 else 0.0
            err = abs(out[0] - _ellipse_reference(a, b, p[0], p[1]))
            foot = abs(dist(shape, p - out[0] * out[1:])[0])
            assert err <= 1e-14 * big + band and foot <= 1e-14 * big + band, (eps, off, err, foot)
            if not band:
                worst = max(worst, err, foot)
    assert worst < 1e-14 * big


def test_elliptic_with_equal_axes_is_the_cylinder():
    """a == b takes the cylinder's own expressions: the same numbers to the bit."""
    rng = np.random.default_rng(6)
    for p in [*rng.uniform(-4.5, 4.5, size=(300, 3)), np.zeros(3), np.array([0.0, 0.0, 2.5])]:
        assert np.array_equal(dist((SHAPE_ELLIPTIC, (1.0, 1.0, 2.0)), p), dist(CYLINDER, p))


def test_cone_with_equal_radii_is_the_cylinder():
    rng = np.random.default_rng(8)
    for p in rng.uniform(-4.5, 4.5, size=(300, 3)):
        got, want = dist((SHAPE_CONE, (1.0, 1.0, 2.0)), p), dist(CYLINDER, p)
        assert np.abs(got - want).max() < 1e-14, p


# --- convex hull --------------------------------------------------------------------------------


def _box_hull(h) -> tuple[np.ndarray, np.ndarray]:
    """A box's 8 corners and 6 face planes [n, d]."""
    h = np.asarray(h, dtype=np.float64)
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * h
    planes = np.array([[*(s * e), h[k]] for k, e in enumerate(np.eye(3)) for s in (1.0, -1.0)])
    return corners, planes


def _prism_hull(sides: int, r: float, hh: float) -> tuple[np.ndarray, np.ndarray]:
    """A regular prism inscribed in the cylinder (r, hh): corners on the circle at the half angles,
    side planes at the apothem r cos(pi / sides), and the two caps."""
    corner = 2.0 * np.pi * (np.arange(sides) + 0.5) / sides
    ring = np.c_[r * np.cos(corner), r * np.sin(corner)]
    vertices = np.vstack([np.c_[ring, np.full(sides, z)] for z in (-hh, hh)])
    face = 2.0 * np.pi * np.arange(sides) / sides
    planes = np.c_[np.cos(face), np.sin(face), np.zeros(sides), np.full(sides, r * math.cos(math.pi / sides))]
    return vertices, np.vstack([planes, [[0.0, 0.0, 1.0, hh], [0.0, 0.0, -1.0, hh]]])


def test_hull_params_row_layout():
    corners, planes = _box_hull((1.0, 2.0, 3.0))
    row = hull_params(corners, planes)
    assert len(row) == HULL_HEADER + HULL_PLANE * 6
    assert row[:3] == (6.0, math.sqrt(14.0), 0.0)  # count, farthest corner, 0
    np.testing.assert_array_equal(np.array(row[3:]).reshape(6, 4), planes)
    check_hull_row(row)  # valid


def test_hull_of_a_box_equals_the_box_kind():
    """The six planes of a box: inside and over the faces (one coordinate outside the box) the
    hull's distance and normal are the box kind's (measured: equal to the bit); over an edge or a
    corner it is a lower bound (the distance to the farthest face plane: at least 1/sqrt(3) of the
    true one; measured 0.60), positive."""
    h = (1.0, 2.0, 3.0)
    row = np.array(hull_params(*_box_hull(h)))
    rng = np.random.default_rng(21)
    seen = {0: 0, 1: 0, 2: 0}
    for p in rng.uniform(-4.5, 4.5, size=(1200, 3)):
        got, want = dist((SHAPE_HULL, row), p), dist(BOX, p)
        outside = int((np.abs(p) > h).sum())
        seen[min(outside, 2)] += 1
        if outside <= 1:
            assert np.abs(got - want).max() < 1e-15, p
        else:
            assert 0.0 < got[0] <= want[0] + 1e-15
            assert got[0] >= want[0] / math.sqrt(outside) - 1e-15  # the largest of the 2-3 components
    assert min(seen.values()) > 50


@pytest.mark.parametrize("sides", [16, 32, 64])
def test_hull_of_a_prism_approaches_the_cylinder(sides):
    """A regular prism inscribed in the cylinder (its sag r (1 - cos(pi / sides)) below the round
    surface): where the hull's distance is exact (beside the side faces, |z| <= hh, or above and
    below the caps inside the apothem, and inside) it is the cylinder's within the sag scaled by the
    point's radius, (1 - cos(pi / sides)) max(rho, r); inside, the worst difference is the sag
    itself (measured 0.9998 to 1.0000 of it, on the axis), so it falls four-fold each time the
    sides double."""
    r, hh = 1.0, 2.0
    row = np.array(hull_params(*_prism_hull(sides, r, hh)))
    sag = 1.0 - math.cos(math.pi / sides)
    rng = np.random.default_rng(22)
    worst = 0.0
    checked = 0
    for p in rng.uniform(-4.5, 4.5, size=(3000, 3)):
        rho = math.hypot(p[0], p[1])
        if not (abs(p[2]) <= hh or rho <= r * math.cos(math.pi / sides)):
            continue  # outside next to a rim: the hull's is a lower bound there
        diff = abs(dist((SHAPE_HULL, row), p)[0] - dist(CYLINDER, p)[0])
        assert diff <= sag * max(rho, r) + 1e-15, p
        if rho <= r:
            worst = max(worst, diff)
        checked += 1
    assert checked > 1200
    assert 0.99 * sag * r <= worst <= sag * r + 1e-15


def test_hull_distance_is_the_largest_plane_distance():
    """Straight from the definition, for an irregular hull (a tetrahedron off the origin)."""
    vertices = np.array([[0.1, 0.0, 0.0], [1.0, 0.2, 0.0], [0.3, 1.1, 0.1], [0.4, 0.3, 0.9]])
    planes = []
    for skip in range(4):
        a, b, c = vertices[[k for k in range(4) if k != skip]]
        n = np.cross(b - a, c - a)
        n /= np.linalg.norm(n)
        if n @ (vertices[skip] - a) > 0.0:
            n = -n
        planes.append([*n, n @ a])
    planes = np.array(planes)
    row = np.array(hull_params(vertices, planes))
    assert row[1] == pytest.approx(np.linalg.norm(vertices, axis=1).max(), abs=1e-15)
    rng = np.random.default_rng(23)
    for p in rng.uniform(-0.5, 1.5, size=(300, 3)):
        s = planes[:, :3] @ p - planes[:, 3]
        k = int(np.argmax(s))
        out = dist((SHAPE_HULL, row), p)
        assert out[0] == pytest.approx(s[k], abs=1e-15)
        assert np.abs(out[1:] - planes[k, :3]).max() < 1e-15  # hull_params renormalised it


def _bad_planes(name):
    corners, planes = _box_hull((1.0, 2.0, 3.0))
    planes = planes.copy()
    if name == "non-unit normal":
        planes[2, :3] *= 1.01
    elif name == "vertex outside":
        planes[4, 3] -= 0.1
    elif name == "plane off the vertices":
        planes[4, 3] += 0.1
    elif name == "too few planes":
        planes = planes[:3]
    elif name == "open (a face missing)":
        planes = planes[:5]
    elif name == "not finite":
        planes[0, 3] = np.nan
    elif name == "planes not (P, 4)":
        planes = planes[:, :3]
    elif name == "vertices not (V, 3)":
        corners = corners[:, :2]
    return corners, planes


@pytest.mark.parametrize(
    "name, match",
    [("non-unit normal", "unit vectors; plane 2"), ("vertex outside", "outside plane 4"),
     ("plane off the vertices", "plane 4 touches none"), ("too few planes", "at least 4 planes"),
     ("open (a face missing)", "do not close around a solid"), ("not finite", "finite"),
     ("planes not \\(P, 4\\)", "\\(P, 4\\)"), ("vertices not \\(V, 3\\)", "\\(V, 3\\)")],
)  # fmt: skip
def test_hull_params_rejects_bad_input(name, match):
    with pytest.raises(ValueError, match=match):
        hull_params(*_bad_planes(name.replace("\\", "")))


def test_hull_params_rejects_planes_reaching_past_the_vertices():
    """Each plane touches a vertex and they close, but a corner of the solid has no vertex: the
    broad phase would cull by too small a radius."""
    cube, planes = _box_hull((0.5, 0.5, 0.5))
    cube, planes = cube + 0.5, planes.copy()  # the unit cube [0, 1]^3
    planes[:, 3] += planes[:, :3] @ np.full(3, 0.5)
    with pytest.raises(ValueError, match="beyond the farthest vertex"):
        hull_params(cube[:-1], planes)  # without the corner (1, 1, 1)


def test_hull_params_computes_the_planes_from_the_vertices():
    pytest.importorskip("scipy")
    vertices, planes = _prism_hull(12, 0.03, 0.05)
    given = np.array(hull_params(vertices, planes))
    computed = np.array(hull_params(vertices))  # qhull's triangles, coplanar ones merged
    assert computed[:3].tolist() == given[:3].tolist()
    a = np.array(sorted(map(tuple, np.round(given[3:].reshape(-1, 4), 12))))
    b = np.array(sorted(map(tuple, np.round(computed[3:].reshape(-1, 4), 12))))
    np.testing.assert_allclose(a, b, atol=1e-12)


@pytest.mark.parametrize(
    "row, match",
    [((6.0, 1.0, 0.0), "at least 4 planes"), ((6.0, 4.0, 0.0, *[0.0] * 24), "unit vectors"),
     ((5.0, 4.0, 0.0, *[0.0] * 24), "says 5.0 planes")],
)  # fmt: skip
def test_hull_rows_are_checked(row, match):
    with pytest.raises(ValueError, match=match):
        check_hull_row(row)
    corners, planes = _box_hull((1.0, 2.0, 3.0))
    good = hull_params(corners, planes)
    with pytest.raises(ValueError, match="beyond the bounding radius"):
        check_hull_row((good[0], 0.5 * good[1], *good[2:]))


# --- the kernels' dispatch, broad phase and switch --------------------------------------------------


@numba.njit
def _shape_distance_of(kind, table, s, p, more_kinds):
    return shape_distance_of(kind, table, s, (p[0], p[1], p[2]), more_kinds)


def test_every_kernel_call_site_dispatches_every_kind():
    """shape_distance_of on a world's padded table: each kind reads its row as shape_distance and
    hull_distance do; for a world of the first five kinds, the kernels' None switch gives the same
    numbers as True."""
    hull = hull_params(*_box_hull((1.0, 2.0, 3.0)))
    rows = [PLANE, SPHERE, BOX, CYLINDER, CAPSULE, (SHAPE_CONE, CONES["narrowing"]),
            (SHAPE_ELLIPTIC, ELLIPTICS["wide"]), (SHAPE_HULL, hull)]  # fmt: skip
    table = np.zeros((len(rows), len(hull)))
    for k, (_, params) in enumerate(rows):
        table[k, : len(params)] = params
    kinds = np.array([kind for kind, _ in rows], dtype=np.int32)
    rng = np.random.default_rng(31)
    for p in rng.uniform(-3.0, 3.0, size=(50, 3)):
        for s, (kind, params) in enumerate(rows):
            want = dist((kind, params), p)
            got = _shape_distance_of(kinds[s], table, s, p, True)
            np.testing.assert_array_equal(got, want)
            if kind <= SHAPE_CAPSULE:
                np.testing.assert_array_equal(_shape_distance_of(kinds[s], table, s, p, None), want)


def test_the_switch_is_none_for_the_first_five_kinds_only():
    assert more_kinds_of(np.zeros(0, dtype=np.int32)) is None
    assert more_kinds_of(np.array([0, 1, 2, 3, 4], dtype=np.int32)) is None
    for kind in (SHAPE_CONE, SHAPE_ELLIPTIC, SHAPE_HULL):
        assert more_kinds_of(np.array([0, 3, kind], dtype=np.int32)) is True


@pytest.mark.parametrize(
    "kind, params",
    [(SHAPE_CONE, p) for p in CONES.values()] + [(SHAPE_ELLIPTIC, p) for p in ELLIPTICS.values()],
)
def test_bounding_radius_holds_the_new_kinds(kind, params):
    """The broad phase's sphere holds the whole shape and touches it (the farthest rim point)."""
    samples, _ = _surface_samples(kind, params)
    far = np.linalg.norm(samples, axis=1).max()
    radius = _bounding_radius(kind, params[0], params[1], params[2], True)
    assert far <= radius + 1e-12
    assert far >= radius - 1e-12  # the rims are sampled at their angle 0


def test_bounding_radius_of_a_hull_is_its_farthest_corner():
    vertices, planes = _prism_hull(64, 0.02, 0.03)
    row = hull_params(vertices, planes)
    assert _bounding_radius(SHAPE_HULL, row[0], row[1], row[2], True) == row[1]
    assert row[1] == pytest.approx(math.hypot(0.02, 0.03), rel=1e-15)


def _static_colliders(kinds, table, local_x=None, local_q=None) -> Colliders:
    s = len(kinds)
    return Colliders(
        rigid_x=np.zeros((0, 3)), rigid_q=np.zeros((0, 4)), rigid_v=np.zeros((0, 3)), rigid_w=np.zeros((0, 3)),
        rigid_inv_mass=np.zeros(0), rigid_inv_inertia=np.zeros((0, 3)), rigid_gravity=np.zeros(0, dtype=np.bool_),
        rigid_in_solve=np.zeros(0, dtype=np.bool_), shape_kind=np.array(kinds, dtype=np.int32),
        shape_params=np.asarray(table, dtype=np.float64), shape_rigid=np.full(s, -1, dtype=np.int32),
        shape_local_x=np.zeros((s, 3)) if local_x is None else np.asarray(local_x, dtype=np.float64),
        shape_local_q=np.tile([0.0, 0.0, 0.0, 1.0], (s, 1)) if local_q is None else np.asarray(local_q, dtype=np.float64),
    )  # fmt: skip


def test_colliders_refuse_tables_the_kernels_would_misread():
    hull = hull_params(*_box_hull((0.01, 0.02, 0.03)))
    _static_colliders([SHAPE_BOX, SHAPE_HULL], np.array([[0.01, 0.02, 0.03, *[0.0] * 24], hull]))  # fine
    with pytest.raises(ValueError, match="hull of 6.0 planes"):
        _static_colliders([SHAPE_HULL], np.array([hull[:3]]))
    with pytest.raises(ValueError, match="no shape code"):
        _static_colliders([9], np.zeros((1, 3)))
    with pytest.raises(ValueError, match="K >= 3"):
        _static_colliders([SHAPE_BOX], np.zeros((1, 2)))
    with pytest.raises(ValueError, match="S = 2 shapes"):
        _static_colliders([SHAPE_BOX, SHAPE_BOX], np.zeros((1, 3)))


# --- the world's shapes -----------------------------------------------------------------------------


def test_shape_spec_takes_each_kinds_params():
    hull = hull_params(*_box_hull((0.01, 0.02, 0.03)))
    for kind, params in [("plane", (0, 0, 0)), ("sphere", (0.5, 0.0, 0.0)), ("box", np.array([1.0, 2.0, 3.0])),
                         ("cylinder", (0.02, 0.05, 0.0)), ("capsule", (0.02, 0.05, 0.0)), ("cone", (0.03, 0.0, 0.04)),
                         ("cone", (0.0, 0.03, 0.04)), ("cone", (0.02, 0.04, 0.04)), ("elliptic", (0.03, 0.02, 0.04)),
                         ("hull", hull)]:  # fmt: skip
        spec = ShapeSpec(kind, params)
        assert spec.params == tuple(float(x) for x in params)
        assert all(type(x) is float for x in spec.params)


@pytest.mark.parametrize(
    "kind, params, match",
    [("box", (1.0, 2.0), "box must be 3 numbers .* got 2"),
     ("cylinder", (0.02, 0.05, 0.0, 0.0), "cylinder must be 3 numbers .* got 4"),
     ("elliptic", (0.03, math.nan, 0.04), "elliptic must be finite"),
     ("elliptic", (0.03, 0.0, 0.04), "must be > 0, got params\\[1\\] = 0.0"),
     ("box", (1.0, -2.0, 3.0), "must be > 0, got params\\[1\\] = -2.0"),
     ("sphere", (0.0, 0.0, 0.0), "sphere .* must be > 0"),
     ("cone", (0.0, 0.0, 0.04), "not both 0"), ("cone", (0.03, -0.01, 0.04), "radii must be >= 0"),
     ("cone", (0.03, 0.01, 0.0), "cone .* must be > 0, got params\\[2\\]"),
     ("hull", (1.0, 2.0, 3.0), "ShapeSpec\\('hull'\\) params: a hull's params row"),
     ("hull", (1.0, 2.0), "at least 4 planes"), ("box", "abc", "numbers"), ("ellipse", (1, 1, 1), "must be one of")],
)  # fmt: skip
def test_shape_spec_rejects_wrong_params(kind, params, match):
    with pytest.raises(ValueError, match=match):
        ShapeSpec(kind, params)


def test_the_worlds_params_table_pads_to_the_longest_row():
    hull = hull_params(*_box_hull((0.01, 0.02, 0.03)))
    shapes = [ShapeSpec("plane", (0, 0, 0)), ShapeSpec("hull", hull, rigid=0), ShapeSpec("cone", (0.03, 0.0, 0.04))]
    table = _params_table(shapes)
    assert table.shape == (3, len(hull)) and table.dtype == np.float64 and table.flags.c_contiguous
    np.testing.assert_array_equal(table[1], hull)
    np.testing.assert_array_equal(table[2], [0.03, 0.0, 0.04] + [0.0] * (len(hull) - 3))
    # without a hull, the (S, 3) table the kernels always read
    assert _params_table(shapes[::2]).shape == (2, 3)
    assert _params_table([]).shape == (0, 3)


# --- end to end: a tissue block resting on each new kind ----------------------------------------------

_ON_ITS_SIDE = (0.0, math.sqrt(0.5), 0.0, math.sqrt(0.5))  # the shape's z axis along world x
_BLOCK_HALF = 0.012
# (kind, params, shape orientation, block centre at the start [m], bound on the overlap [m])
_RESTING = {
    # a frustum on its side: the block lands on its slanted side (7 degrees along the axis, well
    # inside the friction angle; a block rests stably on a round body thicker than its own half
    # height)
    "cone-on-its-side": (SHAPE_CONE, (0.03, 0.02, 0.04), _ON_ITS_SIDE, (0.0, 0.0, 0.044), 1e-8),
    # upright: on the top face, overhanging its rim
    "cone-upright": (SHAPE_CONE, (0.05, 0.015, 0.012), (0.0, 0.0, 0.0, 1.0), (0.008, 0.0, 0.03), 1e-5),
    # a 16-sided prism on its side: faces 22.5 degrees apart, the block across their edges, where
    # the hull's distance is a lower bound
    "hull-on-its-side": ("hull", _prism_hull(16, 0.025, 0.04), _ON_ITS_SIDE, (0.0, 0.004, 0.044), 2e-6),
    "elliptic-on-its-side": (SHAPE_ELLIPTIC, (0.03, 0.02, 0.04), _ON_ITS_SIDE, (0.0, 0.0, 0.039), 6e-5),
}


@pytest.mark.parametrize("case", list(_RESTING))
def test_tissue_block_rests_on_a_static_new_kind_without_sinking_in(case):
    """A free 27-particle block (4 mm particles) dropped from 3 mm onto a static cone, hull or
    elliptic cylinder at the defaults (gravity, friction, the material's substeps), with a ground
    plane 5 cm below to catch it should it slide off: for 1.5 s it settles and stays on the shape,
    its particles' overlap with the shape at every step within the bound, three to five times the
    largest measured (cone on its side 2.1e-9 m, upright 3.2e-6, hull 3.9e-7, elliptic 2.0e-5 on
    the narrow end of its major axis; a box and a cylinder under the same block in a drop beside
    them: 1e-6 and 1.3e-5)."""
    from dataclasses import replace

    from softgrasp_env.config import SimConfig, TissueConfig
    from softgrasp_env.tissue.builder import build_free_block
    from softgrasp_env.tissue.compliant import substeps_for
    from softgrasp_env.tissue.solver import TissueSolver
    from softgrasp_env.tissue.state import state_at_rest

    kind, params, q, start, bound = _RESTING[case]
    if kind == "hull":
        kind, params = SHAPE_HULL, hull_params(*params)
    table = np.zeros((2, max(3, len(params))))
    table[0, : len(params)] = params
    col = _static_colliders([kind, SHAPE_PLANE], table, local_x=[[0.0, 0.0, 0.0], [0.0, 0.0, -0.05]],
                            local_q=[q, [0.0, 0.0, 0.0, 1.0]])  # fmt: skip
    model = build_free_block((_BLOCK_HALF,) * 3, TissueConfig(), spacing=0.008)
    sim = SimConfig()
    n = substeps_for(model, sim.dt)
    solver = TissueSolver(model, replace(sim, dt=sim.dt / n) if n > 1 else sim)
    state = state_at_rest(model, np.array([start]), np.array([[0.0, 0.0, 0.0, 1.0]]))
    worst = 0.0
    touching = 0
    for _ in range(round(1.5 / sim.dt) * n):
        touching += solver.step(state, col).contact_count > 0
        worst = max(worst, solver.penetration(state, col)[0])
    assert solver._more_kinds is True  # the kernels with the new kinds ran
    assert worst <= bound
    assert touching > 0.9 * round(1.5 / sim.dt) * n
    centre = state.particle_x.mean(axis=0)
    assert centre[2] > 0.0  # on the shape, not on the ground (its centre would be at -38 mm)
    assert np.abs(state.particle_v).max() < 0.01  # settled
