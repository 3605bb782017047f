"""Shape matching of implicit groups: the tissue's elasticity (Mueller & Chentanez 2011, "Solid
Simulation with Oriented Particles", sec. 4).

Each particle i is the centre of one group (itself and its neighbours). A group's moment matrix
A = sum_j (A_j + m_j x_j x_bar_j^T) - M c c_bar^T (eq. 10) holds the particles' own moments
A_j = (m_j / 5) R_j diag(a^2, b^2, c^2) R_bar_j^T (eq. 9); its rotation R is extracted with
Mueller et al. 2016 ("A Robust Method to Extract the Rotational Part of Deformations"), warm-started
from the group's last rotation, and every member moves toward its goal g_j = R q_j + c (thesis
eq. 4.8). Only the centre particle turns, toward quat(R) q_bar_i (the paper's goal orientation,
sec. 4.3). Stiffness per iteration k' = 1 - (1 - k)^(1/n) (Mueller et al. 2007 sec. 3.3).

The projection exerts a torque (A carries the particles' own moments) that the goal orientation
takes up nowhere: a freely spinning block lost 23 % of its angular momentum in 1,000 steps. So
each group's corrections of a step are made torque-free (_shape_match_group, balance_torques),
and the particles' spin is carried as angular momentum (integrate.update_velocities). (An earlier
'reaction' rule turned every member by the spin that takes up the torque: it conserved angular
momentum only to first order, and with spinning particles and no damping its energy grew 10-fold
in 1,000 steps; it was removed.)
"""

from __future__ import annotations

