"""Analytic collision shapes and the ellipsoid support radius (numba, float64).

A shape is described in its own frame: plane = the half-space z <= 0; sphere (radius); box (half
extents); cylinder and capsule along z (radius, half height), as in pybullet. ``shape_distance``
gives the signed distance of a point from the surface (negative inside) and the outward unit
normal at the nearest surface point, so one projection rule serves every shape.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

SHAPE_PLANE = 0
SHAPE_SPHERE = 1
SHAPE_BOX = 2
SHAPE_CYLINDER = 3
SHAPE_CAPSULE = 4
SHAPE_CODES = {"plane": SHAPE_PLANE, "sphere": SHAPE_SPHERE, "box": SHAPE_BOX, "cylinder": SHAPE_CYLINDER,
               "capsule": SHAPE_CAPSULE}  # fmt: skip

jit = nb.njit(cache=True, inline="always")


@jit
def shape_distance(kind, params, p):
    """Signed distance of local point ``p`` (3-tuple) from a shape, and the outward unit normal.

    ``params``: sphere (r, -, -); box (hx, hy, hz); cylinder/capsule (r, half height, -).
    Returns (distance, nx, ny, nz) in the shape frame.
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
    """Array front end for tests: returns [distance, nx, ny, nz]."""
    d, nx, ny, nz = shape_distance(kind, (params[0], params[1], params[2]), (p[0], p[1], p[2]))
    out = np.empty(4)
    out[0] = d
    out[1] = nx
    out[2] = ny
    out[3] = nz
    return out
