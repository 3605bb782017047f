"""The oriented-particle solver: one tissue step against a set of rigid colliders.

One step, in the order of the thesis (5.2.2) and of position-based dynamics (Mueller et al. 2007,
Alg. 1), reads as a recipe (see :func:`_step`):

    predict(particles, rigid bodies, dt)          # gravity, damping, x* = x + v dt, q* = exp(w dt) q
    collect contact candidates                    # particle-shape, inner (own core), particle-particle
    for _ in range(iterations):                   # Gauss-Seidel
        shape-match every implicit group          # Mueller & Chentanez 2011 sec. 4
        project contacts (two-way, mass-weighted) # XPBD rigid bodies, Mueller et al. 2020 sec. 3.3
        friction on every touched contact         # position level, Macklin et al. 2014 eq. 23-24
        [consistent coupling: project anchors]    # generalised inverse mass of the core
    couple: anchor error -> impulse on the core, snap attached particles back   # thesis 5.1.3
    update velocities from positions, angular velocities from q* q^-1 (short arc)

Rigid bodies live in pybullet; the solver sees them as read-only inputs (pose at step start,
velocities, mass properties) and returns their predicted poses and the impulses the tissue put on
them. Nothing here imports pybullet or gymnasium.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np

from ..config import SimConfig
from .collision import SHAPE_BOX, SHAPE_CYLINDER, SHAPE_PLANE, SHAPE_SPHERE, shape_distance, support_radius
from .model import TissueModel
from .rotation import extract_rotation_t, extract_rotation_unit_t, qconj, qexp, qlog, qmat, qmul, qnormalize, qrotate
from .state import TissueState

COUPLING_THESIS = 0
COUPLING_CONSISTENT = 1
ORIENT_GOAL = 0
ORIENT_REACTION = 1
ORIENT_MODES = {"goal": ORIENT_GOAL, "reaction": ORIENT_REACTION}
_REACTION_SWEEPS = 16  # rotation-extraction sweeps (at most; early exit at 1e-10 rad) in reaction mode

# Contacts: one row per (particle, shape) candidate; `inner` rows are a particle against its own
# core (thesis 5.1.2 inner collisions: centre must stay outside, no friction).
_NO_RIGID = -1


@dataclass(eq=False)
class Colliders:
    """Rigid bodies and their collision shapes as the tissue sees them (struct of arrays).

    Rigid body poses are centre-of-mass frames; a shape's local pose is relative to its body's
    centre-of-mass frame, or to the world when ``shape_rigid`` is -1 (static geometry).
    """

    rigid_x: np.ndarray
    """(R, 3) centre of mass at step start [m]."""
    rigid_q: np.ndarray
    """(R, 4) orientation at step start [x, y, z, w]."""
    rigid_v: np.ndarray
    """(R, 3) linear velocity [m/s]."""
    rigid_w: np.ndarray
    """(R, 3) angular velocity [rad/s]."""
    rigid_inv_mass: np.ndarray
    """(R,) 1/mass [1/kg]; 0 for static or kinematic bodies."""
    rigid_inv_inertia: np.ndarray
    """(R, 3) inverse principal moments in the centre-of-mass frame [1/(kg m^2)]."""
    rigid_gravity: np.ndarray
    """(R,) bool: predicted under gravity (free bodies); False for bodies held by joints."""
    rigid_in_solve: np.ndarray
    """(R,) bool: takes its mass-weighted share of corrections inside the solve. False treats it
    as infinitely heavy while solving; its impulses are still collected (thesis 5.1.3)."""
    shape_kind: np.ndarray
    """(S,) int32 shape code (see collision.py)."""
    shape_params: np.ndarray
    """(S, 3) shape dimensions [m]."""
    shape_rigid: np.ndarray
    """(S,) int32 owning rigid body, -1 for static world geometry."""
    shape_local_x: np.ndarray
    """(S, 3) shape origin in its body's frame (world frame for static shapes) [m]."""
    shape_local_q: np.ndarray
    """(S, 4) shape orientation in its body's frame."""

    @property
    def rigid_count(self) -> int:
        return int(self.rigid_inv_mass.shape[0])

    @property
    def shape_count(self) -> int:
        return int(self.shape_kind.shape[0])


@dataclass(eq=False)
class StepOutput:
    """What one tissue step hands back to the rigid-body simulation."""

    rigid_pred_x: np.ndarray
    """(R, 3) predicted centre of mass after the solve [m]."""
    rigid_pred_q: np.ndarray
    """(R, 4) predicted orientation after the solve."""
    rigid_impulse: np.ndarray
    """(R, 3) linear impulse the tissue put on each rigid body this step [N s]."""
    rigid_angular_impulse: np.ndarray
    """(R, 3) angular impulse about the predicted centre of mass [N m s]."""
    coupling_impulse: np.ndarray
    """(R, 3) the part of ``rigid_impulse`` from the core attachment (thesis 5.1.3) [N s]."""
    contact_count: int
    pair_count: int


# =================================================================================================
# numba kernels
# =================================================================================================


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _rigid_point_world(rx, rq, p_local):
    r = qrotate(rq, p_local)
    return (rx[0] + r[0], rx[1] + r[1], rx[2] + r[2])


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _shape_pose(s, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q):
    """World pose (x, q) of shape s given the current rigid poses."""
    lx = (shape_local_x[s, 0], shape_local_x[s, 1], shape_local_x[s, 2])
    lq = (shape_local_q[s, 0], shape_local_q[s, 1], shape_local_q[s, 2], shape_local_q[s, 3])
    r = shape_rigid[s]
    if r < 0:
        return lx, lq
    bx = (rig_x[r, 0], rig_x[r, 1], rig_x[r, 2])
    bq = (rig_q[r, 0], rig_q[r, 1], rig_q[r, 2], rig_q[r, 3])
    return _rigid_point_world(bx, bq, lx), qmul(bq, lq)


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _shape_query(s, p, shape_kind, shape_params, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q):
    """Signed distance of world point p from shape s and the world outward normal."""
    sx, sq = _shape_pose(s, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q)
    d = (p[0] - sx[0], p[1] - sx[1], p[2] - sx[2])
    pl = qrotate(qconj(sq), d)
    dist, nx, ny, nz = shape_distance(shape_kind[s], (shape_params[s, 0], shape_params[s, 1], shape_params[s, 2]), pl)
    n = qrotate(sq, (nx, ny, nz))
    return dist, n


