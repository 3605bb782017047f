"""Shape matching of implicit groups: the tissue's elasticity (Mueller & Chentanez 2011, "Solid
Simulation with Oriented Particles", sec. 4).

Each particle i is the centre of one group (itself and its neighbours). A group's moment matrix
A = sum_j (A_j + m_j x_j x_bar_j^T) - M c c_bar^T (eq. 10) holds the particles' own moments
A_j = (m_j / 5) R_j diag(a^2, b^2, c^2) R_bar_j^T (eq. 9); its rotation R is extracted with
Mueller et al. 2016 ("A Robust Method to Extract the Rotational Part of Deformations"), warm-started
from the group's last rotation, and every member moves toward its goal g_j = R q_j + c (thesis
eq. 4.8). Only the centre particle turns, toward quat(R) q_bar_i (the paper's goal orientation,
sec. 4.3). How far the members move toward their goals is the material's (compliant.py: the
implicit step of a shear modulus in Pa); this module holds the fit and the orientations.

The centre's turn changes its spin with nothing to balance it: a freely spinning block lost 23 %
of its angular momentum in 1,000 steps. So each group is turned back by that spin after the step's
last sweep (balance_torques), and the particles' spin is carried as angular momentum
(integrate.update_velocities). (An earlier
'reaction' rule turned every member by the spin that takes up the torque: it conserved angular
momentum only to first order, and with spinning particles and no damping its energy grew 10-fold
in 1,000 steps; it was removed.)
"""

from __future__ import annotations

import numba as nb
import numpy as np

from .jit import KERNEL
from .model import TissueModel
from .rotation import extract_rotation_unit_t, qconj, qlog, qmat, qmul, qnormalize, qrotate


def rest_moments(model: TissueModel) -> np.ndarray:
    """(N, 9) row-major B_i = (m_i / 5) diag(a^2, b^2, c^2) R_bar_i^T of every particle.

    A particle's moment A_i = (m_i / 5) R_i diag(a^2, b^2, c^2) R_bar_i^T (Mueller & Chentanez 2011,
    eq. 9) is then R_i B_i, R_i the current and R_bar_i the rest orientation (the symmetric
    R D R^T would carry no rotation and pull groups toward 'no rotation')."""
    from .rotation import quat_to_matrix

    n = model.particle_count
    out = np.empty((n, 9))
    for i in range(n):
        rb = quat_to_matrix(model.particle_rest_q[i])
        d = model.particle_mass[i] / 5.0 * model.particle_radii[i] ** 2
        out[i] = (d[:, None] * rb.T).ravel()
    return out


def group_pack(model: TissueModel) -> np.ndarray:
    """(G, 12) per group entry e (member j of group i): [m_j / M_i, m_j q_e (3), q_e (3), 1 / m_j,
    b_e (3), 0], with q_e = x_bar_j - c_bar_i the rest offset, M_i the group's mass and, for a
    continuum group (model.group_continuum), b_e = A_qq^-1 m_j q_e its member's column of F
    (compliant.continuum_groups; 0 elsewhere). These are the rest-state factors of Mueller &
    Chentanez 2011 eq. (10) and of the continuum energy, constant over a run: precomputed once,
    each member's row read in one pass instead of recomputed in each of the group solve's."""
    g_mem = model.group_members.astype(np.int64)
    m = model.particle_mass[g_mem]
    sizes = np.diff(model.group_offsets.astype(np.int64))
    msum = np.add.reduceat(m, model.group_offsets[:-1].astype(np.int64)) if m.size else np.zeros(0)
    out = np.zeros((g_mem.shape[0], GROUP_PACK_COLUMNS))
    out[:, 0] = m / np.repeat(msum, sizes)
    out[:, 1:4] = m[:, None] * model.group_rest_offset
    out[:, 4:7] = model.group_rest_offset
    out[:, 7] = 1.0 / m
    _fill_columns(model.group_offsets, model.group_continuum, out)
    return out


GROUP_PACK_COLUMNS = 12
"""group_pack's columns (a 96-byte row)."""


