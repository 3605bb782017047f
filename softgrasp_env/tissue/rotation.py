"""Quaternion maths and rotation extraction, as numba kernels (float64, no object mode).

Quaternions are ``[x, y, z, w]`` like pybullet, so poses pass between the two unchanged. Inside
the kernels quaternions, vectors and 3x3 matrices travel as tuples (row-major for matrices): numba
keeps tuples in registers, whereas a small ``np.empty`` per call would allocate on the heap in the
solver's innermost loops.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

_EPS = 1e-12
# Below these (squared) sizes qexp and qlog use Taylor series that are exact to round-off.
_SERIES_ANGLE2 = 0.06 * 0.06  # rotation angle 0.06 rad (half angle 0.03)
_SERIES_LOG2 = 0.01 * 0.01  # tan of the half angle 0.01

jit = nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})


@jit
def qmul(a, b):
    """Hamilton product a * b (rotate by b first, then by a)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


@jit
def qconj(q):
    return (-q[0], -q[1], -q[2], q[3])


@jit
def qnormalize(q):
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    if n < _EPS:
        return (0.0, 0.0, 0.0, 1.0)
    inv = 1.0 / n
    return (q[0] * inv, q[1] * inv, q[2] * inv, q[3] * inv)


@jit
def qrotate(q, v):
    """R(q) v without forming the matrix: v + 2w (u x v) + 2 u x (u x v)."""
    ux, uy, uz, w = q
    tx = 2.0 * (uy * v[2] - uz * v[1])
    ty = 2.0 * (uz * v[0] - ux * v[2])
    tz = 2.0 * (ux * v[1] - uy * v[0])
    return (
        v[0] + w * tx + (uy * tz - uz * ty),
        v[1] + w * ty + (uz * tx - ux * tz),
        v[2] + w * tz + (ux * ty - uy * tx),
    )


@jit
def qmat(q):
    """Row-major 3x3 rotation matrix of a unit quaternion, as a 9-tuple."""
    x, y, z, w = q
    return (
        1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w),
        2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w),
        2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y),
    )  # fmt: skip


@jit
def qexp(r):
    """Quaternion of the rotation vector r = axis * angle."""
    a2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2]
    if a2 < 1e-18:
        # Second-order accurate for tiny angles, and avoids 0/0.
        return qnormalize((0.5 * r[0], 0.5 * r[1], 0.5 * r[2], 1.0))
    if a2 < _SERIES_ANGLE2:
        # Per-step turns of particles are small (|w| dt ~ 1e-3 rad): Taylor series of sin(h)/h and
        # cos(h), h = angle / 2, to h^8. The first omitted terms, h^10/11! and h^10/10!, are below
        # 1e-22 for h < 0.03, far under double rounding (1.1e-16), so this is sin/cos up to
        # round-off at a fraction of the cost (no sqrt either).
        h2 = 0.25 * a2
        # Horner form with the reciprocal factorials as constants (a division per term would cost
        # more than the library call).
        sh = 1.0 + h2 * (-1.0 / 6.0 + h2 * (1.0 / 120.0 + h2 * (-1.0 / 5040.0 + h2 * (1.0 / 362880.0))))
        ch = 1.0 + h2 * (-0.5 + h2 * (1.0 / 24.0 + h2 * (-1.0 / 720.0 + h2 * (1.0 / 40320.0))))
        s = 0.5 * sh
        return (r[0] * s, r[1] * s, r[2] * s, ch)
    angle = math.sqrt(a2)
    s = math.sin(0.5 * angle) / angle
    return (r[0] * s, r[1] * s, r[2] * s, math.cos(0.5 * angle))


@jit
def qlog(q):
    """Rotation vector (axis * angle) of q on the short arc, angle in [0, pi]."""
    x, y, z, w = q
    if w < 0.0:  # q and -q are one rotation; w >= 0 is the short arc
        x, y, z, w = -x, -y, -z, -w
    s2 = x * x + y * y + z * z
    if s2 < 1e-18:
        return (2.0 * x, 2.0 * y, 2.0 * z)
    if s2 < _SERIES_LOG2 * w * w:
        # Small turn, t = s / w < 0.01 (w > 0.99 here): atan(t) / t by its Taylor series to t^8;
        # the first omitted term t^10 / 11 is below 1e-21, far under double rounding, so this is
        # atan2(s, w) / s up to round-off without the library call.
        iw = 1.0 / w
        t2 = s2 * iw * iw
        f = 2.0 * iw * (1.0 + t2 * (-1.0 / 3.0 + t2 * (1.0 / 5.0 + t2 * (-1.0 / 7.0 + t2 * (1.0 / 9.0)))))
        return (x * f, y * f, z * f)
    s = math.sqrt(s2)
    f = 2.0 * math.atan2(s, w) / s
    return (x * f, y * f, z * f)


