"""Small dense linear algebra for the tissue kernels (numba, float64, no object mode).

A symmetric 3x3 solve, for the damping of each body's deviation from its rigid motion
(integrate.py) and the group solves (compliant.py), and the inverse built from it.
"""

from __future__ import annotations

import numba as nb


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def solve_sym3(i00, i01, i02, i11, i12, i22, bx, by, bz):
    """x with I x = b for a symmetric 3x3 I, by the adjugate; (0, 0, 0) if I is not positive
    definite (e.g. a degenerate group or body)."""
    c00 = i11 * i22 - i12 * i12
    c01 = i02 * i12 - i01 * i22
    c02 = i01 * i12 - i02 * i11
    c11 = i00 * i22 - i02 * i02
    c12 = i01 * i02 - i00 * i12
    c22 = i00 * i11 - i01 * i01
    det = i00 * c00 + i01 * c01 + i02 * c02
    if det <= 0.0:
        return 0.0, 0.0, 0.0
    inv = 1.0 / det
    return (inv * (c00 * bx + c01 * by + c02 * bz), inv * (c01 * bx + c11 * by + c12 * bz),
            inv * (c02 * bx + c12 * by + c22 * bz))  # fmt: skip


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def inv_sym3(i00, i01, i02, i11, i12, i22):
    """The inverse of a symmetric positive definite 3x3, as (00, 01, 02, 11, 12, 22): its columns
    solved by solve_sym3; zeros if it is not positive definite."""
    a00, a01, a02 = solve_sym3(i00, i01, i02, i11, i12, i22, 1.0, 0.0, 0.0)
    _, a11, a12 = solve_sym3(i00, i01, i02, i11, i12, i22, 0.0, 1.0, 0.0)
    _, _, a22 = solve_sym3(i00, i01, i02, i11, i12, i22, 0.0, 0.0, 1.0)
    return a00, a01, a02, a11, a12, a22