# Slack [m] added to bounding radii so that rounding can never reject a true candidate.
_BOUND_SLACK = 1e-9


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _bounding_radius(kind, p0, p1, p2):
    """Radius of a sphere about the shape origin that holds the whole shape (inf for the plane)."""
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
def _shape_poses(shape_kind, shape_params, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q, pose):
    """pose[s] = world position (0:3), orientation (3:7) and bounding radius (7) of every shape, once
    per pass over all particles instead of once per particle (same expressions as _shape_query)."""
    for s in range(shape_kind.shape[0]):
        sx, sq = _shape_pose(s, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q)
        for a in range(3):
            pose[s, a] = sx[a]
        for a in range(4):
            pose[s, 3 + a] = sq[a]
        pose[s, 7] = _bounding_radius(shape_kind[s], shape_params[s, 0], shape_params[s, 1], shape_params[s, 2])
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
def _shape_query_at(s, p, shape_kind, shape_params, pose):
    """_shape_query with the shape's world pose taken from ``pose`` (see _shape_poses)."""
    sx = (pose[s, 0], pose[s, 1], pose[s, 2])
    sq = (pose[s, 3], pose[s, 4], pose[s, 5], pose[s, 6])
    d = (p[0] - sx[0], p[1] - sx[1], p[2] - sx[2])
    pl = qrotate(qconj(sq), d)
    dist, nx, ny, nz = shape_distance(shape_kind[s], (shape_params[s, 0], shape_params[s, 1], shape_params[s, 2]), pl)
    n = qrotate(sq, (nx, ny, nz))
    return dist, n


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _generalized_inv_mass(r, rig_q, rig_inv_mass, rig_inv_inertia, rx, ry, rz, nx, ny, nz):
    """w = 1/m + (r x n)^T I_w^-1 (r x n) of rigid body r at lever arm (rx, ry, rz) along n
    (Mueller et al. 2020, eq. 2-3)."""
    cx = ry * nz - rz * ny
    cy = rz * nx - rx * nz
    cz = rx * ny - ry * nx
    q = (rig_q[r, 0], rig_q[r, 1], rig_q[r, 2], rig_q[r, 3])
    u = qrotate(qconj(q), (cx, cy, cz))
    return (
        rig_inv_mass[r]
        + rig_inv_inertia[r, 0] * u[0] * u[0]
        + rig_inv_inertia[r, 1] * u[1] * u[1]
        + rig_inv_inertia[r, 2] * u[2] * u[2]
    )


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _rigid_apply(r, rx, ry, rz, px, py, pz, move, dt, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, imp_lin, imp_ang):
    """Apply positional impulse P (kg m) at lever arm r to rigid body r: record P/dt and r x P/dt
    as the impulse on it, and, if it moves inside the solve, update its predicted pose
    (Mueller et al. 2020, eq. 6-9)."""
    lx = ry * pz - rz * py
    ly = rz * px - rx * pz
    lz = rx * py - ry * px
    imp_lin[r, 0] += px / dt
    imp_lin[r, 1] += py / dt
    imp_lin[r, 2] += pz / dt
    imp_ang[r, 0] += lx / dt
    imp_ang[r, 1] += ly / dt
    imp_ang[r, 2] += lz / dt
    if not move:
        return
    im = rig_inv_mass[r]
    rig_x[r, 0] += im * px
    rig_x[r, 1] += im * py
    rig_x[r, 2] += im * pz
    q = (rig_q[r, 0], rig_q[r, 1], rig_q[r, 2], rig_q[r, 3])
    ul = qrotate(qconj(q), (lx, ly, lz))
    dth = qrotate(q, (rig_inv_inertia[r, 0] * ul[0], rig_inv_inertia[r, 1] * ul[1], rig_inv_inertia[r, 2] * ul[2]))
    dq = qmul((0.5 * dth[0], 0.5 * dth[1], 0.5 * dth[2], 0.0), q)
    qn = qnormalize((q[0] + dq[0], q[1] + dq[1], q[2] + dq[2], q[3] + dq[3]))
    rig_q[r, 0] = qn[0]
    rig_q[r, 1] = qn[1]
    rig_q[r, 2] = qn[2]
    rig_q[r, 3] = qn[3]


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
    _refresh_moment(i, qn, rest_moment, moment)


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
def _shape_match_sweep(iterations, rot_iters, body_off, body_stiffness, g_off, g_mem, g_rest, g_pack, mass, rest_q,
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
def _refresh_moment(i, q, rest_moment, moment):
    """moment[i] = R(q) B_i: particle i's A_i (Mueller & Chentanez 2011 eq. 9), row-major."""
    r = qmat(q)
    for a in range(3):
        for b in range(3):
            moment[i, 3 * a + b] = (
                r[3 * a] * rest_moment[i, b] + r[3 * a + 1] * rest_moment[i, 3 + b] + r[3 * a + 2] * rest_moment[i, 6 + b]
            )


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _solve_sym3(i00, i01, i02, i11, i12, i22, bx, by, bz):
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
def _spin_reaction(start, end, g_mem, qp, i00, i01, i02, i11, i12, i22, lx, ly, lz):
    """Turn every member of a group by dtheta = -I^-1 L, I = sum_j R_j diag(I_j) R_j^T (world, the
    upper triangle i00..i22 summed by the caller), so that the members' spin takes up the orbital
    angular momentum change L of the projection."""
    tx, ty, tz = _solve_sym3(i00, i01, i02, i11, i12, i22, -lx, -ly, -lz)
    for e in range(start, end):
        j = g_mem[e]
        q = (qp[j, 0], qp[j, 1], qp[j, 2], qp[j, 3])
        dq = qmul((0.5 * tx, 0.5 * ty, 0.5 * tz, 0.0), q)
        qn = qnormalize((q[0] + dq[0], q[1] + dq[1], q[2] + dq[2], q[3] + dq[3]))
        qp[j, 0] = qn[0]
        qp[j, 1] = qn[1]
        qp[j, 2] = qn[2]
        qp[j, 3] = qn[3]


# The contact and friction kernels below each loop over all their rows: one compiled call per
# Gauss-Seidel iteration. Called once per row instead, as numba-inlined bodies in _step, the same
# arithmetic ran at half the speed (the grasp's 124 contacts: 18 us against 9 us a pass).
@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def _project_shape_contacts(
    count, c_particle, c_shape, c_inner, c_lambda, c_normal, xp, qp, radii, inv_mass, shape_kind, shape_params,
    shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_move, imp_lin,
    imp_ang, dt, shape_pose,
):  # fmt: skip
    """Non-penetration of an ellipsoid particle and a rigid shape (Mueller & Chentanez 2011 sec. 5:
    the ellipsoid is treated as a sphere of its support radius along the contact normal), split by
    generalised inverse masses so the body receives the opposite correction (Mueller et al. 2020
    sec. 3.3). Inner contacts keep only the particle centre outside its own core (radius 0)."""
    for c in range(count):
        i = c_particle[c]
        s = c_shape[c]
        p = (xp[i, 0], xp[i, 1], xp[i, 2])
        r = shape_rigid[s]
        if r >= 0 and rig_move[r]:
            dist, n = _shape_query(s, p, shape_kind, shape_params, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q)
        else:
            # Static shapes and bodies that do not move inside the solve keep the pose the contacts were
            # collected at (_shape_poses): the same numbers without re-posing the shape per contact.
            dist, n = _shape_query_at(s, p, shape_kind, shape_params, shape_pose)
        if c_inner[c]:
            rn = 0.0
        else:
            rn = support_radius((qp[i, 0], qp[i, 1], qp[i, 2], qp[i, 3]), (radii[i, 0], radii[i, 1], radii[i, 2]), n)
        pen = rn - dist
        if pen <= 0.0:
            continue
        c_normal[c, 0] = n[0]
        c_normal[c, 1] = n[1]
        c_normal[c, 2] = n[2]
        wp = inv_mass[i]
        wb = 0.0
        rx = ry = rz = 0.0
        if r >= 0:
            # lever arm to the shape's surface point under the particle
            rx = p[0] - dist * n[0] - rig_x[r, 0]
            ry = p[1] - dist * n[1] - rig_x[r, 1]
            rz = p[2] - dist * n[2] - rig_x[r, 2]
            if rig_move[r]:
                wb = _generalized_inv_mass(r, rig_q, rig_inv_mass, rig_inv_inertia, rx, ry, rz, n[0], n[1], n[2])
        dl = pen / (wp + wb)
        c_lambda[c] += dl
        xp[i, 0] += wp * dl * n[0]
        xp[i, 1] += wp * dl * n[1]
        xp[i, 2] += wp * dl * n[2]
        if r >= 0:
            _rigid_apply(r, rx, ry, rz, -dl * n[0], -dl * n[1], -dl * n[2], rig_move[r], dt, rig_x, rig_q,
                         rig_inv_mass, rig_inv_inertia, imp_lin, imp_ang)  # fmt: skip


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def _project_pairs(count, pair_i, pair_j, pair_lambda, pair_normal, xp, qp, radii, inv_mass):
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


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _coulomb(lam_t, lam_t_done, lam_n, mu_s, mu_k):
    """Position-level Coulomb friction (Macklin et al. 2014 eq. 23-24; Mueller et al. 2020 sec.
    3.5). ``lam_t`` is the tangential correction that would cancel the slip since the step began,
    ``lam_t_done`` what this contact already applied this step, ``lam_n`` its normal correction so
    far. Stick - cancel all the slip - while the total stays within mu_s lam_n; otherwise slide,
    with the total capped at mu_k lam_n."""
    if lam_t + lam_t_done <= mu_s * lam_n:
        return lam_t
    return min(lam_t, max(0.0, mu_k * lam_n - lam_t_done))


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def _friction_shape_contacts(
    count, c_particle, c_shape, c_inner, c_lambda, c_lambda_t, c_normal, x0, xp, inv_mass, p_body, body_friction, shape_rigid,
    rig_x0, rig_q0, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_move, imp_lin, imp_ang, dt,
):  # fmt: skip
    for c in range(count):
        lam_n = c_lambda[c]
        if lam_n <= 0.0 or c_inner[c]:
            continue
        i = c_particle[c]
        s = c_shape[c]
        r = shape_rigid[s]
        n = (c_normal[c, 0], c_normal[c, 1], c_normal[c, 2])
        # Relative displacement over the step of the particle against the body point it touches.
        dpx = xp[i, 0] - x0[i, 0]
        dpy = xp[i, 1] - x0[i, 1]
        dpz = xp[i, 2] - x0[i, 2]
        rx = ry = rz = 0.0
        if r >= 0:
            px = (xp[i, 0], xp[i, 1], xp[i, 2])
            rx = px[0] - rig_x[r, 0]
            ry = px[1] - rig_x[r, 1]
            rz = px[2] - rig_x[r, 2]
            q1 = (rig_q[r, 0], rig_q[r, 1], rig_q[r, 2], rig_q[r, 3])
            q0 = (rig_q0[r, 0], rig_q0[r, 1], rig_q0[r, 2], rig_q0[r, 3])
            local = qrotate(qconj(q1), (rx, ry, rz))
            start = qrotate(q0, local)
            dpx -= px[0] - (rig_x0[r, 0] + start[0])
            dpy -= px[1] - (rig_x0[r, 1] + start[1])
            dpz -= px[2] - (rig_x0[r, 2] + start[2])
        dn = dpx * n[0] + dpy * n[1] + dpz * n[2]
        tx = dpx - dn * n[0]
        ty = dpy - dn * n[1]
        tz = dpz - dn * n[2]
        tl = math.sqrt(tx * tx + ty * ty + tz * tz)
        if tl < 1e-15:
            continue
        tx /= tl
        ty /= tl
        tz /= tl
        wp = inv_mass[i]
        wb = 0.0
        if r >= 0 and rig_move[r]:
            wb = _generalized_inv_mass(r, rig_q, rig_inv_mass, rig_inv_inertia, rx, ry, rz, tx, ty, tz)
        b = p_body[i]
        dl = _coulomb(tl / (wp + wb), c_lambda_t[c], lam_n, body_friction[b, 0], body_friction[b, 1])
        c_lambda_t[c] += dl
        xp[i, 0] -= wp * dl * tx
        xp[i, 1] -= wp * dl * ty
        xp[i, 2] -= wp * dl * tz
        if r >= 0:
            _rigid_apply(r, rx, ry, rz, dl * tx, dl * ty, dl * tz, rig_move[r], dt, rig_x, rig_q, rig_inv_mass,
                         rig_inv_inertia, imp_lin, imp_ang)  # fmt: skip


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def _friction_pairs(count, pair_i, pair_j, pair_lambda, pair_lambda_t, pair_normal, x0, xp, inv_mass, p_body, body_friction):
    for k in range(count):
        lam_n = pair_lambda[k]
        if lam_n <= 0.0:
            continue
        i = pair_i[k]
        j = pair_j[k]
        n = (pair_normal[k, 0], pair_normal[k, 1], pair_normal[k, 2])
        d = (
            (xp[i, 0] - x0[i, 0]) - (xp[j, 0] - x0[j, 0]),
            (xp[i, 1] - x0[i, 1]) - (xp[j, 1] - x0[j, 1]),
            (xp[i, 2] - x0[i, 2]) - (xp[j, 2] - x0[j, 2]),
        )
        dn = d[0] * n[0] + d[1] * n[1] + d[2] * n[2]
        t = (d[0] - dn * n[0], d[1] - dn * n[1], d[2] - dn * n[2])
        tl = math.sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2])
        if tl < 1e-15:
            continue
        wi = inv_mass[i]
        wj = inv_mass[j]
        bi = p_body[i]
        bj = p_body[j]
        mu_s = 0.5 * (body_friction[bi, 0] + body_friction[bj, 0])
        mu_k = 0.5 * (body_friction[bi, 1] + body_friction[bj, 1])
        dl = _coulomb(tl / (wi + wj), pair_lambda_t[k], lam_n, mu_s, mu_k)
        pair_lambda_t[k] += dl
        for a in range(3):
            xp[i, a] -= wi * dl * t[a] / tl
            xp[j, a] += wj * dl * t[a] / tl


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _core_of_body(b, body_core_shape, shape_rigid):
    s = body_core_shape[b]
    if s < 0:
        return -1
    return shape_rigid[s]


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _project_anchor(i, r, rest_x, xp, inv_mass, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_move, imp_lin, imp_ang, dt):
    """Consistent coupling: the attachment of particle i to its spot on core r as a zero-compliance
    XPBD constraint whose denominator holds the core's generalised inverse mass (Mueller et al.
    2020; Bender's PositionBasedDynamics, solve_RigidBodyParticleBallJoint)."""
    bx = (rig_x[r, 0], rig_x[r, 1], rig_x[r, 2])
    bq = (rig_q[r, 0], rig_q[r, 1], rig_q[r, 2], rig_q[r, 3])
    arm = qrotate(bq, (rest_x[i, 0], rest_x[i, 1], rest_x[i, 2]))
    ex = xp[i, 0] - (bx[0] + arm[0])
    ey = xp[i, 1] - (bx[1] + arm[1])
    ez = xp[i, 2] - (bx[2] + arm[2])
    el = math.sqrt(ex * ex + ey * ey + ez * ez)
    if el < 1e-15:
        return
    n = (ex / el, ey / el, ez / el)
    wp = inv_mass[i]
    wb = 0.0
    if rig_move[r]:
        wb = _generalized_inv_mass(r, rig_q, rig_inv_mass, rig_inv_inertia, arm[0], arm[1], arm[2], n[0], n[1], n[2])
    dl = el / (wp + wb)
    xp[i, 0] -= wp * dl * n[0]
    xp[i, 1] -= wp * dl * n[1]
    xp[i, 2] -= wp * dl * n[2]
    _rigid_apply(r, arm[0], arm[1], arm[2], dl * n[0], dl * n[1], dl * n[2], rig_move[r], dt, rig_x, rig_q,
                 rig_inv_mass, rig_inv_inertia, imp_lin, imp_ang)  # fmt: skip


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def _snap_attached(
    model_rest_x, model_rest_q, mass, attached, p_body, body_core_shape, shape_rigid, xp, qp, rig_x, rig_q,
    imp_lin, imp_ang, coupling_imp, dt,
):  # fmt: skip
    """Thesis 5.1.3 / 5.2.2: each attached particle's error against its fixed spot on the (predicted)
    core becomes the impulse p = m_i e / dt at that spot (PBD 2007 sec. 4.2); then the particle is
    set onto the spot with the core's orientation. The tissue loses exactly the momentum the core
    gains, whichever coupling ran during the iterations."""
    n = xp.shape[0]
    for i in range(n):
        if not attached[i]:
            continue
        r = _core_of_body(p_body[i], body_core_shape, shape_rigid)
        if r < 0:
            continue
        bq = (rig_q[r, 0], rig_q[r, 1], rig_q[r, 2], rig_q[r, 3])
        arm = qrotate(bq, (model_rest_x[i, 0], model_rest_x[i, 1], model_rest_x[i, 2]))
        ax = rig_x[r, 0] + arm[0]
        ay = rig_x[r, 1] + arm[1]
        az = rig_x[r, 2] + arm[2]
        m = mass[i]
        px = m * (xp[i, 0] - ax) / dt
        py = m * (xp[i, 1] - ay) / dt
        pz = m * (xp[i, 2] - az) / dt
        imp_lin[r, 0] += px
        imp_lin[r, 1] += py
        imp_lin[r, 2] += pz
        coupling_imp[r, 0] += px
        coupling_imp[r, 1] += py
        coupling_imp[r, 2] += pz
        imp_ang[r, 0] += arm[1] * pz - arm[2] * py
        imp_ang[r, 1] += arm[2] * px - arm[0] * pz
        imp_ang[r, 2] += arm[0] * py - arm[1] * px
        xp[i, 0] = ax
        xp[i, 1] = ay
        xp[i, 2] = az
        qn = qmul(bq, (model_rest_q[i, 0], model_rest_q[i, 1], model_rest_q[i, 2], model_rest_q[i, 3]))
        qp[i, 0] = qn[0]
        qp[i, 1] = qn[1]
        qp[i, 2] = qn[2]
        qp[i, 3] = qn[3]


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def _collect_contacts(
    xp, x0, radii, p_body, attached, body_core_shape, shape_kind, shape_params, shape_rigid, shape_local_x,
    shape_local_q, rig_x, rig_q, margin, c_particle, c_shape, c_inner, pose,
):  # fmt: skip
    """Candidate (particle, shape) contacts for this step: within the particle's largest radius plus
    how far it moves plus a margin. A particle meets its own core only as an inner contact (outer
    particles; attached ones are tied to the core anyway). Returns the count (or the number
    needed, if larger than the buffers). Shapes are posed once, and a particle far outside a
    shape's bounding sphere skips the exact query (the candidates are the same)."""
    n = xp.shape[0]
    ns = shape_kind.shape[0]
    cap = c_particle.shape[0]
    count = 0
    _shape_poses(shape_kind, shape_params, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q, pose)
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
            dist, _ = _shape_query_at(s, p, shape_kind, shape_params, pose)
            if dist < reach:
                if count < cap:
                    c_particle[count] = i
                    c_shape[count] = s
                    c_inner[count] = inner
                count += 1
    return count


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def _collect_pairs(xp, x0, radii, body_off, margin, pair_i, pair_j):
    """Candidate particle pairs between different tissue bodies (the two fingers can touch): the
    overlap of the bodies' bounding boxes is searched exhaustively, which is cheap because it is
    empty unless the bodies are close. Returns the count (or the number needed)."""
    nb_ = body_off.shape[0] - 1
    cap = pair_i.shape[0]
    count = 0
    lo = np.empty((nb_, 3))
    hi = np.empty((nb_, 3))
    reach = np.zeros(nb_)
    for b in range(nb_):
        for a in range(3):
            lo[b, a] = np.inf
            hi[b, a] = -np.inf
        for i in range(body_off[b], body_off[b + 1]):
            rmax = max(radii[i, 0], max(radii[i, 1], radii[i, 2]))
            mv = math.sqrt((xp[i, 0] - x0[i, 0]) ** 2 + (xp[i, 1] - x0[i, 1]) ** 2 + (xp[i, 2] - x0[i, 2]) ** 2)
            reach[b] = max(reach[b], rmax + mv)
            for a in range(3):
                lo[b, a] = min(lo[b, a], xp[i, a])
                hi[b, a] = max(hi[b, a], xp[i, a])
    for b1 in range(nb_):
        for b2 in range(b1 + 1, nb_):
            pad = reach[b1] + reach[b2] + margin
            olo = np.empty(3)
            ohi = np.empty(3)
            empty = False
            for a in range(3):
                olo[a] = max(lo[b1, a], lo[b2, a]) - pad
                ohi[a] = min(hi[b1, a], hi[b2, a]) + pad
                if olo[a] > ohi[a]:
                    empty = True
            if empty:
                continue
            for i in range(body_off[b1], body_off[b1 + 1]):
                if not (olo[0] <= xp[i, 0] <= ohi[0] and olo[1] <= xp[i, 1] <= ohi[1] and olo[2] <= xp[i, 2] <= ohi[2]):
                    continue
                ri = max(radii[i, 0], max(radii[i, 1], radii[i, 2]))
                mi = math.sqrt((xp[i, 0] - x0[i, 0]) ** 2 + (xp[i, 1] - x0[i, 1]) ** 2 + (xp[i, 2] - x0[i, 2]) ** 2)
                for j in range(body_off[b2], body_off[b2 + 1]):
                    rj = max(radii[j, 0], max(radii[j, 1], radii[j, 2]))
                    mj = math.sqrt((xp[j, 0] - x0[j, 0]) ** 2 + (xp[j, 1] - x0[j, 1]) ** 2 + (xp[j, 2] - x0[j, 2]) ** 2)
                    d2 = (xp[i, 0] - xp[j, 0]) ** 2 + (xp[i, 1] - xp[j, 1]) ** 2 + (xp[i, 2] - xp[j, 2]) ** 2
                    lim = ri + mi + rj + mj + margin
                    if d2 < lim * lim:
                        if count < cap:
                            pair_i[count] = i
                            pair_j[count] = j
                        count += 1
    return count


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def _damped_velocities(x, v, omega, mass, body_off, c, vd, wd):
    """Damp each particle's deviation from its body's rigid motion by the fraction c (Mueller et
    al. 2007 sec. 3.5): v_i += c (v_cm + W x r_i - v_i), w_i += c (W - w_i), with v_cm, W the body's
    centre-of-mass and angular velocity. Rigid motion, so momentum and angular momentum, are kept:
    a falling or spinning body is not slowed, unlike damping the absolute velocity."""
    for b in range(body_off.shape[0] - 1):
        s = body_off[b]
        e = body_off[b + 1]
        if c == 0.0:
            for i in range(s, e):
                for a in range(3):
                    vd[i, a] = v[i, a]
                    wd[i, a] = omega[i, a]
            continue
        msum = 0.0
        cx = cy = cz = 0.0
        px = py = pz = 0.0
        for i in range(s, e):
            m = mass[i]
            msum += m
            cx += m * x[i, 0]
            cy += m * x[i, 1]
            cz += m * x[i, 2]
            px += m * v[i, 0]
            py += m * v[i, 1]
            pz += m * v[i, 2]
        cx /= msum
        cy /= msum
        cz /= msum
        vx = px / msum
        vy = py / msum
        vz = pz / msum
        lx = ly = lz = 0.0
        i00 = i01 = i02 = i11 = i12 = i22 = 0.0
        for i in range(s, e):
            m = mass[i]
            rx = x[i, 0] - cx
            ry = x[i, 1] - cy
            rz = x[i, 2] - cz
            lx += m * (ry * v[i, 2] - rz * v[i, 1])
            ly += m * (rz * v[i, 0] - rx * v[i, 2])
            lz += m * (rx * v[i, 1] - ry * v[i, 0])
            i00 += m * (ry * ry + rz * rz)
            i11 += m * (rx * rx + rz * rz)
            i22 += m * (rx * rx + ry * ry)
            i01 -= m * rx * ry
            i02 -= m * rx * rz
            i12 -= m * ry * rz
        wx, wy, wz = _solve_sym3(i00, i01, i02, i11, i12, i22, lx, ly, lz)
        for i in range(s, e):
            rx = x[i, 0] - cx
            ry = x[i, 1] - cy
            rz = x[i, 2] - cz
            vd[i, 0] = v[i, 0] + c * (vx + wy * rz - wz * ry - v[i, 0])
            vd[i, 1] = v[i, 1] + c * (vy + wz * rx - wx * rz - v[i, 1])
            vd[i, 2] = v[i, 2] + c * (vz + wx * ry - wy * rx - v[i, 2])
            wd[i, 0] = omega[i, 0] + c * (wx - omega[i, 0])
            wd[i, 1] = omega[i, 1] + c * (wy - omega[i, 1])
            wd[i, 2] = omega[i, 2] + c * (wz - omega[i, 2])


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def _step(
    # model
    rest_x, rest_q, rest_moment, inertia, radii, mass, inv_mass, p_body, attached, g_off, g_mem, g_rest, g_pack, body_off,
    body_core_shape, body_stiffness, body_friction,
    # state (updated in place on success)
    x, v, q, omega, group_q,
    # colliders (read only) and rigid outputs
    rig_x0, rig_q0, rig_v, rig_w, rig_inv_mass, rig_inv_inertia, rig_gravity, rig_move, shape_kind, shape_params,
    shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q, imp_lin, imp_ang, coupling_imp,
    # scratch
    xp, qp, vd, wd, moment, c_particle, c_shape, c_inner, c_lambda, c_lambda_t, c_normal, pair_i, pair_j, pair_lambda,
    pair_lambda_t, pair_normal, shape_pose,
    # parameters
    dt, iterations, rot_iters, gx, gy, gz, damping, coupling, orient_mode, margin, counts,
):  # fmt: skip
    """One tissue step. Returns 0, or 1 if a contact buffer was too small (``counts`` then holds
    the sizes needed and the state is untouched, so the caller can grow the buffers and retry)."""
    n = x.shape[0]
    nr = rig_x0.shape[0]
    # --- predict rigid bodies: semi-implicit Euler, as pybullet will integrate them (thesis 5.2.2)
    for r in range(nr):
        vx, vy, vz = rig_v[r, 0], rig_v[r, 1], rig_v[r, 2]
        if rig_gravity[r]:
            vx += gx * dt
            vy += gy * dt
            vz += gz * dt
        rig_x[r, 0] = rig_x0[r, 0] + vx * dt
        rig_x[r, 1] = rig_x0[r, 1] + vy * dt
        rig_x[r, 2] = rig_x0[r, 2] + vz * dt
        qn = qnormalize(qmul(qexp((rig_w[r, 0] * dt, rig_w[r, 1] * dt, rig_w[r, 2] * dt)),
                             (rig_q0[r, 0], rig_q0[r, 1], rig_q0[r, 2], rig_q0[r, 3])))  # fmt: skip
        for a in range(4):
            rig_q[r, a] = qn[a]
        for a in range(3):
            imp_lin[r, a] = 0.0
            imp_ang[r, a] = 0.0
            coupling_imp[r, a] = 0.0
    # --- predict particles (PBD Alg. 1 lines 5-11; Mueller & Chentanez 2011 sec. 3):
    #     v += g dt; damping of the deviation from each body's rigid motion; x* = x + v dt;
    #     q* = [w_hat sin(|w| dt / 2), cos(|w| dt / 2)] q
    fd = math.exp(-damping * dt)
    _damped_velocities(x, v, omega, mass, body_off, 1.0 - fd, vd, wd)
    for i in range(n):
        for a in range(3):
            g = gx if a == 0 else (gy if a == 1 else gz)
            xp[i, a] = x[i, a] + (vd[i, a] + g * dt) * dt
        dq = qexp((wd[i, 0] * dt, wd[i, 1] * dt, wd[i, 2] * dt))
        qn = qnormalize(qmul(dq, (q[i, 0], q[i, 1], q[i, 2], q[i, 3])))
        for a in range(4):
            qp[i, a] = qn[a]
        if orient_mode == ORIENT_GOAL:
            _refresh_moment(i, qn, rest_moment, moment)
        # Warm start of group i's rotation, carried forward by its centre's spin: a stale warm start
        # lags a turning group, and every lagging projection brakes the rotation.
        gq = qnormalize(qmul(dq, (group_q[i, 0], group_q[i, 1], group_q[i, 2], group_q[i, 3])))
        for a in range(4):
            group_q[i, a] = gq[a]
    # --- contact candidates, against predicted rigid poses
    nc = _collect_contacts(xp, x, radii, p_body, attached, body_core_shape, shape_kind, shape_params, shape_rigid,
                           shape_local_x, shape_local_q, rig_x, rig_q, margin, c_particle, c_shape, c_inner,
                           shape_pose)  # fmt: skip
    npairs = _collect_pairs(xp, x, radii, body_off, margin, pair_i, pair_j)
    counts[0] = nc
    counts[1] = npairs
    if nc > c_particle.shape[0] or npairs > pair_i.shape[0]:
        return 1
    for c in range(nc):
        c_lambda[c] = 0.0
        c_lambda_t[c] = 0.0
    for k in range(npairs):
        pair_lambda[k] = 0.0
        pair_lambda_t[k] = 0.0
    # --- Gauss-Seidel iterations. Stiffness per iteration k' = 1 - (1 - k)^(1/n) makes the
    #     per-step stiffness independent of the iteration count (Mueller et al. 2007 sec. 3.3).
    nbodies = body_off.shape[0] - 1
    # The spin reaction is conservative only about the optimal rotation: with an unconverged one its
    # feedback through the particles' moments grows (a free block with random velocities blew up
    # within 1000 steps at 1-2 sweeps, within 4000 at 3). So that mode extracts to convergence.
    rot_eff = rot_iters if orient_mode == ORIENT_GOAL else max(rot_iters, _REACTION_SWEEPS)
    for _ in range(iterations):
        _shape_match_sweep(iterations, rot_eff, body_off, body_stiffness, g_off, g_mem, g_rest, g_pack, mass, rest_q,
                           rest_moment, inertia, x, xp, qp, group_q, orient_mode, moment)  # fmt: skip
        _project_shape_contacts(nc, c_particle, c_shape, c_inner, c_lambda, c_normal, xp, qp, radii, inv_mass,
                                shape_kind, shape_params, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q,
                                rig_inv_mass, rig_inv_inertia, rig_move, imp_lin, imp_ang, dt, shape_pose)  # fmt: skip
        _project_pairs(npairs, pair_i, pair_j, pair_lambda, pair_normal, xp, qp, radii, inv_mass)
        # Friction inside the loop, after the normal corrections: static friction is then a
        # constraint of the same Gauss-Seidel solve as the shape matching. Applied once after the
        # loop it could only stop the touching particles, and a block on a ramp crept downhill
        # at a steady ~0.1 m/s below the friction angle.
        _friction_shape_contacts(nc, c_particle, c_shape, c_inner, c_lambda, c_lambda_t, c_normal, x, xp, inv_mass,
                                 p_body, body_friction, shape_rigid, rig_x0, rig_q0, rig_x, rig_q, rig_inv_mass,
                                 rig_inv_inertia, rig_move, imp_lin, imp_ang, dt)  # fmt: skip
        _friction_pairs(npairs, pair_i, pair_j, pair_lambda, pair_lambda_t, pair_normal, x, xp, inv_mass, p_body,
                        body_friction)  # fmt: skip
        if coupling == COUPLING_CONSISTENT:
            for i in range(n):
                if attached[i]:
                    r = _core_of_body(p_body[i], body_core_shape, shape_rigid)
                    if r >= 0:
                        _project_anchor(i, r, rest_x, xp, inv_mass, rig_x, rig_q, rig_inv_mass, rig_inv_inertia,
                                        rig_move, imp_lin, imp_ang, dt)  # fmt: skip
    # --- coupling to the cores (thesis 5.1.3): error -> impulse, snap back
    _snap_attached(rest_x, rest_q, mass, attached, p_body, body_core_shape, shape_rigid, xp, qp, rig_x, rig_q,
                   imp_lin, imp_ang, coupling_imp, dt)  # fmt: skip
    # --- velocities from positions (PBD Alg. 1 lines 18-21); angular velocity from q* q^-1 on the
    #     short arc (Mueller & Chentanez 2011 sec. 3)
    inv_dt = 1.0 / dt
    for i in range(n):
        for a in range(3):
            v[i, a] = (xp[i, a] - x[i, a]) * inv_dt
            x[i, a] = xp[i, a]
        rv = qlog(qmul((qp[i, 0], qp[i, 1], qp[i, 2], qp[i, 3]), qconj((q[i, 0], q[i, 1], q[i, 2], q[i, 3]))))
        for a in range(3):
            omega[i, a] = rv[a] * inv_dt
        for a in range(4):
            q[i, a] = qp[i, a]
    return 0


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def _max_penetration(x, q, radii, p_body, attached, body_core_shape, shape_kind, shape_params, shape_rigid,
                     shape_local_x, shape_local_q, rig_x, rig_q, out):  # fmt: skip
    """Deepest overlap of any particle ellipsoid with a rigid shape (out[0]) and deepest intrusion
    of an outer particle's centre into its own core (out[1]) [m]."""
    out[0] = 0.0
    out[1] = 0.0
    pose = np.empty((shape_kind.shape[0], 8))
    _shape_poses(shape_kind, shape_params, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q, pose)
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
                dist, _ = _shape_query_at(s, p, shape_kind, shape_params, pose)
                out[1] = max(out[1], -dist)
                continue
            if _far_from_shape(s, p, rmax, pose):
                continue
            dist, nrm = _shape_query_at(s, p, shape_kind, shape_params, pose)
            rn = support_radius((q[i, 0], q[i, 1], q[i, 2], q[i, 3]), (radii[i, 0], radii[i, 1], radii[i, 2]), nrm)
            out[0] = max(out[0], rn - dist)


