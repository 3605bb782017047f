"""Rigid bodies as the tissue sees them: their poses, mass properties and collision shapes, and
the two things the solver does to them.

Rigid bodies live in pybullet; the solver takes them as read-only inputs (pose at step start,
velocities, mass properties, :class:`Colliders`), predicts their poses the way pybullet will
integrate them (semi-implicit Euler, thesis 5.2.2), and moves a predicted pose under a positional
impulse with the body's generalised inverse mass w = 1/m + (r x n)^T I_w^-1 (r x n) (Mueller et al.
2020, "Detailed Rigid Body Simulation with Extended Position Based Dynamics", eq. 2-3 and 6-9).
Nothing here imports pybullet.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba as nb
import numpy as np

from .collision import HULL_HEADER, HULL_MIN_PLANES, HULL_PLANE, SHAPE_CODES, SHAPE_HULL
from .jit import KERNEL
from .rotation import qconj, qexp, qmul, qnormalize, qrotate


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
    """(S,) int32 shape code (see collision.py). A solver reads which kinds there are when it first
    sees this array (the kernels it runs depend on it, collision.shape_distance_of): to change a
    shape's kind, assign a new array rather than editing this one."""
    shape_params: np.ndarray
    """(S, K) shape dimensions [m], K >= 3, float64: each kind's three in columns 0-2 (the rest
    zeros), or a hull's row [plane count, bounding radius, 0, n0x, n0y, n0z, d0, n1x, ...]
    (collision.hull_params), all rows padded to the longest."""
    shape_rigid: np.ndarray
    """(S,) int32 owning rigid body, -1 for static world geometry."""
    shape_local_x: np.ndarray
    """(S, 3) shape origin in its body's frame (world frame for static shapes) [m]."""
    shape_local_q: np.ndarray
    """(S, 4) shape orientation in its body's frame."""
    rigid_axis: np.ndarray | None = field(default=None)
    """(R, 3) unit axis along which a slot moves inside the solve, or zeros for a free body: a link
    on a prismatic joint can only slide along it (the joint takes up the rest of any impulse, and
    it cannot turn). Defaults to all free."""
    rigid_force: np.ndarray | None = field(default=None)
    """(R, 3) force pybullet will put on a slot over the coming step that is known now, apart
    from gravity and the tissue (a finger's joint motor, as applied in the last step) [N]. Slots
    that move inside the solve are predicted under it; without it a pushed core recoils in the
    solve as if nothing pushed it. Defaults to zeros."""

    def __post_init__(self) -> None:
        _check_shape_table(self.shape_kind, self.shape_params)
        n = self.rigid_inv_mass.shape[0]
        if self.rigid_axis is None:
            self.rigid_axis = np.zeros((n, 3))
        if self.rigid_force is None:
            self.rigid_force = np.zeros((n, 3))

    @property
    def rigid_count(self) -> int:
        return int(self.rigid_inv_mass.shape[0])

    @property
    def shape_count(self) -> int:
        return int(self.shape_kind.shape[0])


