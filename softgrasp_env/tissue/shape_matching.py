"""Shape matching of implicit groups: the tissue's elasticity (Mueller & Chentanez 2011, "Solid
Simulation with Oriented Particles", sec. 4).

Each particle i is the centre of one group (itself and its neighbours). A group's moment matrix
A = sum_j (A_j + m_j x_j x_bar_j^T) - M c c_bar^T (eq. 10) holds the particles' own moments
A_j = (m_j / 5) R_j diag(a^2, b^2, c^2) R_bar_j^T (eq. 9); its rotation R is extracted with
Mueller et al. 2016 ("A Robust Method to Extract the Rotational Part of Deformations"), warm-started
from the group's last rotation, and every member moves toward its goal g_j = R q_j + c (thesis
eq. 4.8). Orientations follow one of two rules (``orient_mode``, see _shape_match_group). Stiffness
per iteration k' = 1 - (1 - k)^(1/n) (Mueller et al. 2007 sec. 3.3).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from .linalg import solve_sym3
from .model import TissueModel
from .rotation import extract_rotation_t, extract_rotation_unit_t, qmat, qmul, qnormalize

ORIENT_GOAL = 0
ORIENT_REACTION = 1
ORIENT_MODES = {"goal": ORIENT_GOAL, "reaction": ORIENT_REACTION}
_REACTION_SWEEPS = 16  # rotation-extraction sweeps (at most; early exit at 1e-10 rad) in reaction mode


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
def _spin_reaction(start, end, g_mem, qp, i00, i01, i02, i11, i12, i22, lx, ly, lz):
    """Turn every member of a group by dtheta = -I^-1 L, I = sum_j R_j diag(I_j) R_j^T (world, the
    upper triangle i00..i22 summed by the caller), so that the members' spin takes up the orbital
    angular momentum change L of the projection."""
    tx, ty, tz = solve_sym3(i00, i01, i02, i11, i12, i22, -lx, -ly, -lz)
    for e in range(start, end):
        j = g_mem[e]
        q = (qp[j, 0], qp[j, 1], qp[j, 2], qp[j, 3])
        dq = qmul((0.5 * tx, 0.5 * ty, 0.5 * tz, 0.0), q)
        qn = qnormalize((q[0] + dq[0], q[1] + dq[1], q[2] + dq[2], q[3] + dq[3]))
        qp[j, 0] = qn[0]
        qp[j, 1] = qn[1]
        qp[j, 2] = qn[2]
        qp[j, 3] = qn[3]


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _shape_match_group(
    i, k_iter, rot_iters, g_off, g_mem, g_rest, mass, rest_q, rest_moment, inertia, xs, xp, qp, group_q, orient_mode,
    moment,
):  # fmt: skip
    """Project implicit group i (centred on particle i) toward its goal shape.

    Mueller & Chentanez 2011 eq. (10): A = sum_j (A_j + m_j x_j x_bar_j^T) - M c c_bar^T, written
    with rest offsets q_j = x_bar_j - c_bar (sum_j m_j q_j = 0) as sum_j (A_j + m_j x_j q_j^T).
    R = rot(A) (Mueller et al. 2016), goals g_j = R q_j + c (eq. 4.8 of the thesis). Moving every
    member by k (g_j - x_j) keeps sum_j m_j x_j fixed, so linear momentum is conserved exactly.

    Orientation, ``orient_mode``:
    ORIENT_GOAL - the paper (sec. 4.3): only the centre particle turns toward quat(R) q_bar_i.
      The positional projection exerts a torque (A carries the particles' own moments) that no
      spin takes up, so angular momentum leaks: a freely spinning block loses ~10 % in 1000 steps.
    ORIENT_REACTION - every member turns by the same small rotation that takes up the orbital
      angular momentum the projection removed, -I_group^-1 sum_j m_j x_j x dx_j (x_j at step start,
      the positions the velocity update differences against). Orbital plus spin angular momentum
      is then conserved to first order, and the mismatch between particle and group rotation
      decays at rate k per projection (the two are coupled like the ends of one spring)."""
    i = np.uint64(i)
    start = np.uint64(g_off[i])
    end = np.uint64(g_off[i + 1])
    msum = 0.0
    cx = 0.0
    cy = 0.0
    cz = 0.0
    a00 = a01 = a02 = a10 = a11 = a12 = a20 = a21 = a22 = 0.0
    i00 = i01 = i02 = i11 = i12 = i22 = 0.0
    for e in range(start, end):
        j = np.uint64(g_mem[e])
        m = mass[j]
        x0 = xp[j, 0]
        x1 = xp[j, 1]
        x2 = xp[j, 2]
        msum += m
        cx += m * x0
        cy += m * x1
        cz += m * x2
        q0 = g_rest[e, 0]
        q1 = g_rest[e, 1]
        q2 = g_rest[e, 2]
        if orient_mode == ORIENT_GOAL:
            # Only centres turn in this mode, so each particle's moment A_j = R_j B_j (eq. 9) is
            # cached and refreshed when it turns: forming it here would redo it in all of the
            # ~group_size groups the particle belongs to.
            a00 += moment[j, 0] + m * x0 * q0
            a01 += moment[j, 1] + m * x0 * q1
            a02 += moment[j, 2] + m * x0 * q2
            a10 += moment[j, 3] + m * x1 * q0
            a11 += moment[j, 4] + m * x1 * q1
            a12 += moment[j, 5] + m * x1 * q2
            a20 += moment[j, 6] + m * x2 * q0
            a21 += moment[j, 7] + m * x2 * q1
            a22 += moment[j, 8] + m * x2 * q2
            continue
        # Reaction mode turns every member, so a cache would be refreshed as often as it is read:
        # R_j once per member gives both A_j = R_j B_j and the world inertia R_j diag(I_j) R_j^T
        # of the spin reaction (orientations do not change between here and the reaction).
        r0, r1, r2, r3, r4, r5, r6, r7, r8 = qmat((qp[j, 0], qp[j, 1], qp[j, 2], qp[j, 3]))
        b0 = rest_moment[j, 0]
        b1 = rest_moment[j, 1]
        b2 = rest_moment[j, 2]
        b3 = rest_moment[j, 3]
        b4 = rest_moment[j, 4]
        b5 = rest_moment[j, 5]
        b6 = rest_moment[j, 6]
        b7 = rest_moment[j, 7]
        b8 = rest_moment[j, 8]
        a00 += (r0 * b0 + r1 * b3 + r2 * b6) + m * x0 * q0
        a01 += (r0 * b1 + r1 * b4 + r2 * b7) + m * x0 * q1
        a02 += (r0 * b2 + r1 * b5 + r2 * b8) + m * x0 * q2
        a10 += (r3 * b0 + r4 * b3 + r5 * b6) + m * x1 * q0
        a11 += (r3 * b1 + r4 * b4 + r5 * b7) + m * x1 * q1
        a12 += (r3 * b2 + r4 * b5 + r5 * b8) + m * x1 * q2
        a20 += (r6 * b0 + r7 * b3 + r8 * b6) + m * x2 * q0
        a21 += (r6 * b1 + r7 * b4 + r8 * b7) + m * x2 * q1
        a22 += (r6 * b2 + r7 * b5 + r8 * b8) + m * x2 * q2
        d0 = inertia[j, 0]
        d1 = inertia[j, 1]
        d2 = inertia[j, 2]
        i00 += d0 * r0 * r0 + d1 * r1 * r1 + d2 * r2 * r2
        i01 += d0 * r0 * r3 + d1 * r1 * r4 + d2 * r2 * r5
        i02 += d0 * r0 * r6 + d1 * r1 * r7 + d2 * r2 * r8
        i11 += d0 * r3 * r3 + d1 * r4 * r4 + d2 * r5 * r5
        i12 += d0 * r3 * r6 + d1 * r4 * r7 + d2 * r5 * r8
        i22 += d0 * r6 * r6 + d1 * r7 * r7 + d2 * r8 * r8
    cx /= msum
    cy /= msum
    cz /= msum
    qr = extract_rotation_t(
        (a00, a01, a02, a10, a11, a12, a20, a21, a22),
        (group_q[i, 0], group_q[i, 1], group_q[i, 2], group_q[i, 3]),
        rot_iters,
        1e-10,
    )
    group_q[i, 0] = qr[0]
    group_q[i, 1] = qr[1]
    group_q[i, 2] = qr[2]
    group_q[i, 3] = qr[3]
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = qmat(qr)
    lx = ly = lz = 0.0
    for e in range(start, end):
        j = np.uint64(g_mem[e])
        q0 = g_rest[e, 0]
        q1 = g_rest[e, 1]
        q2 = g_rest[e, 2]
        dx = k_iter * (r00 * q0 + r01 * q1 + r02 * q2 + cx - xp[j, 0])
        dy = k_iter * (r10 * q0 + r11 * q1 + r12 * q2 + cy - xp[j, 1])
        dz = k_iter * (r20 * q0 + r21 * q1 + r22 * q2 + cz - xp[j, 2])
        xp[j, 0] += dx
        xp[j, 1] += dy
        xp[j, 2] += dz
        if orient_mode == ORIENT_REACTION:
            # Lever arm from the centre's start position: sum_j m_j dx_j = 0 makes the reference
            # point irrelevant, and a local one keeps the sum free of cancellation.
            m = mass[j]
            ax = xs[j, 0] - xs[i, 0]
            ay = xs[j, 1] - xs[i, 1]
            az = xs[j, 2] - xs[i, 2]
            lx += m * (ay * dz - az * dy)
            ly += m * (az * dx - ax * dz)
            lz += m * (ax * dy - ay * dx)
    if orient_mode == ORIENT_REACTION:
        _spin_reaction(start, end, g_mem, qp, i00, i01, i02, i11, i12, i22, lx, ly, lz)
        return
    _turn_centre(i, qr, k_iter, rest_q, qp, rest_moment, moment)


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _shape_match_group_goal(i, k_iter, rot_iters, g_off, g_mem, g_pack, rest_q, rest_moment, xp, qp, group_q, moment):
    """_shape_match_group for ORIENT_GOAL (the paper's orientation rule), on precomputed rest data
    (see group_pack): c = sum_j (m_j / M) x_j and A = sum_j (A_j + x_j (m_j q_j)^T) (Mueller &
    Chentanez 2011 eq. 10 with sum_j m_j q_j = 0), so no division and no mass product per member.
    The same arithmetic as the general kernel up to round-off."""
    i = np.uint64(i)
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
        # A_j = R_j B_j is cached in `moment` (only centres turn in this mode; see _shape_match_group).
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
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = qmat(qr)
    for e in range(start, end):
        j = np.uint64(g_mem[e])
        q0 = g_pack[e, 4]
        q1 = g_pack[e, 5]
        q2 = g_pack[e, 6]
        xp[j, 0] += k_iter * (r00 * q0 + r01 * q1 + r02 * q2 + cx - xp[j, 0])
        xp[j, 1] += k_iter * (r10 * q0 + r11 * q1 + r12 * q2 + cy - xp[j, 1])
        xp[j, 2] += k_iter * (r20 * q0 + r21 * q1 + r22 * q2 + cz - xp[j, 2])
    _turn_centre(i, qr, k_iter, rest_q, qp, rest_moment, moment)


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def shape_match_sweep(iterations, rot_iters, body_off, body_stiffness, g_off, g_mem, g_rest, g_pack, mass, rest_q,
                      rest_moment, inertia, xs, xp, qp, group_q, orient_mode, moment):  # fmt: skip
    """One Gauss-Seidel sweep over every implicit group, body by body. Stiffness per iteration
    k' = 1 - (1 - k)^(1/n) makes the per-step stiffness independent of the iteration count (Mueller
    et al. 2007 sec. 3.3). A function of its own so the sweep can be timed alone; as fast as the
    same loop written inside _step (measured)."""
    for b in range(body_off.shape[0] - 1):
        k_it = 1.0 - (1.0 - body_stiffness[b]) ** (1.0 / iterations)
        if orient_mode == ORIENT_GOAL:
            for i in range(body_off[b], body_off[b + 1]):
                _shape_match_group_goal(i, k_it, rot_iters, g_off, g_mem, g_pack, rest_q, rest_moment, xp, qp, group_q,
                                        moment)  # fmt: skip
            continue
        for i in range(body_off[b], body_off[b + 1]):
            _shape_match_group(i, k_it, rot_iters, g_off, g_mem, g_rest, mass, rest_q, rest_moment, inertia, xs, xp,
                               qp, group_q, orient_mode, moment)  # fmt: skip


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def rotation_sweeps(rot_iters, orient_mode):
    """Rotation-extraction sweeps per group solve in ``orient_mode``."""
    # The spin reaction is conservative only about the optimal rotation: with an unconverged one its
    # feedback through the particles' moments grows (a free block with random velocities blew up
    # within 1000 steps at 1-2 sweeps, within 4000 at 3). So that mode extracts to convergence.
    return rot_iters if orient_mode == ORIENT_GOAL else max(rot_iters, _REACTION_SWEEPS)