@nb.njit(**KERNEL)
def _fill_columns(g_off, g_cont, pack):
    """b_e = A_qq^-1 (m_j q_e) of each continuum group's members into pack[:, 8:11], by the very
    expression the group solve used to evaluate per pass (same operations, same contraction), so
    the solve's numbers do not change."""
    for i in range(g_off.shape[0] - 1):
        if g_cont[i, 6] <= 0.0:  # not a continuum group
            continue
        p00, p01, p02, p11, p12, p22 = g_cont[i, 0], g_cont[i, 1], g_cont[i, 2], g_cont[i, 3], g_cont[i, 4], g_cont[i, 5]
        for e in range(g_off[i], g_off[i + 1]):
            q0 = pack[e, 1]
            q1 = pack[e, 2]
            q2 = pack[e, 3]
            pack[e, 8] = p00 * q0 + p01 * q1 + p02 * q2
            pack[e, 9] = p01 * q0 + p11 * q1 + p12 * q2
            pack[e, 10] = p02 * q0 + p12 * q1 + p22 * q2


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def refresh_moment(i, q, rest_moment, moment):
    """moment[i] = R(q) B_i: particle i's A_i (Mueller & Chentanez 2011 eq. 9), row-major."""
    r = qmat(q)
    for a in range(3):
        for b in range(3):
            moment[i, 3 * a + b] = (
                r[3 * a] * rest_moment[i, b] + r[3 * a + 1] * rest_moment[i, 3 + b] + r[3 * a + 2] * rest_moment[i, 6 + b]
            )


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _turn_centre(i, qr, k_iter, rest_q, qp, rest_moment, moment):
    """Goal orientation of an implicit group (DESIGN.md; Mueller & Chentanez 2011 sec. 4): only
    the centre particle turns toward quat(R) q_bar_i, by the same stiffness, on the short arc
    (nlerp: no transcendental functions in the innermost loop)."""
    goal = qmul(qr, (rest_q[i, 0], rest_q[i, 1], rest_q[i, 2], rest_q[i, 3]))
    sgn = 1.0
    if goal[0] * qp[i, 0] + goal[1] * qp[i, 1] + goal[2] * qp[i, 2] + goal[3] * qp[i, 3] < 0.0:
        sgn = -1.0
    qn = qnormalize((
        qp[i, 0] + k_iter * (sgn * goal[0] - qp[i, 0]),
        qp[i, 1] + k_iter * (sgn * goal[1] - qp[i, 1]),
        qp[i, 2] + k_iter * (sgn * goal[2] - qp[i, 2]),
        qp[i, 3] + k_iter * (sgn * goal[3] - qp[i, 3]),
    ))  # fmt: skip
    qp[i, 0] = qn[0]
    qp[i, 1] = qn[1]
    qp[i, 2] = qn[2]
    qp[i, 3] = qn[3]
    refresh_moment(i, qn, rest_moment, moment)


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _spin_gained(i, q_pred, qp, inertia, spin_kick):
    """The step's turns of particle i (it turns only as the centre of its own group) as an angular
    impulse times dt: I_w dtheta, dtheta = log(q q_pred^-1), I_w its world inertia now. Stored in
    ``spin_kick[i]`` for the spin update (integrate.update_velocities) and returned for the group's
    torque balance: the same number in both, so the two agree exactly."""
    qn = (qp[i, 0], qp[i, 1], qp[i, 2], qp[i, 3])
    th = qlog(qmul(qn, qconj((q_pred[i, 0], q_pred[i, 1], q_pred[i, 2], q_pred[i, 3]))))
    ul = qrotate(qconj(qn), th)
    kick = qrotate(qn, (inertia[i, 0] * ul[0], inertia[i, 1] * ul[1], inertia[i, 2] * ul[2]))
    spin_kick[i, 0] = kick[0]
    spin_kick[i, 1] = kick[1]
    spin_kick[i, 2] = kick[2]
    return kick