@jit
def mat_to_quat(m):
    """Unit quaternion of a row-major rotation 9-tuple (Shepperd's method)."""
    m00, m01, m02, m10, m11, m12, m20, m21, m22 = m
    tr = m00 + m11 + m22
    if tr > 0.0:
        s = math.sqrt(tr + 1.0) * 2.0
        q = ((m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s, 0.25 * s)
    elif m00 > m11 and m00 > m22:
        s = math.sqrt(1.0 + m00 - m11 - m22) * 2.0
        q = (0.25 * s, (m01 + m10) / s, (m02 + m20) / s, (m21 - m12) / s)
    elif m11 > m22:
        s = math.sqrt(1.0 + m11 - m00 - m22) * 2.0
        q = ((m01 + m10) / s, 0.25 * s, (m12 + m21) / s, (m02 - m20) / s)
    else:
        s = math.sqrt(1.0 + m22 - m00 - m11) * 2.0
        q = ((m02 + m20) / s, (m12 + m21) / s, 0.25 * s, (m10 - m01) / s)
    return qnormalize(q)


@jit
def extract_rotation_t(a, q, max_iterations, tolerance):
    """Rotational part of the row-major 3x3 tuple ``a``, warm-started from quaternion ``q``.

    Mueller, Bender, Chentanez, Macklin 2016, "A Robust Method to Extract the Rotational Part of
    Deformations", Alg. 1 / eq. (8)-(9): q <- exp(omega) q with
    omega = sum_i r_i x a_i / (|sum_i r_i . a_i| + eps), r_i and a_i the columns of R(q) and A.
    Every update is a rotation, so det R = +1 always. The fixed point maximises tr(R^T A) (the
    polar factor when det A > 0); directions that A leaves undetermined (planar, collinear or zero
    A) keep the warm start instead of snapping to identity.
    """
    return extract_rotation_unit_t(a, qnormalize(q), max_iterations, tolerance)


@jit
def extract_rotation_unit_t(a, qq, max_iterations, tolerance):
    """:func:`extract_rotation_t` for a warm start ``qq`` that is already a unit quaternion (the
    solver's group rotations always are): saves the square root and division of normalising it."""
    a00, a01, a02, a10, a11, a12, a20, a21, a22 = a
    tol2 = tolerance * tolerance
    for _ in range(max_iterations):
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = qmat(qq)
        # sum over columns c of r_c x a_c and r_c . a_c
        ox = (r10 * a20 - r20 * a10) + (r11 * a21 - r21 * a11) + (r12 * a22 - r22 * a12)
        oy = (r20 * a00 - r00 * a20) + (r21 * a01 - r01 * a21) + (r22 * a02 - r02 * a22)
        oz = (r00 * a10 - r10 * a00) + (r01 * a11 - r11 * a01) + (r02 * a12 - r12 * a02)
        dot = (r00 * a00 + r10 * a10 + r20 * a20) + (r01 * a01 + r11 * a11 + r21 * a21) + (
            r02 * a02 + r12 * a12 + r22 * a22
        )
        # omega = o / den. The tests on |omega| are made on |o| against den, and the small-angle
        # update below is scale-free, so the common case needs no division: this loop is one
        # serial chain per group solve and its latency is the cost.
        den = abs(dot) + 1e-9
        o2 = ox * ox + oy * oy + oz * oz
        den2 = den * den
        if o2 < tol2 * den2:  # |omega| < tolerance
            break
        if o2 < 0.25 * den2:  # |omega| < 1/2
            # normalise([omega / 2, 1]) turns by 2 atan(|omega| / 2) = |omega| (1 - |omega|^2 / 12 ...):
            # the fixed point (omega = 0) is the same and it needs no sin/cos, which dominate the
            # cost of this loop in the solver. [omega / 2, 1] = [o / 2, den] / den, and a positive
            # factor does not survive the normalisation of the product, so neither it nor the
            # normalisation of the increment itself is applied (same rotation up to round-off).
            qq = qnormalize(qmul((0.5 * ox, 0.5 * oy, 0.5 * oz, den), qq))
        else:
            inv = 1.0 / den
            qq = qnormalize(qmul(qexp((ox * inv, oy * inv, oz * inv)), qq))
    return qq


@jit
def polar_rotation_unit_t(a, qq, max_iterations, tolerance):
    """The polar rotation of the row-major 3x3 tuple ``a`` (det a > 0) to ``tolerance`` [rad], by
    Newton's method on tr(R^T A), warm-started from the unit quaternion ``qq``.

    With R <- exp(omega) R and B = A R^T, tr(R^T A) gains o . omega - omega^T M omega / 2 to
    second order, o = sum_c r_c x a_c (the axial vector of B - B^T) and M = tr(B) I - sym(B), so
    the Newton step is omega = M^-1 o. Mueller et al. 2016 (extract_rotation_unit_t) take
    omega = o / tr(B) instead, which near rest (B ~ I, M ~ 2 I) is 2/3 of the step: their error
    falls by a factor of 3 an iteration, 13 iterations from a 1e-4 rad warm start to 1e-10. Newton's
    falls quadratically: 3 evaluations there. Where M is not positive definite (A far from its
    warm start, or inverted) or the step is longer than 1/2 rad, the iteration takes Mueller's step,
    which always climbs. Stops when the step it would take is below ``tolerance``.
    """
    a00, a01, a02, a10, a11, a12, a20, a21, a22 = a
    tol2 = tolerance * tolerance
    for _ in range(max_iterations):
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = qmat(qq)
        ox = (r10 * a20 - r20 * a10) + (r11 * a21 - r21 * a11) + (r12 * a22 - r22 * a12)
        oy = (r20 * a00 - r00 * a20) + (r21 * a01 - r01 * a21) + (r22 * a02 - r02 * a22)
        oz = (r00 * a10 - r10 * a00) + (r01 * a11 - r11 * a01) + (r02 * a12 - r12 * a02)
        # sym(B), B = A R^T: B_ij = sum_c a_ic r_jc
        b00 = a00 * r00 + a01 * r01 + a02 * r02
        b11 = a10 * r10 + a11 * r11 + a12 * r12
        b22 = a20 * r20 + a21 * r21 + a22 * r22
        s01 = 0.5 * ((a00 * r10 + a01 * r11 + a02 * r12) + (a10 * r00 + a11 * r01 + a12 * r02))
        s02 = 0.5 * ((a00 * r20 + a01 * r21 + a02 * r22) + (a20 * r00 + a21 * r01 + a22 * r02))
        s12 = 0.5 * ((a10 * r20 + a11 * r21 + a12 * r22) + (a20 * r10 + a21 * r11 + a22 * r12))
        tr = b00 + b11 + b22
        m00, m11, m22 = tr - b00, tr - b11, tr - b22
        m01, m02, m12 = -s01, -s02, -s12
        # M^-1 o by cofactors, if M is positive definite (its leading minors)
        c00 = m11 * m22 - m12 * m12
        c01 = m02 * m12 - m01 * m22
        c02 = m01 * m12 - m02 * m11
        det = m00 * c00 + m01 * c01 + m02 * c02
        newton = m00 > 0.0 and m00 * m11 - m01 * m01 > 0.0 and det > 0.0
        if newton:
            c11 = m00 * m22 - m02 * m02
            c12 = m01 * m02 - m00 * m12
            c22 = m00 * m11 - m01 * m01
            inv = 1.0 / det
            wx = (c00 * ox + c01 * oy + c02 * oz) * inv
            wy = (c01 * ox + c11 * oy + c12 * oz) * inv
            wz = (c02 * ox + c12 * oy + c22 * oz) * inv
            w2 = wx * wx + wy * wy + wz * wz
            newton = w2 < 0.25
        if not newton:  # Mueller et al.'s step (extract_rotation_unit_t)
            den = abs(tr) + 1e-9
            wx, wy, wz = ox / den, oy / den, oz / den
            w2 = wx * wx + wy * wy + wz * wz
        if w2 < tol2:
            break
        if w2 < 0.25:
            # normalise([omega / 2, 1]) turns by 2 atan(|omega| / 2) = |omega| (1 - |omega|^2 / 12 ...):
            # a third-order error, below Newton's second-order one
            qq = qnormalize(qmul((0.5 * wx, 0.5 * wy, 0.5 * wz, 1.0), qq))
        else:
            qq = qnormalize(qmul(qexp((wx, wy, wz)), qq))
    return qq


@nb.njit(cache=True)
def extract_rotation(a: np.ndarray, q: np.ndarray, max_iterations: int, tolerance: float) -> np.ndarray:
    """Array front end of :func:`extract_rotation_t`: ``a`` (3, 3), ``q`` (4,) -> quaternion (4,)."""
    t = (a[0, 0], a[0, 1], a[0, 2], a[1, 0], a[1, 1], a[1, 2], a[2, 0], a[2, 1], a[2, 2])
    r = extract_rotation_t(t, (q[0], q[1], q[2], q[3]), max_iterations, tolerance)
    out = np.empty(4)
    out[0] = r[0]
    out[1] = r[1]
    out[2] = r[2]
    out[3] = r[3]
    return out


def polar_rotation_svd(a: np.ndarray) -> np.ndarray:
    """Reference: the proper rotation nearest to ``a`` via SVD (tests only, not the hot loop)."""
    u, _, vt = np.linalg.svd(a)
    d = np.sign(np.linalg.det(u @ vt))
    return u @ np.diag([1.0, 1.0, d]) @ vt


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """R(q) as a (3, 3) array, for Python-side use."""
    x, y, z, w = (float(c) for c in q)
    return np.array(
        [
            [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)],
            [2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)],
            [2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)],
        ]
    )


def matrix_to_quat(m: np.ndarray) -> np.ndarray:
    """Quaternion [x, y, z, w] of a rotation matrix, for Python-side use."""
    return np.array(_mat_to_quat_py(tuple(float(v) for v in np.asarray(m).ravel())))


@nb.njit(cache=True)
def _mat_to_quat_py(m):
    return mat_to_quat(m)
