"""Core <-> tissue coupling on the pybullet side (thesis 5.1.3, 5.2.2).

The solver returns, per rigid slot, the linear impulse P and the angular impulse L (about the
predicted centre of mass) that the tissue exerted during the step. Here they reach pybullet:

* a free base body (the cylinder) gets them as a velocity change before pybullet's step,
  dv = P / m, dw = I_w^-1 L, exactly as the solver predicted it (Mueller et al. 2020, eq. 6-9);
* links and constrained bases (finger cores, palm) get them as an external force P / dt and torque
  L / dt for the coming step, because pybullet cannot set a link's velocity and clears external
  forces after every step (DESIGN.md): the joint motors and constraints then act against them.

After pybullet's step the attached particles are set onto their spots on the cores' actual poses
with the cores' point velocities (:func:`sync_attached`), so the tissue never lags its core.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np
import pybullet as p
from pybullet_utils.bullet_client import BulletClient

from ..tissue.rotation import qconj, qmul, qrotate
from .bullet import RigidRef


def apply_impulses(
    client: BulletClient,
    refs: list[RigidRef],
    x: np.ndarray,
    q: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    inv_mass: np.ndarray,
    inv_inertia: np.ndarray,
    impulse: np.ndarray,
    angular_impulse: np.ndarray,
    dt: float,
    free: np.ndarray,
) -> None:
    """Hand the tissue's impulses on every rigid slot to pybullet for its next step. ``free`` (R,)
    marks the slots that are free base bodies; nothing is applied if any impulse is not finite.
    (One-off form of :class:`ImpulseApplier`.)"""
    ImpulseApplier(client, refs, free=free).apply(x, q, v, w, inv_mass, inv_inertia, impulse, angular_impulse, dt)


class ImpulseApplier:
    """:func:`apply_impulses` for one world, with its buffers and per-slot calls prepared once: the
    per-step Python work is one compiled call, one ``tolist`` and the pybullet calls themselves
    (every numpy call and object built per step is a noticeable share of a ~300 us step)."""

    def __init__(self, client: BulletClient, refs: list[RigidRef], *, free: np.ndarray | None = None) -> None:
        self._cid = client._client  # pybullet's functions on our own client, without BulletClient's wrapper
        if free is None:
            free = np.array([r.free_base for r in refs], dtype=np.bool_)
        self._free = np.asarray(free, dtype=np.bool_)
        self._slots = [(k, r.body, r.link, bool(f)) for (k, r), f in zip(enumerate(refs), self._free, strict=True)]
        self._out = np.zeros((len(refs), 10))

    def apply(self, x, q, v, w, inv_mass, inv_inertia, impulse, angular_impulse, dt) -> bool:
        """Hand the impulses to pybullet; False, with nothing handed over, if any is not finite (a
        NaN would poison pybullet's bodies and its broadphase for good). The check is in the
        compiled call: two ``np.isfinite(...).all()`` in Python cost ~6 us a step."""
        out = self._out
        count = _impulse_commands(x, q, v, w, inv_mass, inv_inertia, impulse, angular_impulse, self._free, dt, out)
        if count <= 0:
            return count == 0
        rows = out.tolist()
        cid = self._cid
        # pybullet's arguments by position (keywords cost ~0.4 us a call to parse):
        # resetBaseVelocity(body, linear, angular, client), applyExternalForce(body, link, force,
        # position, flags, client), applyExternalTorque(body, link, torque, flags, client)
        for k, body, link, free in self._slots:
            row = rows[k]
            if row[9] == 0.0:
                continue
            if free:
                p.resetBaseVelocity(body, row[0:3], row[3:6], cid)
            else:
                p.applyExternalForce(body, link, row[0:3], row[6:9], p.WORLD_FRAME, cid)
                p.applyExternalTorque(body, link, row[3:6], p.WORLD_FRAME, cid)
        return True


@nb.njit(cache=True)
def _impulse_commands(x, q, v, w, inv_mass, inv_inertia, impulse, angular_impulse, free, dt, out):
    """Per slot, what pybullet is told: a free base's new velocities v + P/m, w + I_w^-1 L; anything
    else the force P/dt and torque L/dt at its centre of mass x. out[k] = (6 values, x (3), active
    flag); returns how many slots have anything to apply (static and kinematic slots, 1/m = 0,
    never do), or -1 if any slot's impulse is not finite (then nothing is to be applied)."""
    n = x.shape[0]
    for k in range(n):
        for a in range(3):
            if not (math.isfinite(impulse[k, a]) and math.isfinite(angular_impulse[k, a])):
                return -1
    count = 0
    for k in range(n):
        out[k, 9] = 0.0
        if inv_mass[k] == 0.0:
            continue
        px, py, pz = impulse[k, 0], impulse[k, 1], impulse[k, 2]
        lx, ly, lz = angular_impulse[k, 0], angular_impulse[k, 1], angular_impulse[k, 2]
        if px == 0.0 and py == 0.0 and pz == 0.0 and lx == 0.0 and ly == 0.0 and lz == 0.0:
            continue
        out[k, 9] = 1.0
        count += 1
        for a in range(3):
            out[k, 6 + a] = x[k, a]
        if free[k]:
            qk = (q[k, 0], q[k, 1], q[k, 2], q[k, 3])
            ll = qrotate(qconj(qk), (lx, ly, lz))
            dw = qrotate(qk, (inv_inertia[k, 0] * ll[0], inv_inertia[k, 1] * ll[1], inv_inertia[k, 2] * ll[2]))
            out[k, 0] = v[k, 0] + inv_mass[k] * px
            out[k, 1] = v[k, 1] + inv_mass[k] * py
            out[k, 2] = v[k, 2] + inv_mass[k] * pz
            out[k, 3] = w[k, 0] + dw[0]
            out[k, 4] = w[k, 1] + dw[1]
            out[k, 5] = w[k, 2] + dw[2]
        else:
            out[k, 0] = px / dt
            out[k, 1] = py / dt
            out[k, 2] = pz / dt
            out[k, 3] = lx / dt
            out[k, 4] = ly / dt
            out[k, 5] = lz / dt
    return count


@nb.njit(cache=True)
def sync_attached(
    rest_x, rest_q, attached, p_body, body_core_shape, shape_rigid, rig_x, rig_q, rig_v, rig_w, x, v, q, omega
):  # fmt: skip
    """Put every attached particle onto its fixed spot on its core's current pose, moving with the
    core: v = v_c + w_c x r, orientation q_c q_bar, angular velocity w_c (thesis 5.1.1: attached
    particles are tied to the core)."""
    for i in range(x.shape[0]):
        if not attached[i]:
            continue
        s = body_core_shape[p_body[i]]
        if s < 0:
            continue
        r = shape_rigid[s]
        bq = (rig_q[r, 0], rig_q[r, 1], rig_q[r, 2], rig_q[r, 3])
        arm = qrotate(bq, (rest_x[i, 0], rest_x[i, 1], rest_x[i, 2]))
        x[i, 0] = rig_x[r, 0] + arm[0]
        x[i, 1] = rig_x[r, 1] + arm[1]
        x[i, 2] = rig_x[r, 2] + arm[2]
        wx, wy, wz = rig_w[r, 0], rig_w[r, 1], rig_w[r, 2]
        v[i, 0] = rig_v[r, 0] + wy * arm[2] - wz * arm[1]
        v[i, 1] = rig_v[r, 1] + wz * arm[0] - wx * arm[2]
        v[i, 2] = rig_v[r, 2] + wx * arm[1] - wy * arm[0]
        qn = qmul(bq, (rest_q[i, 0], rest_q[i, 1], rest_q[i, 2], rest_q[i, 3]))
        for a in range(4):
            q[i, a] = qn[a]
        omega[i, 0] = wx
        omega[i, 1] = wy
        omega[i, 2] = wz
