"""Attachment of the tissue to its rigid core: the tissue side of the coupling (thesis 5.1.3).

Attached particles have a fixed spot on their body's core. Two couplings:
- thesis (COUPLING_THESIS): the core is infinitely heavy inside the solve; after the iterations each
  attached particle's error against its spot becomes the impulse p = m_i e / dt on the core (PBD
  2007 sec. 4.2) and the particle snaps back (:func:`snap_attached`).
- consistent (COUPLING_CONSISTENT): in addition, every iteration projects the attachment as a
  zero-compliance XPBD constraint whose denominator holds the core's generalised inverse mass
  (Mueller et al. 2020; Bender's PositionBasedDynamics, solve_RigidBodyParticleBallJoint), so the
  core takes its share inside the solve (:func:`project_anchors`); the snap then finds little error.
"""

from __future__ import annotations

import math

import numba as nb

from .jit import KERNEL
from .rigid import generalized_inv_mass, rigid_apply
from .rotation import qmul, qrotate

COUPLING_THESIS = 0
COUPLING_CONSISTENT = 1


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _core_of_body(b, body_core_shape, shape_rigid):
    s = body_core_shape[b]
    if s < 0:
        return -1
    return shape_rigid[s]


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _project_anchor(i, r, slack, rest_x, xp, inv_mass, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move,
                    imp_lin, imp_ang, dt):  # fmt: skip
    """Particle i within ``slack`` of its spot on core r [m], as a zero-compliance XPBD constraint
    whose denominator holds the core's generalised inverse mass (Mueller et al. 2020; Bender's
    PositionBasedDynamics, solve_RigidBodyParticleBallJoint): the consistent coupling's attachment
    (slack 0), and the material's strain limit (limit_deviation)."""
    bx = (rig_x[r, 0], rig_x[r, 1], rig_x[r, 2])
    bq = (rig_q[r, 0], rig_q[r, 1], rig_q[r, 2], rig_q[r, 3])
    arm = qrotate(bq, (rest_x[i, 0], rest_x[i, 1], rest_x[i, 2]))
    ex = xp[i, 0] - (bx[0] + arm[0])
    ey = xp[i, 1] - (bx[1] + arm[1])
    ez = xp[i, 2] - (bx[2] + arm[2])
    el = math.sqrt(ex * ex + ey * ey + ez * ez)
    if el < 1e-15 or el <= slack:
        return
    n = (ex / el, ey / el, ez / el)
    wp = inv_mass[i]
    wb = 0.0
    if rig_move[r]:
        wb = generalized_inv_mass(r, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, arm[0], arm[1], arm[2], n[0], n[1], n[2])
    dl = (el - slack) / (wp + wb)
    xp[i, 0] -= wp * dl * n[0]
    xp[i, 1] -= wp * dl * n[1]
    xp[i, 2] -= wp * dl * n[2]
    rigid_apply(r, arm[0], arm[1], arm[2], dl * n[0], dl * n[1], dl * n[2], rig_move[r], dt, rig_x, rig_q,
                rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin, imp_ang)  # fmt: skip


@nb.njit(**KERNEL)
def project_anchors(rest_x, inv_mass, attached, p_body, body_core_shape, shape_rigid, xp, rig_x, rig_q, rig_inv_mass,
                    rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, dt):  # fmt: skip
    """One Gauss-Seidel pass of the consistent coupling over every attached particle (see
    _project_anchor)."""
    project_anchors_of(0, xp.shape[0], rest_x, inv_mass, attached, p_body, body_core_shape, shape_rigid, xp, rig_x,
                       rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, dt)  # fmt: skip


@nb.njit(**KERNEL)
def project_anchors_of(lo, hi, rest_x, inv_mass, attached, p_body, body_core_shape, shape_rigid, xp, rig_x, rig_q,
                       rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, dt):  # fmt: skip
    """project_anchors over particles lo .. hi - 1."""
    for i in range(lo, hi):
        if attached[i]:
            r = _core_of_body(p_body[i], body_core_shape, shape_rigid)
            if r >= 0:
                _project_anchor(i, r, 0.0, rest_x, xp, inv_mass, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis,
                                rig_move, imp_lin, imp_ang, dt)  # fmt: skip