@nb.njit(**KERNEL)
def group_frames(g_off, g_mem, mass, xs, frame):
    """What each group's torque balance needs from the step's start positions xs, once per step
    (they do not change over the iterations): frame[i] = [cs (3), I^-1 (6: xx, xy, xz, yy, yz,
    zz), M], the group's centre of mass at the start, the inverse of its inertia about it (0 if
    singular: a degenerate group gets no balance) and its mass."""
    group_frames_of(0, g_off.shape[0] - 1, g_off, g_mem, mass, xs, frame)


@nb.njit(**KERNEL)
def group_frames_of(lo, hi, g_off, g_mem, mass, xs, frame):
    """group_frames over groups lo .. hi - 1."""
    for i in range(lo, hi):
        # unsigned indices: no negative-index wraparound per access
        i = np.uint64(i)
        start = np.uint64(g_off[i])
        end = np.uint64(g_off[i + 1])
        # moments about the centre particle's start position (small numbers: no cancellation)
        ox, oy, oz = xs[i, 0], xs[i, 1], xs[i, 2]
        msum = sx = sy = sz = 0.0
        s00 = s01 = s02 = s11 = s12 = s22 = 0.0
        for e in range(start, end):
            j = np.uint64(g_mem[e])
            m = mass[j]
            rx = xs[j, 0] - ox
            ry = xs[j, 1] - oy
            rz = xs[j, 2] - oz
            msum += m
            sx += m * rx
            sy += m * ry
            sz += m * rz
            s00 += m * rx * rx
            s01 += m * rx * ry
            s02 += m * rx * rz
            s11 += m * ry * ry
            s12 += m * ry * rz
            s22 += m * rz * rz
        inv_m = 1.0 / msum
        cx = sx * inv_m
        cy = sy * inv_m
        cz = sz * inv_m
        s00 -= sx * cx
        s01 -= sx * cy
        s02 -= sx * cz
        s11 -= sy * cy
        s12 -= sy * cz
        s22 -= sz * cz
        # I = sum m (r^2 1 - r r^T) about the centre of mass; inverse by the adjugate
        i00 = s11 + s22
        i11 = s00 + s22
        i22 = s00 + s11
        c00 = i11 * i22 - s12 * s12
        c01 = s02 * s12 + s01 * i22
        c02 = s01 * s12 + s02 * i11
        c11 = i00 * i22 - s02 * s02
        c12 = i00 * s12 + s01 * s02
        c22 = i00 * i11 - s01 * s01
        det = i00 * c00 - s01 * c01 - s02 * c02
        inv = 1.0 / det if det > 1e-300 else 0.0
        frame[i, 0] = ox + cx
        frame[i, 1] = oy + cy
        frame[i, 2] = oz + cz
        frame[i, 3] = inv * c00
        frame[i, 4] = inv * c01
        frame[i, 5] = inv * c02
        frame[i, 6] = inv * c11
        frame[i, 7] = inv * c12
        frame[i, 8] = inv * c22
        frame[i, 9] = msum


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _fit_group(i, rot_iters, g_off, g_mem, g_pack, xp, group_q, moment):
    """Group i's rigid fit to the predicted positions (Mueller & Chentanez 2011 eq. 10,
    A = sum_j (A_j + m_j x_j x_bar_j^T) - M c c_bar^T, written with rest offsets
    q_j = x_bar_j - c_bar, sum_j m_j q_j = 0, as c = sum_j (m_j / M) x_j and
    A = sum_j (A_j + x_j (m_j q_j)^T): no division and no mass product per member): its centre of
    mass c and rotation R = rot(A) (Mueller et al. 2016), warm-started from and stored in
    ``group_q[i]``. Returns (quat(R), c)."""
    start = np.uint64(g_off[i])
    end = np.uint64(g_off[i + 1])
    cx = 0.0
    cy = 0.0
    cz = 0.0
    a00 = a01 = a02 = a10 = a11 = a12 = a20 = a21 = a22 = 0.0
    for e in range(start, end):
        j = np.uint64(g_mem[e])
        x0 = xp[j, 0]
        x1 = xp[j, 1]
        x2 = xp[j, 2]
        w = g_pack[e, 0]
        q0 = g_pack[e, 1]
        q1 = g_pack[e, 2]
        q2 = g_pack[e, 3]
        cx += w * x0
        cy += w * x1
        cz += w * x2
        # A_j = R_j B_j is cached in `moment`, refreshed whenever a particle turns: forming it here
        # would redo it in all of the ~group_size groups the particle belongs to.
        a00 += moment[j, 0] + x0 * q0
        a01 += moment[j, 1] + x0 * q1
        a02 += moment[j, 2] + x0 * q2
        a10 += moment[j, 3] + x1 * q0
        a11 += moment[j, 4] + x1 * q1
        a12 += moment[j, 5] + x1 * q2
        a20 += moment[j, 6] + x2 * q0
        a21 += moment[j, 7] + x2 * q1
        a22 += moment[j, 8] + x2 * q2
    qr = extract_rotation_unit_t(  # group_q is kept unit (predict and every solve normalise it)
        (a00, a01, a02, a10, a11, a12, a20, a21, a22),
        (group_q[i, 0], group_q[i, 1], group_q[i, 2], group_q[i, 3]),
        rot_iters,
        1e-10,
    )
    group_q[i, 0] = qr[0]
    group_q[i, 1] = qr[1]
    group_q[i, 2] = qr[2]
    group_q[i, 3] = qr[3]
    return qr, cx, cy, cz