# =================================================================================================
# Python front end
# =================================================================================================


class TissueSolver:
    """Owns the scratch buffers of one model and runs :func:`_step` on it."""

    def __init__(self, model: TissueModel, sim: SimConfig) -> None:
        self.model = model
        self.sim = sim
        n = model.particle_count
        self._xp = np.zeros((n, 3))
        self._qp = np.zeros((n, 4))
        self._vd = np.zeros((n, 3))
        self._wd = np.zeros((n, 3))
        self._moment = np.zeros((n, 9))
        self._rest_moment = rest_moments(model)
        self._g_pack = group_pack(model)
        self._inertia = np.ascontiguousarray(model.particle_inertia_local())
        self._counts = np.zeros(2, dtype=np.int64)
        self._alloc_contacts(4 * n + 16)
        self._alloc_pairs(4 * n + 16)
        self._rigid_buffers_for = -1
        self._shape_pose = np.zeros((0, 8))

    def _alloc_contacts(self, cap: int) -> None:
        self._c_particle = np.zeros(cap, dtype=np.int32)
        self._c_shape = np.zeros(cap, dtype=np.int32)
        self._c_inner = np.zeros(cap, dtype=np.bool_)
        self._c_lambda = np.zeros(cap)
        self._c_lambda_t = np.zeros(cap)
        self._c_normal = np.zeros((cap, 3))

    def _alloc_pairs(self, cap: int) -> None:
        self._pair_i = np.zeros(cap, dtype=np.int32)
        self._pair_j = np.zeros(cap, dtype=np.int32)
        self._pair_lambda = np.zeros(cap)
        self._pair_lambda_t = np.zeros(cap)
        self._pair_normal = np.zeros((cap, 3))

    def _rigid_buffers(self, count: int) -> None:
        if self._rigid_buffers_for != count:
            self._rig_x = np.zeros((count, 3))
            self._rig_q = np.zeros((count, 4))
            self._imp_lin = np.zeros((count, 3))
            self._imp_ang = np.zeros((count, 3))
            self._coupling_imp = np.zeros((count, 3))
            self._rigid_buffers_for = count

    def _shape_buffer(self, count: int) -> np.ndarray:
        if self._shape_pose.shape[0] != count:
            self._shape_pose = np.zeros((count, 8))
        return self._shape_pose

    def step(self, state: TissueState, col: Colliders) -> StepOutput:
        """Advance ``state`` by one step of ``sim.dt`` in place; returns predicted rigid poses and
        the impulses the tissue put on each rigid body (to be applied by the rigid simulation)."""
        m = self.model
        sim = self.sim
        self._rigid_buffers(col.rigid_count)
        shape_pose = self._shape_buffer(col.shape_count)
        coupling = COUPLING_CONSISTENT if sim.coupling == "consistent" else COUPLING_THESIS
        while True:
            code = _step(
                m.particle_rest_x, m.particle_rest_q, self._rest_moment, self._inertia, m.particle_radii, m.particle_mass, m.particle_inv_mass,
                m.particle_body, m.particle_attached, m.group_offsets, m.group_members, m.group_rest_offset,
                self._g_pack, m.body_particle_offsets, m.body_core_shape, m.body_stiffness, m.body_friction,
                state.particle_x, state.particle_v, state.particle_q, state.particle_omega, state.group_q,
                col.rigid_x, col.rigid_q, col.rigid_v, col.rigid_w, col.rigid_inv_mass, col.rigid_inv_inertia,
                col.rigid_gravity, col.rigid_in_solve, col.shape_kind, col.shape_params, col.shape_rigid,
                col.shape_local_x, col.shape_local_q, self._rig_x, self._rig_q, self._imp_lin, self._imp_ang,
                self._coupling_imp,
                self._xp, self._qp, self._vd, self._wd, self._moment, self._c_particle, self._c_shape, self._c_inner,
                self._c_lambda, self._c_lambda_t, self._c_normal, self._pair_i, self._pair_j, self._pair_lambda,
                self._pair_lambda_t, self._pair_normal, shape_pose,
                sim.dt, sim.iterations, sim.rotation_iterations, 0.0, 0.0, -sim.gravity, sim.damping, coupling,
                ORIENT_MODES[sim.orientation], sim.contact_margin, self._counts,
            )  # fmt: skip
            if code == 0:
                break
            # A buffer was too small: nothing was changed; grow it and run the step again.
            if self._counts[0] > self._c_particle.shape[0]:
                self._alloc_contacts(int(2 * self._counts[0]))
            if self._counts[1] > self._pair_i.shape[0]:
                self._alloc_pairs(int(2 * self._counts[1]))
        return StepOutput(
            rigid_pred_x=self._rig_x,
            rigid_pred_q=self._rig_q,
            rigid_impulse=self._imp_lin,
            rigid_angular_impulse=self._imp_ang,
            coupling_impulse=self._coupling_imp,
            contact_count=int(self._counts[0]),
            pair_count=int(self._counts[1]),
        )

    def contact_normal_force(self, shape: int) -> np.ndarray:
        """Normal force each tissue body pressed on shape ``shape`` with during the last step [N],
        shape (bodies,). A contact's accumulated normal multiplier lambda is a positional impulse
        [kg m] (Mueller et al. 2020, eq. 6), so its force over the step is lambda / dt^2."""
        m = self.model
        out = np.zeros(m.body_count)
        nc = int(self._counts[0])
        if nc == 0:
            return out
        sel = (self._c_shape[:nc] == shape) & ~self._c_inner[:nc]
        bodies = m.particle_body[self._c_particle[:nc][sel]]
        np.add.at(out, bodies, self._c_lambda[:nc][sel])
        return out / (self.sim.dt * self.sim.dt)

    def penetration(self, state: TissueState, col: Colliders) -> tuple[float, float]:
        """(deepest particle overlap with any other rigid shape, deepest outer-particle intrusion into
        its own core) at the colliders' current poses [m]."""
        m = self.model
        out = np.zeros(2)
        _max_penetration(state.particle_x, state.particle_q, m.particle_radii, m.particle_body, m.particle_attached,
                         m.body_core_shape, col.shape_kind, col.shape_params, col.shape_rigid, col.shape_local_x,
                         col.shape_local_q, col.rigid_x, col.rigid_q, out)  # fmt: skip
        return float(out[0]), float(out[1])


def empty_colliders() -> Colliders:
    """No rigid bodies and no shapes (free tissue in empty space)."""
    return Colliders(
        rigid_x=np.zeros((0, 3)),
        rigid_q=np.zeros((0, 4)),
        rigid_v=np.zeros((0, 3)),
        rigid_w=np.zeros((0, 3)),
        rigid_inv_mass=np.zeros(0),
        rigid_inv_inertia=np.zeros((0, 3)),
        rigid_gravity=np.zeros(0, dtype=np.bool_),
        rigid_in_solve=np.zeros(0, dtype=np.bool_),
        shape_kind=np.zeros(0, dtype=np.int32),
        shape_params=np.zeros((0, 3)),
        shape_rigid=np.zeros(0, dtype=np.int32),
        shape_local_x=np.zeros((0, 3)),
        shape_local_q=np.zeros((0, 4)),
    )