@nb.njit(**KERNEL)
def limit_deviation(rest_x, inv_mass, attached, p_body, body_core_shape, body_max_deviation, shape_rigid, xp, rig_x,
                    rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, dt):  # fmt: skip
    """The material's strain limit: every free particle back within its body's
    ``body_max_deviation`` of the spot its core carries it to, the core taking the reaction (a
    deformation constraint, Provot 1995, between particle and core; _project_anchor with slack).

    Projected after friction in every iteration, it is what a snagged particle's friction gives way
    to. Why it is needed: a particle caught on the cylinder's top face is pulled by its group
    straight toward its goal, through the cylinder, so the pull presses it onto the face as hard as
    it drags it, and Coulomb friction (mu 0.9) holds it however hard the finger pulls (a
    self-locking wedge); real tissue wraps around the rim and is pulled along the face. Without it
    the tissue tore in long random-action runs."""
    limit_deviation_of(0, xp.shape[0], rest_x, inv_mass, attached, p_body, body_core_shape, body_max_deviation,
                       shape_rigid, xp, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang,
                       dt)  # fmt: skip


@nb.njit(**KERNEL)
def limit_deviation_of(lo, hi, rest_x, inv_mass, attached, p_body, body_core_shape, body_max_deviation, shape_rigid, xp,
                       rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, dt):  # fmt: skip
    """limit_deviation over particles lo .. hi - 1."""
    for i in range(lo, hi):
        if attached[i]:
            continue
        b = p_body[i]
        slack = body_max_deviation[b]
        if math.isinf(slack):
            continue
        r = _core_of_body(b, body_core_shape, shape_rigid)
        if r >= 0:
            _project_anchor(i, r, slack, rest_x, xp, inv_mass, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis,
                            rig_move, imp_lin, imp_ang, dt)  # fmt: skip


@nb.njit(**KERNEL)
def snap_attached(
    model_rest_x, model_rest_q, mass, attached, p_body, body_core_shape, shape_rigid, xp, qp, rig_x, rig_q,
    imp_lin, imp_ang, coupling_imp, dt,
):  # fmt: skip
    """Thesis 5.1.3 / 5.2.2: each attached particle's error against its fixed spot on the (predicted)
    core becomes the impulse p = m_i e / dt at that spot (PBD 2007 sec. 4.2); then the particle is
    set onto the spot with the core's orientation. The tissue loses exactly the momentum the core
    gains, whichever coupling ran during the iterations."""
    snap_attached_of(0, xp.shape[0], model_rest_x, model_rest_q, mass, attached, p_body, body_core_shape, shape_rigid,
                     xp, qp, rig_x, rig_q, imp_lin, imp_ang, coupling_imp, dt)  # fmt: skip


@nb.njit(**KERNEL)
def snap_attached_of(lo, hi, model_rest_x, model_rest_q, mass, attached, p_body, body_core_shape, shape_rigid, xp, qp,
                     rig_x, rig_q, imp_lin, imp_ang, coupling_imp, dt):  # fmt: skip
    """snap_attached over particles lo .. hi - 1."""
    for i in range(lo, hi):
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


@nb.njit(**KERNEL)
def mark_fixed(attached, p_body, body_core_shape, fixed):
    """fixed[i]: particle i is held by its core inside the group solve (compliant.project_group):
    attached, of a body with a core. Under the thesis coupling it does not move (the core is infinitely heavy in
    the solve), under the consistent one it moves with its core along the core's joint."""
    for i in range(attached.shape[0]):
        b = p_body[i]
        fixed[i] = attached[i] and body_core_shape[b] >= 0


@nb.njit(cache=True, parallel=True, error_model="numpy", fastmath={"contract"})
def limit_and_anchor_bodies(consistent, body_off, rest_x, inv_mass, attached, p_body, body_core_shape,
                            body_max_deviation, shape_rigid, xp, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis,
                            rig_move, imp_lin, imp_ang, dt):  # fmt: skip
    """limit_deviation and then (``consistent``) project_anchors, the bodies on threads: a particle's
    projections touch only it and its own body's core, so where no two bodies share a core
    (compliant.bodies_independent) this is the two passes over all particles, to the bit."""
    for b in nb.prange(body_off.shape[0] - 1):
        limit_deviation_of(body_off[b], body_off[b + 1], rest_x, inv_mass, attached, p_body, body_core_shape,
                           body_max_deviation, shape_rigid, xp, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis,
                           rig_move, imp_lin, imp_ang, dt)  # fmt: skip
        if consistent:
            project_anchors_of(body_off[b], body_off[b + 1], rest_x, inv_mass, attached, p_body, body_core_shape,
                               shape_rigid, xp, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move,
                               imp_lin, imp_ang, dt)  # fmt: skip