import numba as nb
import numpy as np

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
    """(G, 8) per group entry e (member j of group i): [m_j / M_i, m_j q_e (3), q_e (3), 0], with
    q_e = x_bar_j - c_bar_i the rest offset and M_i the group's mass. These are the rest-state
    factors of Mueller & Chentanez 2011 eq. (10), constant over a run: precomputed once, and one
    64-byte row per entry, the group solve reads one cache line per member instead of three."""
    g_mem = model.group_members.astype(np.int64)
    m = model.particle_mass[g_mem]
    sizes = np.diff(model.group_offsets.astype(np.int64))
    msum = np.add.reduceat(m, model.group_offsets[:-1].astype(np.int64)) if m.size else np.zeros(0)
    out = np.zeros((g_mem.shape[0], 8))
    out[:, 0] = m / np.repeat(msum, sizes)
    out[:, 1:4] = m[:, None] * model.group_rest_offset
    out[:, 4:7] = model.group_rest_offset
    return out


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


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def group_frames(g_off, g_mem, mass, xs, frame, torque):
    """What each group's torque balance needs from the step's start positions xs, once per step
    (they do not change over the iterations): frame[i] = [cs (3), I^-1 (6: xx, xy, xz, yy, yz,
    zz), M], the group's centre of mass at the start, the inverse of its inertia about it (0 if
    singular: a degenerate group gets no balance) and its mass. Clears the groups' torque sums."""
    for i in range(g_off.shape[0] - 1):
        # unsigned indices: no negative-index wraparound per access (as in _shape_match_group)
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
        torque[i, 0] = 0.0
        torque[i, 1] = 0.0
        torque[i, 2] = 0.0


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _fit_group(i, rot_iters, g_off, g_mem, g_pack, xp, group_q, moment):
    """Group i's rigid fit to the predicted positions (Mueller & Chentanez 2011 eq. 10, see
    _shape_match_group): its centre of mass c and rotation R = rot(A), warm-started from and
    stored in ``group_q[i]``. Returns (quat(R), c). Shared by both materials."""
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


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _shape_match_group(i, k_iter, rot_iters, g_off, g_mem, g_pack, frame, torque, xs, xp, group_q, moment):
    """Project implicit group i (centred on particle i) toward its goal shape, on precomputed rest
    data (see group_pack), without a net torque over the step.

    Mueller & Chentanez 2011 eq. (10): A = sum_j (A_j + m_j x_j x_bar_j^T) - M c c_bar^T, written
    with rest offsets q_j = x_bar_j - c_bar (sum_j m_j q_j = 0) as c = sum_j (m_j / M) x_j and
    A = sum_j (A_j + x_j (m_j q_j)^T), so no division and no mass product per member. R = rot(A)
    (Mueller et al. 2016), goals g_j = R q_j + c (eq. 4.8 of the thesis), corrections
    dx_j = k (g_j - x_j); sum_j m_j dx_j = 0, so linear momentum is kept exactly. The centre turns
    toward quat(R) q_bar_i (_turn_centre, called by the sweep with the R returned).

    Internal forces must not turn a body, but these corrections do: A carries the particles' own
    moments, so R is not the rotation that fits the positions alone, and the centre's turn changes
    its spin with nothing to balance it. A free block lost 23 % of its angular momentum in 1,000
    steps, and a block resting on the ground kept turning. So the step's corrections of each group
    are made torque-free: its torque T = sum_j m_j r_j x dx_j (r_j = xs_j - cs about the group's
    centre of mass at the step's start) is summed over the iterations, and after the last one
    balance_torques adds the centre's spin change and turns the group back. Position-based dynamics differences positions against the step's
    start, v = (x - xs) / dt, so the angular momentum a step leaves is sum m xs x v, and torque-free
    about xs is what conserves it."""
    i = np.uint64(i)
    start = np.uint64(g_off[i])
    end = np.uint64(g_off[i + 1])
    qr, cx, cy, cz = _fit_group(i, rot_iters, g_off, g_mem, g_pack, xp, group_q, moment)
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = qmat(qr)
    csx, csy, csz = frame[i, 0], frame[i, 1], frame[i, 2]
    tx = ty = tz = 0.0  # sum_j (m_j / M) r_j x dx_j
    for e in range(start, end):
        j = np.uint64(g_mem[e])
        q0 = g_pack[e, 4]
        q1 = g_pack[e, 5]
        q2 = g_pack[e, 6]
        dx = k_iter * (r00 * q0 + r01 * q1 + r02 * q2 + cx - xp[j, 0])
        dy = k_iter * (r10 * q0 + r11 * q1 + r12 * q2 + cy - xp[j, 1])
        dz = k_iter * (r20 * q0 + r21 * q1 + r22 * q2 + cz - xp[j, 2])
        xp[j, 0] += dx
        xp[j, 1] += dy
        xp[j, 2] += dz
        w = g_pack[e, 0]
        rx = xs[j, 0] - csx
        ry = xs[j, 1] - csy
        rz = xs[j, 2] - csz
        tx += w * (ry * dz - rz * dy)
        ty += w * (rz * dx - rx * dz)
        tz += w * (rx * dy - ry * dx)
    msum = frame[i, 9]
    tx = torque[i, 0] + msum * tx
    ty = torque[i, 1] + msum * ty
    tz = torque[i, 2] + msum * tz
    torque[i, 0] = tx
    torque[i, 1] = ty
    torque[i, 2] = tz
    return qr


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def shape_match_sweep(iterations, rot_iters, body_off, body_stiffness, body_compliant, g_off, g_mem, g_pack, frame, torque,
                      attached, rest_q, rest_moment, xs, xp, qp, group_q, moment):  # fmt: skip
    """One Gauss-Seidel sweep over the implicit groups of every per-step body (the compliant ones:
    compliant.compliant_sweep), body by body. Stiffness per iteration
    k' = 1 - (1 - k)^(1/n) makes the per-step stiffness independent of the iteration count (Mueller
    et al. 2007 sec. 3.3). A function of its own so the sweep can be timed alone; as fast as the
    same loop written inside _step (measured)."""
    for b in range(body_off.shape[0] - 1):
        if body_compliant[b]:
            continue  # compliant.compliant_sweep
        k_it = 1.0 - (1.0 - body_stiffness[b]) ** (1.0 / iterations)
        for i in range(body_off[b], body_off[b + 1]):
            qr = _shape_match_group(i, k_it, rot_iters, g_off, g_mem, g_pack, frame, torque, xs, xp, group_q, moment)
            if not attached[i]:
                # An attached centre is tied to its core and keeps the core's orientation (the snap
                # sets it so after the solve anyway); only the tissue's own particles turn.
                _turn_centre(i, qr, k_it, rest_q, qp, rest_moment, moment)


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def balance_torques(g_off, g_mem, frame, torque, attached, fixed, inertia, xs, xp, qp, q_pred, spin_kick):
    """After the step's last sweep: give each group's centre the spin of its turns (_spin_gained)
    and turn each group back by dth = I^-1 T, T its summed torque plus that spin (I its inertia
    about cs, frame): x_j -= dth x r_j, r_j = xs_j - cs. Then every group's corrections of the step
    together exert no torque (_shape_match_group). One turn by the summed torque is the sum of the
    turns of each iteration: the lever arms r_j do not change over the step. (In the sweep itself,
    this branch made every sweep 50 % slower.) A group with a member held by its core (``fixed``,
    the compliant material) is left: the core takes its torque through that member; the compliant
    groups' own passes are free of torque already (compliant._apply_deformation), so for them
    only the centre's spin is balanced here."""
    for i in range(g_off.shape[0] - 1):
        i = np.uint64(i)  # unsigned indices: no negative-index wraparound per access
        held = False
        for e in range(np.uint64(g_off[i]), np.uint64(g_off[i + 1])):
            held = held or fixed[np.uint64(g_mem[e])]
        if held:
            continue
        tx, ty, tz = torque[i, 0], torque[i, 1], torque[i, 2]
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