@nb.njit(**KERNEL)
def balance_torques(g_off, g_mem, frame, attached, fixed, inertia, xs, xp, qp, q_pred, spin_kick):
    """After the step's last sweep: give each group's centre the spin of its turns (_spin_gained)
    and turn the group back by dth = I^-1 T, T that spin (I the group's inertia about cs, frame):
    x_j -= dth x r_j, r_j = xs_j - cs. The groups' own passes are free of torque already
    (compliant._apply_deformation); the centre's turn is not, and nothing else balances it. One
    turn by the step's summed spin is the sum of the turns of each iteration: the lever arms r_j do
    not change over the step. A group with a member held by its core (``fixed``) is left: the core
    takes its torque through that member."""
    balance_torques_of(0, g_off.shape[0] - 1, g_off, g_mem, frame, attached, fixed, inertia, xs, xp, qp, q_pred,
                       spin_kick)  # fmt: skip


@nb.njit(**KERNEL)
def balance_torques_of(lo, hi, g_off, g_mem, frame, attached, fixed, inertia, xs, xp, qp, q_pred, spin_kick):
    """balance_torques over groups lo .. hi - 1."""
    for i in range(lo, hi):
        i = np.uint64(i)  # unsigned indices: no negative-index wraparound per access
        held = False
        for e in range(np.uint64(g_off[i]), np.uint64(g_off[i + 1])):
            held = held or fixed[np.uint64(g_mem[e])]
        if held:
            continue
        tx = ty = tz = 0.0
        if not attached[i]:
            kx, ky, kz = _spin_gained(i, q_pred, qp, inertia, spin_kick)
            tx += kx
            ty += ky
            tz += kz
        wx = frame[i, 3] * tx + frame[i, 4] * ty + frame[i, 5] * tz
        wy = frame[i, 4] * tx + frame[i, 6] * ty + frame[i, 7] * tz
        wz = frame[i, 5] * tx + frame[i, 7] * ty + frame[i, 8] * tz
        csx, csy, csz = frame[i, 0], frame[i, 1], frame[i, 2]
        for e in range(np.uint64(g_off[i]), np.uint64(g_off[i + 1])):
            j = np.uint64(g_mem[e])
            rx = xs[j, 0] - csx
            ry = xs[j, 1] - csy
            rz = xs[j, 2] - csz
            xp[j, 0] -= wy * rz - wz * ry
            xp[j, 1] -= wz * rx - wx * rz
            xp[j, 2] -= wx * ry - wy * rx