def _check_shape_table(kind: np.ndarray, params: np.ndarray) -> None:
    """The kernels index shape_params by the kind's layout without checks: a code they do not know
    or a hull row cut short would be read as garbage, so refuse them here."""
    s = kind.shape[0]
    if params.ndim != 2 or params.shape[0] != s or params.shape[1] < 3:
        raise ValueError(f"Colliders.shape_params must be (S, K) with S = {s} shapes and K >= 3, got {params.shape}")
    known = np.isin(kind, list(SHAPE_CODES.values()))
    if not known.all():
        raise ValueError(f"Colliders.shape_kind {int(kind[~known][0])} is no shape code (collision.SHAPE_CODES)")
    for k in np.flatnonzero(kind == SHAPE_HULL):
        count = params[k, 0]
        if not (count >= HULL_MIN_PLANES and count == int(count)
                and HULL_HEADER + HULL_PLANE * int(count) <= params.shape[1]):  # fmt: skip
            raise ValueError(f"Colliders: shape {k} is a hull of {float(count)!r} planes, which its params row of "
                             f"{params.shape[1]} columns cannot hold (rows from collision.hull_params)")  # fmt: skip


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
        rigid_axis=np.zeros((0, 3)),
        rigid_force=np.zeros((0, 3)),
    )


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def rigid_point_world(rx, rq, p_local):
    r = qrotate(rq, p_local)
    return (rx[0] + r[0], rx[1] + r[1], rx[2] + r[2])


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def shape_world_pose(s, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q):
    """World pose (x, q) of shape s given the current rigid poses."""
    lx = (shape_local_x[s, 0], shape_local_x[s, 1], shape_local_x[s, 2])
    lq = (shape_local_q[s, 0], shape_local_q[s, 1], shape_local_q[s, 2], shape_local_q[s, 3])
    r = shape_rigid[s]
    if r < 0:
        return lx, lq
    bx = (rig_x[r, 0], rig_x[r, 1], rig_x[r, 2])
    bq = (rig_q[r, 0], rig_q[r, 1], rig_q[r, 2], rig_q[r, 3])
    return rigid_point_world(bx, bq, lx), qmul(bq, lq)


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def generalized_inv_mass(r, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rx, ry, rz, nx, ny, nz):
    """w = 1/m + (r x n)^T I_w^-1 (r x n) of rigid body r at lever arm (rx, ry, rz) along n
    (Mueller et al. 2020, eq. 2-3); for a slot that only slides along a unit axis a (a prismatic
    joint's link), w = (a . n)^2 / m."""
    ax, ay, az = rig_axis[r, 0], rig_axis[r, 1], rig_axis[r, 2]
    if ax != 0.0 or ay != 0.0 or az != 0.0:
        d = ax * nx + ay * ny + az * nz
        return rig_inv_mass[r] * d * d
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
def rigid_apply(r, rx, ry, rz, px, py, pz, move, dt, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin,
                imp_ang):  # fmt: skip
    """Apply positional impulse P (kg m) at lever arm r to rigid body r: record P/dt and r x P/dt
    as the impulse on it, and, if it moves inside the solve, update its predicted pose
    (Mueller et al. 2020, eq. 6-9); a slot on an axis moves along it by (a . P) / m only."""
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
    ax, ay, az = rig_axis[r, 0], rig_axis[r, 1], rig_axis[r, 2]
    if ax != 0.0 or ay != 0.0 or az != 0.0:
        d = im * (ax * px + ay * py + az * pz)
        rig_x[r, 0] += d * ax
        rig_x[r, 1] += d * ay
        rig_x[r, 2] += d * az
        return
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


@nb.njit(**KERNEL)
def predict_rigid(rig_x0, rig_q0, rig_v, rig_w, rig_gravity, rig_move, rig_inv_mass, rig_force, gx, gy, gz, dt, rig_x,
                  rig_q, imp_lin, imp_ang, coupling_imp):  # fmt: skip
    """Predict every rigid body's pose by semi-implicit Euler, as pybullet will integrate it (thesis
    5.2.2): v += g dt for bodies under gravity, v += F / m dt for the known forces of slots that
    move inside the solve, x* = x + v dt, q* = exp(w dt) q. Also clears the impulse accumulators
    the step adds to."""
    nr = rig_x0.shape[0]
    for r in range(nr):
        vx, vy, vz = rig_v[r, 0], rig_v[r, 1], rig_v[r, 2]
        if rig_gravity[r]:
            vx += gx * dt
            vy += gy * dt
            vz += gz * dt
        if rig_move[r]:
            k = rig_inv_mass[r] * dt
            vx += k * rig_force[r, 0]
            vy += k * rig_force[r, 1]
            vz += k * rig_force[r, 2]
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
