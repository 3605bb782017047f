"""Analytic shape distances and the ellipsoid support radius."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest

from softgrasp_env.tissue.collision import (
    SHAPE_BOX,
    SHAPE_CAPSULE,
    SHAPE_CODES,
    SHAPE_CYLINDER,
    SHAPE_PLANE,
    SHAPE_SPHERE,
    shape_distance_array,
    support_radius,
)
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
                           "cylinder": SHAPE_CYLINDER, "capsule": SHAPE_CAPSULE}  # fmt: skip
    assert len(set(SHAPE_CODES.values())) == 5


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
