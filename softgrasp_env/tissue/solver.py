"""The oriented-particle solver: one tissue step against a set of rigid colliders.

One step, in the order of the thesis (5.2.2) and of position-based dynamics (Mueller et al. 2007,
Alg. 1), reads as a recipe (see :func:`_step`)::

    predict(particles, rigid bodies, dt)          # gravity, damping, x* = x + v dt, q* = exp(w dt) q
    collect contact candidates                    # particle-shape, inner (own core), particle-particle
    for _ in range(iterations):                   # Gauss-Seidel
        shape-match every implicit group          # Mueller & Chentanez 2011 sec. 4
        project contacts (two-way, mass-weighted) # XPBD rigid bodies, Mueller et al. 2020 sec. 3.3
        friction per contact patch, with anchors  # position level, Mueller et al. 2020 sec. 3.5
        strain limit                              # a particle within reach of its core, Provot 1995
        [consistent coupling: project anchors]    # generalised inverse mass of the core
    couple: anchor error -> impulse on the core, snap attached particles back   # thesis 5.1.3
    update velocities from positions, angular velocities from q* q^-1 (short arc)
    kinetic friction's velocity half; keep the friction anchors for the next step

The material (compliant.py) is a shear modulus in Pa: the members attached to a core are held by
it through the solve (the thesis coupling snaps them onto their cores' spots before every sweep,
not only after the last); the group solve is a Newton step of the implicit step; and after
friction a strain limit keeps every particle within reach of its core (anchors.limit_deviation).
Where the material is too stiff for dt, the world runs in shorter steps (compliant.world_substeps).

Each line is one module's kernel: rigid.py (rigid bodies as the tissue sees them, their prediction),
integrate.py (particle prediction and velocity update), contacts.py (collection and projection),
shape_matching.py (the groups' fit and orientations), compliant.py (the group solve),
friction.py, anchors.py (the attachment to the core). This module holds only the recipe and its
Python front end, which owns the scratch buffers.

Rigid bodies live in pybullet; the solver sees them as read-only inputs (pose at step start,
velocities, mass properties) and returns their predicted poses and the impulses the tissue put on
them. Nothing here imports pybullet or gymnasium.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import NamedTuple

import numba as nb
import numpy as np

from ..config import COMPLIANT_DAMPING, SimConfig
from .anchors import (
    COUPLING_CONSISTENT,
    COUPLING_THESIS,
    limit_and_anchor_bodies,
    limit_deviation,
    mark_fixed,
    project_anchors,
    snap_attached,
    snap_attached_of,
)
from .collision import more_kinds_of
from .compliant import bodies_independent, compliant_sweep, sweep_body, turn_rates
from .contacts import (
    clear_multipliers,
    collect_contacts,
    collect_pairs,
    max_penetration,
    pair_scratch_sizes,
    project_pairs,
    project_shape_contacts,
)
from .friction import friction_pairs, friction_patches, friction_velocity_pass, load_anchors, store_anchors
from .global_step import (
    GlobalSystem,
    friction_weights,
    global_body_finish,
    global_body_pass,
    global_finish,
    global_pass,
    global_system,
    project_contacts,
)
from .integrate import predict_body, predict_particles, update_velocities, update_velocities_of
from .jit import KERNEL
from .model import CONTINUUM_COLUMNS, TissueModel
from .rigid import Colliders, predict_rigid
from .shape_matching import (
    GROUP_PACK_COLUMNS,
    balance_torques,
    balance_torques_of,
    group_frames,
    group_frames_of,
    group_pack,
    rest_moments,
)
from .state import TissueState

RIGID_ROW = 16
"""Floats a row of the solver's rigid outputs takes (128 bytes: TissueSolver._rigid_buffers)."""


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


class LastContacts(NamedTuple):
    """The particle-shape contacts of a step (TissueSolver.last_contacts): the first ``count`` rows
    of each array are valid. Multipliers are positional impulses [kg m] (Mueller et al. 2020 eq. 6):
    a force over the step is the multiplier / dt^2."""

    count: int
    particle: np.ndarray
    """(C,) the particle of each contact."""
    inner: np.ndarray
    """(C,) bool: a particle's contact with its own core (internal, not a load)."""
    normal_lambda: np.ndarray
    """(C,) the normal multiplier, along ``normal``."""
    normal: np.ndarray
    """(C, 3) the contact normal, pushing the particle out of the shape."""
    friction: np.ndarray
    """(C, 3) the friction's positional impulse on the particle (the position half of it)."""
    patch: np.ndarray
    """(C,) the contact's friction patch (-1: none)."""
    patch_slide: np.ndarray
    """(P,) bool: the patch slides (kinetic friction, half of it applied on velocities)."""
    patch_change: np.ndarray
    """(P,) bool: the sliding patch stops within the step."""
    shape: np.ndarray
    """(C,) the rigid shape of each contact (the scene's shape index: colliders' order)."""
    friction_velocity: np.ndarray
    """(C, 3) the velocity half of kinetic friction on the particle, as a positional impulse [kg m]
    (impulse x dt): ``friction + friction_velocity`` is the contact's whole friction of the step."""
    single: int
    """Patch rows from this one on are single contacts (TissueConfig.friction_law "contact"), whose
    kinetic friction is all in ``friction``; the rows before it are (tissue body, shape) patches,
    whose sliding contacts take about as much again in the velocity pass."""


# =================================================================================================
# packed scratch: one flat buffer per dtype, each array a (offset, rows, cols) row of `layout`
# =================================================================================================

# float64 scratch, by size: per particle, per contact, per pair, per shape, per patch
_F_SCRATCH = (
    ("xp", "n", 3), ("qp", "n", 4), ("q_pred", "n", 4), ("vd", "n", 3), ("wd", "n", 3), ("moment", "n", 9),
    ("spin_kick", "n", 3), ("g_frame", "n", 10),
    ("c_lambda", "contacts", 0), ("c_normal", "contacts", 3), ("c_rn", "contacts", 0), ("c_friction", "contacts", 3),
    ("c_friction_goal", "contacts", 3), ("c_anchor", "contacts", 3), ("c_point", "contacts", 3),
    ("pair_lambda", "pairs", 0), ("pair_lambda_t", "pairs", 0), ("pair_normal", "pairs", 3),
    ("shape_pose", "shapes", 8), ("patch", "patches", 18),
    ("g_u", "members", 3), ("g_raw", "members", 3), ("c_friction_vel", "contacts", 3),
    ("pair_boxes", "pair_boxes", 0), ("g_turn", "n", 0),
)  # fmt: skip
_I_SCRATCH = (("c_particle", "contacts", 0), ("c_shape", "contacts", 0), ("c_patch", "contacts", 0),
              ("pair_i", "pairs", 0), ("pair_j", "pairs", 0), ("patch_body", "patches", 0),
              ("pair_grid", "pair_grid", 0))  # fmt: skip  (int32)
_B_SCRATCH = (("c_inner", "contacts", 0), ("patch_slide", "patches", 0), ("patch_change", "patches", 0),
              ("c_slip", "contacts", 0),
              ("fixed", "n", 0))  # fmt: skip  (bool)
# the model's arrays, copied in once (TissueModel is frozen; the solver reads it at construction,
# as it does for the rest moments and group data it derives from it)
_F_MODEL = (("rest_x", "n", 3), ("rest_q", "n", 4), ("rest_moment", "n", 9), ("inertia", "n", 3), ("radii", "n", 3),
            ("mass", "n", 0), ("inv_mass", "n", 0), ("g_pack", "members", GROUP_PACK_COLUMNS),
            ("body_friction", "bodies", 2), ("group_kappa", "n", 0), ("body_max_deviation", "bodies", 0),
            ("g_cont", "n", CONTINUUM_COLUMNS))  # fmt: skip
_I_MODEL = (("p_body", "n", 0), ("g_off", "groups", 0), ("g_mem", "members", 0), ("body_off", "body_offsets", 0),
            ("body_core_shape", "bodies", 0))  # fmt: skip
_B_MODEL = (("attached", "n", 0), ("body_contact_cone", "bodies", 0), ("body_contact_law", "bodies", 0))
_F_PACK = _F_SCRATCH + _F_MODEL
_I_PACK = _I_SCRATCH + _I_MODEL
_B_PACK = _B_SCRATCH + _B_MODEL
_PACK = _F_PACK + _I_PACK + _B_PACK
# their rows in `layout` (numba reads module-level ints as compile-time constants)
(_XP, _QP, _Q_PRED, _VD, _WD, _MOMENT, _SPIN_KICK, _G_FRAME, _C_LAMBDA, _C_NORMAL, _C_RN, _C_FRICTION,
 _C_FRICTION_GOAL, _C_ANCHOR, _C_POINT, _PAIR_LAMBDA, _PAIR_LAMBDA_T, _PAIR_NORMAL, _SHAPE_POSE, _PATCH,
 _G_U, _G_RAW, _C_FRICTION_VEL, _PAIR_BOXES, _G_TURN,
 _REST_X, _REST_Q, _REST_MOMENT, _INERTIA, _RADII, _MASS, _INV_MASS, _G_PACK, _BODY_FRICTION,
 _GROUP_KAPPA, _BODY_MAX_DEVIATION, _G_CONT,
 _C_PARTICLE, _C_SHAPE, _C_PATCH, _PAIR_I, _PAIR_J, _PATCH_BODY, _PAIR_GRID,
 _P_BODY, _G_OFF, _G_MEM, _BODY_OFF, _BODY_CORE_SHAPE,
 _C_INNER, _PATCH_SLIDE, _PATCH_CHANGE, _C_SLIP, _FIXED,
 _ATTACHED, _BODY_CONTACT_CONE, _BODY_CONTACT_LAW) = range(len(_PACK))  # fmt: skip
assert [name for name, _, _ in _PACK][_ATTACHED] == "attached" and _PACK[_P_BODY][0] == "p_body"
assert _PACK[_G_RAW][0] == "g_raw" and _PACK[_GROUP_KAPPA][0] == "group_kappa"
assert _PACK[_BODY_MAX_DEVIATION][0] == "body_max_deviation" and _PACK[_G_CONT][0] == "g_cont"
assert _PACK[_PAIR_J][0] == "pair_j" and _PACK[_FIXED][0] == "fixed" and _PACK[_G_FRAME][0] == "g_frame"
assert _PACK[_BODY_CONTACT_CONE][0] == "body_contact_cone" and _PACK[_BODY_CONTACT_LAW][0] == "body_contact_law"
assert _PACK[_PATCH_BODY][0] == "patch_body" and _PACK[_C_FRICTION_VEL][0] == "c_friction_vel"
assert _PACK[_PAIR_BOXES][0] == "pair_boxes" and _PACK[_PAIR_GRID][0] == "pair_grid"
assert _PACK[_G_TURN][0] == "g_turn"


@nb.njit(cache=True, inline="always")
def _view(buf, layout, k):
    """The (rows, cols) array k of a packed buffer: a C-contiguous view, no copy (a slice without a
    step keeps numba's C layout, so every kernel sees the array type it always did)."""
    o = layout[k, 0]
    return buf[o : o + layout[k, 1] * layout[k, 2]].reshape((layout[k, 1], layout[k, 2]))


@nb.njit(cache=True, inline="always")
def _view1(buf, layout, k):
    """The 1-D array k of a packed buffer (a view)."""
    o = layout[k, 0]
    return buf[o : o + layout[k, 1]]


# =================================================================================================
# the step (numba kernel): one call per constraint module
# =================================================================================================


@nb.njit(**KERNEL)
def _sweep(it, iterations, g_turn, rot_iters, body_off, group_kappa, dt, g_off, g_mem, g_pack, g_frame, attached, fixed,
           rest_q, rest_moment, inertia, x, xp, qp, q_pred, spin_kick, group_q, moment, g_u, g_raw, mass, body_core_shape, shape_rigid, rig_x, rig_q, rig_inv_mass, rig_inv_inertia,
           rig_axis, rig_move, imp_lin, imp_ang, coupling_imp, continuum, g_cont):  # fmt: skip
    """One shape-matching sweep over every body's groups, and after the last one each group's
    spin of the step turned back. ``continuum``: some groups have the continuum group energy
    (compliant.continuum_groups)."""
    compliant_sweep(g_turn, rot_iters, body_off, group_kappa, dt, g_off, g_mem, g_pack, g_frame, attached, fixed,
                    rest_q, rest_moment, x, xp, qp, group_q, moment, g_u, g_raw, mass, body_core_shape, shape_rigid,
                    rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, coupling_imp,
                    continuum, g_cont)  # fmt: skip
    if it == iterations - 1:
        # internal forces exert no torque: each group's spin of the step turned back
        balance_torques(g_off, g_mem, g_frame, attached, fixed, inertia, x, xp, qp, q_pred, spin_kick)


@nb.njit(cache=True, parallel=True, error_model="numpy", fastmath={"contract"})
def _bodies_pass(snap, last, g_turn, rot_iters, body_off, group_kappa, dt, g_off, g_mem, g_pack, g_frame, attached,
                 fixed, rest_x, rest_q, rest_moment, inertia, x, xp, qp, q_pred, spin_kick, group_q, moment, g_u, g_raw,
                 mass, p_body, body_core_shape, shape_rigid, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis,
                 rig_move, imp_lin, imp_ang, coupling_imp, continuum, g_cont):  # fmt: skip
    """An iteration's passes that stay inside each body, the bodies on threads: the thesis
    coupling's snap of the attached particles (``snap``), the sweep over the body's groups, and
    after the last sweep (``last``) the groups' torque balance. Where no two bodies share a core
    (compliant.bodies_independent) each touches only its body's particles, groups and core, so
    this is the serial order's result to the bit (snap_attached, then _sweep, over all bodies),
    on any number of threads."""
    for b in nb.prange(body_off.shape[0] - 1):
        lo, hi = body_off[b], body_off[b + 1]
        if snap:
            snap_attached_of(lo, hi, rest_x, rest_q, mass, attached, p_body, body_core_shape, shape_rigid, xp, qp,
                             rig_x, rig_q, imp_lin, imp_ang, coupling_imp, dt)  # fmt: skip
        sweep_body(b, g_turn, rot_iters, body_off, group_kappa, dt, g_off, g_mem, g_pack, g_frame, attached, fixed,
                   rest_q, rest_moment, x, xp, qp, group_q, moment, g_u, g_raw, mass, body_core_shape, shape_rigid,
                   rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, coupling_imp,
                   continuum, g_cont)  # fmt: skip
        if last:
            balance_torques_of(lo, hi, g_off, g_mem, g_frame, attached, fixed, inertia, x, xp, qp, q_pred, spin_kick)


@nb.njit(cache=True, parallel=True, error_model="numpy", fastmath={"contract"})
def _global_bodies_pass(last, gsys, rot_iters, dt, g_turn, body_off, g_off, g_mem, g_pack, g_cont, g_frame, attached,
                        fixed, rest_x, rest_q, rest_moment, inertia, x, xp, qp, q_pred, spin_kick, group_q, moment, mass,
                        p_body, body_core_shape, shape_rigid, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis,
                        imp_lin, imp_ang, coupling_imp):  # fmt: skip
    """The global material solve's pass (global_step.global_body_pass), the bodies on threads: the
    thesis coupling's snap of the attached particles, the body's pass, and after the last pass
    (``last``) the groups' torque balance. Each body's pass reads and writes its own particles,
    groups, block of the factor and core, so where no two bodies share a core this is the serial
    order's result to the bit (snap_attached, global_pass, balance_torques), on any number of
    threads."""
    for b in nb.prange(body_off.shape[0] - 1):
        lo, hi = body_off[b], body_off[b + 1]
        snap_attached_of(lo, hi, rest_x, rest_q, mass, attached, p_body, body_core_shape, shape_rigid, xp, qp, rig_x,
                         rig_q, imp_lin, imp_ang, coupling_imp, dt)  # fmt: skip
        global_body_pass(b, gsys, rot_iters, dt, g_turn, body_off, g_off, g_mem, g_pack, g_cont, attached, rest_q,
                         rest_moment, xp, qp, group_q, moment, mass, p_body, body_core_shape, shape_rigid, rig_x, rig_q,
                         rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin, imp_ang, coupling_imp)  # fmt: skip
        if last:
            balance_torques_of(lo, hi, g_off, g_mem, g_frame, attached, fixed, inertia, x, xp, qp, q_pred, spin_kick)


@nb.njit(cache=True, parallel=True, error_model="numpy", fastmath={"contract"})
def _global_bodies_finish(gsys, rot_iters, dt, body_off, g_off, g_mem, g_pack, g_cont, xp, group_q, mass, p_body,
                          body_core_shape, shape_rigid, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin,
                          imp_ang, coupling_imp):  # fmt: skip
    """global_step.global_finish, the bodies on threads (each its own particles and core: the serial
    result to the bit)."""
    for b in nb.prange(body_off.shape[0] - 1):
        global_body_finish(b, gsys, rot_iters, dt, body_off, g_off, g_mem, g_pack, g_cont, xp, group_q, mass, p_body,
                           body_core_shape, shape_rigid, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin,
                           imp_ang, coupling_imp)  # fmt: skip


@nb.njit(cache=True, parallel=True, error_model="numpy", fastmath={"contract"})
def _bodies_start(x, v, q, omega, group_q, mass, inertia, body_off, rest_moment, gx, gy, gz, damping, dt, xp, qp, q_pred,
                  vd, wd, moment, g_off, g_mem, g_frame):  # fmt: skip
    """predict_particles and group_frames, the bodies on threads (each reads and writes its own
    particles and groups only: the serial result to the bit)."""
    for b in nb.prange(body_off.shape[0] - 1):
        predict_body(b, x, v, q, omega, group_q, mass, inertia, body_off, rest_moment, gx, gy, gz, damping, dt, xp, qp,
                     q_pred, vd, wd, moment)  # fmt: skip
        group_frames_of(body_off[b], body_off[b + 1], g_off, g_mem, mass, x, g_frame)


@nb.njit(cache=True, parallel=True, error_model="numpy", fastmath={"contract"})
def _bodies_end(rest_x, rest_q, mass, attached, p_body, body_core_shape, shape_rigid, x, v, q, omega, xp, qp, wd, inertia,
                spin_kick, rig_x, rig_q, imp_lin, imp_ang, coupling_imp, body_off, dt):  # fmt: skip
    """The step's last snap of the attached particles and the velocities from positions, the bodies
    on threads (each body's own particles and core: the serial result to the bit)."""
    for b in nb.prange(body_off.shape[0] - 1):
        lo, hi = body_off[b], body_off[b + 1]
        snap_attached_of(lo, hi, rest_x, rest_q, mass, attached, p_body, body_core_shape, shape_rigid, xp, qp, rig_x,
                         rig_q, imp_lin, imp_ang, coupling_imp, dt)  # fmt: skip
        update_velocities_of(lo, hi, x, v, q, omega, xp, qp, wd, inertia, spin_kick, attached, dt)


@nb.njit(**KERNEL)
def _step(
    # state (updated in place on success)
    x, v, q, omega, group_q, anchor_shape, anchor_x, anchor_slide,
    # colliders (read only) and rigid outputs
    rig_x0, rig_q0, rig_v, rig_w, rig_inv_mass, rig_inv_inertia, rig_axis, rig_force, rig_gravity, rig_move, shape_kind,
    shape_params,
    shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q, imp_lin, imp_ang, coupling_imp,
    # the model's arrays and every scratch array of the step, packed (see TissueSolver._pack and _view)
    f_pack, i_pack, b_pack, layout,
    # parameters
    dt, iterations, rot_iters, gx, gy, gz, damping, coupling, margin, continuum, counts, threads, more_kinds,
    gsys,
):  # fmt: skip
    """One tissue step. Returns 0, or 1 if a contact buffer was too small (``counts`` then holds
    the sizes needed and the state is untouched, so the caller can grow the buffers and retry).

    ``threads`` is None for the serial passes, or True for the pads' passes on numba's threads
    (_bodies_start, _bodies_pass, limit_and_anchor_bodies, _bodies_end). The test is on None
    because numba prunes such a branch when it compiles: the None overload holds no parallel code,
    so a one-thread process never loads it. Loading parallel code starts numba's thread pool, and
    once started the pool refuses any change of NUMBA_NUM_THREADS, which training sets for its env
    processes.

    ``more_kinds`` is None when every shape is a plane, sphere, box, cylinder or capsule, True
    when there is a cone, elliptic cylinder or hull (collision.shape_distance_of): the same test
    on None, so a world of the first five kinds runs the code it always ran.

    ``gsys`` is None for the material's Gauss-Seidel sweep over the groups (compliant.py), or the
    arrays of a global_step.GlobalSystem for its global solve (SimConfig.material_solve "global"),
    whose pads' blocks run on threads with ``threads`` (_global_bodies_pass); pruned on None as
    above."""
    # The model's and the scratch arrays arrive packed in three flat buffers: numba unboxes every
    # array argument on each call (~0.1 us apiece), and ~45 separate arrays cost ~5 us a step.
    rest_x, rest_q = _view(f_pack, layout, _REST_X), _view(f_pack, layout, _REST_Q)
    rest_moment, inertia = _view(f_pack, layout, _REST_MOMENT), _view(f_pack, layout, _INERTIA)
    radii, mass, inv_mass = _view(f_pack, layout, _RADII), _view1(f_pack, layout, _MASS), _view1(f_pack, layout, _INV_MASS)
    g_pack = _view(f_pack, layout, _G_PACK)
    body_friction, group_kappa = _view(f_pack, layout, _BODY_FRICTION), _view1(f_pack, layout, _GROUP_KAPPA)
    body_max_deviation = _view1(f_pack, layout, _BODY_MAX_DEVIATION)
    g_cont = _view(f_pack, layout, _G_CONT)
    p_body, g_off, g_mem = _view1(i_pack, layout, _P_BODY), _view1(i_pack, layout, _G_OFF), _view1(i_pack, layout, _G_MEM)
    body_off, body_core_shape = _view1(i_pack, layout, _BODY_OFF), _view1(i_pack, layout, _BODY_CORE_SHAPE)
    attached = _view1(b_pack, layout, _ATTACHED)
    body_contact_cone = _view1(b_pack, layout, _BODY_CONTACT_CONE)
    body_contact_law = _view1(b_pack, layout, _BODY_CONTACT_LAW)
    patch_body = _view1(i_pack, layout, _PATCH_BODY)
    xp, qp, q_pred = _view(f_pack, layout, _XP), _view(f_pack, layout, _QP), _view(f_pack, layout, _Q_PRED)
    vd, wd, moment = _view(f_pack, layout, _VD), _view(f_pack, layout, _WD), _view(f_pack, layout, _MOMENT)
    spin_kick, g_frame = _view(f_pack, layout, _SPIN_KICK), _view(f_pack, layout, _G_FRAME)
    c_lambda = _view1(f_pack, layout, _C_LAMBDA)
    c_normal, c_rn = _view(f_pack, layout, _C_NORMAL), _view1(f_pack, layout, _C_RN)
    c_friction, c_friction_goal = _view(f_pack, layout, _C_FRICTION), _view(f_pack, layout, _C_FRICTION_GOAL)
    c_anchor, c_point = _view(f_pack, layout, _C_ANCHOR), _view(f_pack, layout, _C_POINT)
    pair_lambda, pair_lambda_t = _view1(f_pack, layout, _PAIR_LAMBDA), _view1(f_pack, layout, _PAIR_LAMBDA_T)
    pair_normal, shape_pose = _view(f_pack, layout, _PAIR_NORMAL), _view(f_pack, layout, _SHAPE_POSE)
    patch = _view(f_pack, layout, _PATCH)
    g_u, g_raw = _view(f_pack, layout, _G_U), _view(f_pack, layout, _G_RAW)
    c_friction_vel = _view(f_pack, layout, _C_FRICTION_VEL)
    c_particle, c_shape, c_patch = _view1(i_pack, layout, _C_PARTICLE), _view1(i_pack, layout, _C_SHAPE), _view1(i_pack, layout, _C_PATCH)
    pair_i, pair_j = _view1(i_pack, layout, _PAIR_I), _view1(i_pack, layout, _PAIR_J)
    pair_grid, pair_boxes = _view1(i_pack, layout, _PAIR_GRID), _view1(f_pack, layout, _PAIR_BOXES)
    c_inner, patch_slide = _view1(b_pack, layout, _C_INNER), _view1(b_pack, layout, _PATCH_SLIDE)
    patch_change, fixed = _view1(b_pack, layout, _PATCH_CHANGE), _view1(b_pack, layout, _FIXED)
    c_slip = _view1(b_pack, layout, _C_SLIP)
    g_turn = _view1(f_pack, layout, _G_TURN)
    # --- predict rigid bodies: semi-implicit Euler, as pybullet will integrate them (thesis 5.2.2)
    predict_rigid(rig_x0, rig_q0, rig_v, rig_w, rig_gravity, rig_move, rig_inv_mass, rig_force, gx, gy, gz, dt, rig_x,
                  rig_q, imp_lin, imp_ang, coupling_imp)  # fmt: skip
    # --- predict particles (PBD Alg. 1 lines 5-11; Mueller & Chentanez 2011 sec. 3):
    #     v += g dt; damping of the deviation from each body's rigid motion; x* = x + v dt;
    #     q* = [w_hat sin(|w| dt / 2), cos(|w| dt / 2)] q
    if threads is not None:
        _bodies_start(x, v, q, omega, group_q, mass, inertia, body_off, rest_moment, gx, gy, gz, damping, dt, xp, qp,
                      q_pred, vd, wd, moment, g_off, g_mem, g_frame)  # fmt: skip
    else:
        predict_particles(x, v, q, omega, group_q, mass, inertia, body_off, rest_moment, gx, gy, gz, damping, dt, xp,
                          qp, q_pred, vd, wd, moment)  # fmt: skip
        group_frames(g_off, g_mem, mass, x, g_frame)  # the groups' start-of-step torque balance data
    # --- contact candidates, against predicted rigid poses
    nc = collect_contacts(xp, x, radii, p_body, attached, body_core_shape, shape_kind, shape_params, shape_rigid,
                          shape_local_x, shape_local_q, rig_x, rig_q, margin, c_particle, c_shape, c_inner,
                          shape_pose, more_kinds)  # fmt: skip
    npairs = collect_pairs(xp, x, radii, body_off, margin, pair_i, pair_j, pair_grid, pair_boxes)
    counts[0] = nc
    counts[1] = npairs
    if nc > c_particle.shape[0] or npairs > pair_i.shape[0]:
        return 1
    clear_multipliers(nc, c_lambda, c_friction)
    clear_multipliers(npairs, pair_lambda, pair_lambda_t)
    ns = shape_kind.shape[0]
    load_anchors(nc, c_particle, c_shape, c_inner, x, p_body, shape_rigid, shape_local_x, shape_local_q, rig_x0, rig_q0,
                 anchor_shape, anchor_x, anchor_slide, ns, c_anchor, c_patch, patch_slide, patch_change, patch_body,
                 body_contact_law)  # fmt: skip
    # The material (compliant.py): the members attached to a core are held by it through the solve
    # (anchors.mark_fixed), and each group's displacement field starts at zero.
    mark_fixed(attached, p_body, body_core_shape, fixed)
    g_u[...] = 0.0
    if gsys is not None:
        gsys[5][...] = 0.0  # the material's displacement this step (global_step.global_pass)
    # --- Gauss-Seidel iterations
    for it in range(iterations):
        if gsys is not None:
            # the material over all groups at once (global_step.py), each body's block on its own; the
            # thesis coupling's snap first, as below (the solver admits the global solve under that
            # coupling only)
            if threads is not None:
                _global_bodies_pass(it == iterations - 1, gsys, rot_iters, dt, g_turn, body_off, g_off, g_mem, g_pack,
                                    g_cont, g_frame, attached, fixed, rest_x, rest_q, rest_moment, inertia, x, xp, qp,
                                    q_pred, spin_kick, group_q, moment, mass, p_body, body_core_shape, shape_rigid,
                                    rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin, imp_ang,
                                    coupling_imp)  # fmt: skip
            else:
                snap_attached(rest_x, rest_q, mass, attached, p_body, body_core_shape, shape_rigid, xp, qp, rig_x,
                              rig_q, imp_lin, imp_ang, coupling_imp, dt)  # fmt: skip
                global_pass(gsys, rot_iters, dt, g_turn, body_off, g_off, g_mem, g_pack, g_cont, attached, rest_q,
                            rest_moment, xp, qp, group_q, moment, mass, p_body, body_core_shape, shape_rigid, rig_x,
                            rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin, imp_ang, coupling_imp)  # fmt: skip
                if it == iterations - 1:
                    balance_torques(g_off, g_mem, g_frame, attached, fixed, inertia, x, xp, qp, q_pred, spin_kick)
        elif threads is not None:
            _bodies_pass(coupling == COUPLING_THESIS, it == iterations - 1, g_turn, rot_iters, body_off, group_kappa,
                         dt, g_off, g_mem, g_pack, g_frame, attached, fixed, rest_x, rest_q, rest_moment, inertia, x, xp,
                         qp, q_pred, spin_kick, group_q, moment, g_u, g_raw, mass, p_body, body_core_shape, shape_rigid,
                         rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, coupling_imp,
                         continuum, g_cont)  # fmt: skip
        else:
            if coupling == COUPLING_THESIS:
                # attached particles onto their cores' predicted spots before the groups take them as
                # held there: first their prediction error, then whatever a contact moved them by, the
                # core taking it as an impulse (the thesis coupling's snap, 5.1.3, each iteration)
                snap_attached(rest_x, rest_q, mass, attached, p_body, body_core_shape, shape_rigid, xp, qp, rig_x,
                              rig_q, imp_lin, imp_ang, coupling_imp, dt)  # fmt: skip
            _sweep(it, iterations, g_turn, rot_iters, body_off, group_kappa, dt, g_off, g_mem, g_pack, g_frame, attached,
                   fixed, rest_q, rest_moment, inertia, x, xp, qp, q_pred, spin_kick, group_q, moment, g_u, g_raw, mass,
                   body_core_shape, shape_rigid, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move,
                   imp_lin, imp_ang, coupling_imp, continuum, g_cont)  # fmt: skip
        if gsys is not None:
            project_contacts(gsys, nc, c_particle, c_shape, c_inner, c_lambda, c_normal, c_rn, xp, qp, radii, inv_mass,
                             p_body, shape_kind, shape_params, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q,
                             rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, dt, shape_pose,
                             more_kinds)  # fmt: skip
        else:
            project_shape_contacts(nc, c_particle, c_shape, c_inner, c_lambda, c_normal, c_rn, xp, qp, radii,
                                   inv_mass, shape_kind, shape_params, shape_rigid, shape_local_x, shape_local_q, rig_x,
                                   rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, dt,
                                   shape_pose, more_kinds)  # fmt: skip
        project_pairs(npairs, pair_i, pair_j, pair_lambda, pair_normal, xp, qp, radii, inv_mass)
        # Friction inside the loop, after the normal corrections: static friction is then a
        # constraint of the same Gauss-Seidel solve as the shape matching. Applied once after the
        # loop it could only stop the touching particles, and a block on a ramp crept downhill
        # at a steady ~0.1 m/s below the friction angle.
        if gsys is not None:
            # friction moves a particle by its compliance in the pad (global_step.friction_weights)
            friction_weights(gsys, -1.0, nc, c_particle, c_patch, c_lambda, c_normal, c_friction, inv_mass, p_body)
            friction_patches(nc, c_particle, c_shape, c_patch, c_lambda, c_friction, c_friction_goal, c_normal, c_rn,
                             c_anchor, c_point, xp, gsys[10], body_friction, ns, shape_rigid, shape_local_x,
                             shape_local_q, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin,
                             imp_ang, dt, shape_pose, patch, patch_slide, patch_change, it == iterations - 1,
                             body_contact_cone, c_slip, patch_body)  # fmt: skip
            friction_weights(gsys, 1.0, nc, c_particle, c_patch, c_lambda, c_normal, c_friction, inv_mass, p_body)
        else:
            friction_patches(nc, c_particle, c_shape, c_patch, c_lambda, c_friction, c_friction_goal, c_normal, c_rn,
                             c_anchor, c_point, xp, inv_mass, body_friction, ns, shape_rigid, shape_local_x,
                             shape_local_q, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin,
                             imp_ang, dt, shape_pose, patch, patch_slide, patch_change, it == iterations - 1,
                             body_contact_cone, c_slip, patch_body)  # fmt: skip
        friction_pairs(npairs, pair_i, pair_j, pair_lambda, pair_lambda_t, pair_normal, x, xp, inv_mass, p_body,
                       body_friction)  # fmt: skip
        # the strain limit, after friction: what a snagged particle's friction gives way to
        if threads is not None:
            limit_and_anchor_bodies(coupling == COUPLING_CONSISTENT, body_off, rest_x, inv_mass, attached, p_body,
                                    body_core_shape, body_max_deviation, shape_rigid, xp, rig_x, rig_q, rig_inv_mass,
                                    rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, dt)  # fmt: skip
        else:
            limit_deviation(rest_x, inv_mass, attached, p_body, body_core_shape, body_max_deviation, shape_rigid, xp,
                            rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, dt)  # fmt: skip
            if coupling == COUPLING_CONSISTENT:
                project_anchors(rest_x, inv_mass, attached, p_body, body_core_shape, shape_rigid, xp, rig_x, rig_q,
                                rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, dt)  # fmt: skip
    if gsys is not None:
        if threads is not None:
            _global_bodies_finish(gsys, rot_iters, dt, body_off, g_off, g_mem, g_pack, g_cont, xp, group_q, mass,
                                  p_body, body_core_shape, shape_rigid, rig_x, rig_q, rig_inv_mass, rig_inv_inertia,
                                  rig_axis, imp_lin, imp_ang, coupling_imp)  # fmt: skip
        else:
            global_finish(gsys, rot_iters, dt, body_off, g_off, g_mem, g_pack, g_cont, xp, group_q, mass, p_body,
                          body_core_shape, shape_rigid, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin,
                          imp_ang, coupling_imp)  # fmt: skip
    # --- coupling to the cores (thesis 5.1.3): error -> impulse, snap back; then velocities from
    #     positions (PBD Alg. 1 lines 18-21); angular velocity from q* q^-1 on the short arc
    #     (Mueller & Chentanez 2011 sec. 3)
    if threads is not None:
        _bodies_end(rest_x, rest_q, mass, attached, p_body, body_core_shape, shape_rigid, x, v, q, omega, xp, qp, wd,
                    inertia, spin_kick, rig_x, rig_q, imp_lin, imp_ang, coupling_imp, body_off, dt)  # fmt: skip
    else:
        snap_attached(rest_x, rest_q, mass, attached, p_body, body_core_shape, shape_rigid, xp, qp, rig_x, rig_q,
                      imp_lin, imp_ang, coupling_imp, dt)  # fmt: skip
        update_velocities(x, v, q, omega, xp, qp, wd, inertia, spin_kick, attached, dt)
    # --- the velocity half of kinetic friction; anchors kept for the next step
    friction_velocity_pass(nc, c_particle, c_shape, c_patch, c_lambda, c_friction, c_normal, c_rn, x, v, inv_mass,
                           shape_rigid, rig_x0, rig_q0, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move,
                           imp_lin, imp_ang, dt, patch_slide, patch_change, c_friction_vel, body_friction, ns)  # fmt: skip
    store_anchors(nc, c_particle, c_shape, c_patch, c_lambda, c_anchor, x, shape_rigid, shape_local_x, shape_local_q,
                  rig_x, rig_q, patch_slide, patch_change, anchor_shape, anchor_x, anchor_slide, c_slip)  # fmt: skip
    return 0


# =================================================================================================
# Python front end
# =================================================================================================


def damping_of(model: TissueModel, sim: SimConfig) -> float:
    """The deformation damping rate [1/s] of ``model``'s tissue under ``sim``: ``sim.damping``, or
    the material's default, config.COMPLIANT_DAMPING."""
    if sim.damping is not None:
        return sim.damping
    return COMPLIANT_DAMPING


class TissueSolver:
    """Owns the scratch buffers of one model and runs :func:`_step` on it."""

    def __init__(self, model: TissueModel, sim: SimConfig) -> None:
        self.model = model
        self.sim = sim
        n = model.particle_count
        self._counts = np.zeros(2, dtype=np.int64)
        model_arrays = {
            "rest_x": model.particle_rest_x, "rest_q": model.particle_rest_q, "rest_moment": rest_moments(model),
            "inertia": model.particle_inertia_local(), "radii": model.particle_radii, "mass": model.particle_mass,
            "inv_mass": model.particle_inv_mass, "g_pack": group_pack(model),
            "body_friction": model.body_friction, "p_body": model.particle_body, "g_off": model.group_offsets,
            "g_mem": model.group_members, "body_off": model.body_particle_offsets,
            "body_core_shape": model.body_core_shape, "attached": model.particle_attached,
            "group_kappa": model.group_kappa, "g_cont": model.group_continuum,
            "body_max_deviation": model.body_max_deviation, "body_contact_cone": model.body_contact_cone,
            "body_contact_law": model.body_contact_law,
        }  # fmt: skip
        self._sizes = {"n": n, "contacts": 4 * n + 16, "pairs": 4 * n + 16, "shapes": 0, "patches": 0,
                       "members": model.group_members.shape[0], "groups": model.group_offsets.shape[0],
                       "bodies": model.body_count, "body_offsets": model.body_particle_offsets.shape[0]}  # fmt: skip
        self._sizes["pair_grid"], self._sizes["pair_boxes"] = pair_scratch_sizes(n, model.body_count)
        self._scratch: dict[str, np.ndarray] = {}
        self._args_for: tuple | None = None
        self._pack(tuple(self._sizes))
        for name, a in model_arrays.items():
            if self._scratch[name].shape != a.shape:
                raise ValueError(f"TissueModel array {name!r} has shape {a.shape}, expected {self._scratch[name].shape}")
            self._scratch[name][...] = a
        self._rigid_buffers_for = -1
        self._threads = sim.solver_threads()  # checked here: a bad count fails at construction
        self._threaded = False
        self._threaded_for: np.ndarray | None = None
        self._more_kinds: bool | None = None
        self._kinds_for: np.ndarray | None = None
        self._warned_serial = False
        self._global: GlobalSystem | None = None
        self._global_arrays()  # the global solve's factor now: a bad setting fails at construction

    def _pack(self, resized: tuple[str, ...]) -> None:
        """(Re)build the packed scratch buffers for ``self._sizes``. Arrays sized by an entry of
        ``resized`` start at zero (as freshly allocated arrays did); every other array keeps its
        contents. The arrays stay reachable from Python as views (``self._scratch[name]``)."""
        old = self._scratch
        sizes = self._sizes
        layout = np.zeros((len(_PACK), 3), dtype=np.int64)
        new: dict[str, np.ndarray] = {}
        bufs = []
        k = 0
        for table, dtype in ((_F_PACK, np.float64), (_I_PACK, np.int32), (_B_PACK, np.bool_)):
            total = sum(sizes[size] * max(cols, 1) for _, size, cols in table)
            buf = np.zeros(max(total, 1), dtype=dtype)  # never empty: a 0-size buffer is one too
            o = 0
            for name, size, cols in table:
                rows = sizes[size]
                layout[k] = (o, rows, max(cols, 1))
                a = buf[o : o + rows * max(cols, 1)]
                a = a.reshape((rows, cols)) if cols else a
                if size not in resized:
                    a[...] = old[name]
                new[name] = a
                o += rows * max(cols, 1)
                k += 1
            bufs.append(buf)
        self._scratch = new
        self._packed = (*bufs, layout)
        self._args_for = None

    def _rigid_buffers(self, count: int) -> None:
        """The rigid outputs, one row per rigid slot, each row RIGID_ROW floats wide of which the
        first 3 (4: the orientation) are used: every pad's passes add to its own core's row of the
        impulses at each attached member (compliant.deliver_to_core), and on threads two cores'
        rows in one cache line would bounce it between the cores at every add (false sharing);
        rows a cache line apart or more do not share one. The kernels index the columns they use
        and never read the rest; StepOutput hands out views of the used columns."""
        if self._rigid_buffers_for != count:
            self._rig_x = np.zeros((count, RIGID_ROW))
            self._rig_q = np.zeros((count, RIGID_ROW))
            self._imp_lin = np.zeros((count, RIGID_ROW))
            self._imp_ang = np.zeros((count, RIGID_ROW))
            self._coupling_imp = np.zeros((count, RIGID_ROW))
            self._outputs = (self._rig_x[:, :3], self._rig_q[:, :4], self._imp_lin[:, :3], self._imp_ang[:, :3],
                             self._coupling_imp[:, :3])  # fmt: skip
            self._rigid_buffers_for = count
            self._args_for = None

    def _shape_buffer(self, count: int) -> None:
        if self._sizes["shapes"] != count:
            self._sizes["shapes"] = count
            self._sizes["patches"] = self._patch_rows(count, self._sizes["contacts"])
            self._pack(("shapes", "patches"))
            self._args_for = None

    def _patch_rows(self, shapes: int, contacts: int) -> int:
        """One friction patch per (tissue body, shape), and under the contact law one per contact
        slot as well (friction.load_anchors)."""
        rows = self.model.body_count * shapes
        return rows + contacts if self.model.body_contact_law.any() else rows

    def _fixed_args(self) -> None:
        """The arguments of _step that do not change from step to step (the rigid outputs, the packed
        model and scratch arrays, the parameters) as one tuple: one splat per call instead of ~20
        attribute loads. Rebuilt whenever a buffer or the config is replaced (``_args_for`` is
        reset then, or is no longer ``self.sim``)."""
        sim = self.sim
        coupling = COUPLING_CONSISTENT if sim.coupling == "consistent" else COUPLING_THESIS
        self.damping = damping_of(self.model, sim)
        turn_rates(self.model.group_kappa, sim.dt, sim.iterations, self._scratch["g_turn"])
        self._tail_args = (
            self._rig_x, self._rig_q, self._imp_lin, self._imp_ang, self._coupling_imp,
            *self._packed,
            sim.dt, sim.iterations, sim.rotation_iterations, 0.0, 0.0, -sim.gravity, self.damping, coupling,
            sim.contact_margin, self.model.continuum, self._counts, True if self._threaded else None,
            self._more_kinds, self._global_arrays(),
        )  # fmt: skip
        self._args_for = sim

    def _global_arrays(self) -> tuple | None:
        """The global material solve's arrays for the kernel (None for the sweep over the groups),
        its factor made for ``sim.dt`` once and again whenever the step length changes."""
        if self.sim.material_solve != "global":
            return None
        # (SimConfig refuses the global solve with any coupling but the thesis one)
        sim = self.sim
        g = self._global
        if (g is None or g.dt != sim.dt or g.linear_solve != sim.global_linear_solve
                or int(g.cycles[0]) != sim.multigrid_cycles):  # fmt: skip
            self._global = global_system(self.model, sim.dt, sim.global_linear_solve, sim.multigrid_cycles)
        return self._global.arrays()

    def step(self, state: TissueState, col: Colliders) -> StepOutput:
        """Advance ``state`` by one step of ``sim.dt`` in place; returns predicted rigid poses and
        the impulses the tissue put on each rigid body (to be applied by the rigid simulation)."""
        # Per-step Python work is a noticeable share of a ~100 us tissue step: the checks below are
        # inline (col.rigid_count and friends are properties), the fixed arguments come from tuples.
        if col.rigid_inv_mass.shape[0] != self._rigid_buffers_for:
            self._rigid_buffers(col.rigid_inv_mass.shape[0])
        if col.shape_kind.shape[0] != self._sizes["shapes"]:
            self._shape_buffer(col.shape_kind.shape[0])
        if col.shape_kind is not self._kinds_for:
            # which kernels the shapes need (collision.shape_distance_of), read once per array as
            # shape_rigid is below: a Colliders' shape arrays are replaced, not edited in place
            self._more_kinds = more_kinds_of(col.shape_kind)
            self._kinds_for = col.shape_kind
            self._args_for = None
        if col.shape_rigid is not self._threaded_for or self._args_for is not self.sim:
            # the pads on threads only where no two share a core (_bodies_pass)
            self._threads = self.sim.solver_threads()
            self._threaded = self._threads > 1 and bodies_independent(self.model, col.shape_rigid)
            if self._threads > 1 and not self._threaded and not self._warned_serial:
                # asked for, not given: say so once rather than run serial in silence
                warnings.warn(
                    f"tissue solver: {self._threads} threads asked for, running on one: the parallel passes "
                    "split the work by pad, and here a pad has no core of its own (pads sharing a core, a pad "
                    "without one, or particles outside every pad)", RuntimeWarning, stacklevel=2)  # fmt: skip
                self._warned_serial = True
            self._threaded_for = col.shape_rigid
            self._args_for = None
        if self._threaded:
            before = nb.get_num_threads()
            nb.set_num_threads(self._threads)
            try:
                return self._step(state, col)
            finally:
                nb.set_num_threads(before)
        return self._step(state, col)

    def _step(self, state: TissueState, col: Colliders) -> StepOutput:
        while True:
            if self._args_for is not self.sim:
                self._fixed_args()
            code = _step(
                state.particle_x, state.particle_v, state.particle_q, state.particle_omega, state.group_q,
                state.particle_anchor_shape, state.particle_anchor_x, state.particle_anchor_slide,
                col.rigid_x, col.rigid_q, col.rigid_v, col.rigid_w, col.rigid_inv_mass, col.rigid_inv_inertia,
                col.rigid_axis, col.rigid_force, col.rigid_gravity, col.rigid_in_solve, col.shape_kind,
                col.shape_params, col.shape_rigid, col.shape_local_x, col.shape_local_q,
                *self._tail_args,
            )  # fmt: skip
            if code == 0:
                break
            # A buffer was too small: nothing was changed; grow it and run the step again.
            grown = []
            if self._counts[0] > self._sizes["contacts"]:
                self._sizes["contacts"] = int(2 * self._counts[0])
                grown.append("contacts")
                if self.model.body_contact_law.any():
                    self._sizes["patches"] = self._patch_rows(self._sizes["shapes"], self._sizes["contacts"])
                    grown.append("patches")
            if self._counts[1] > self._sizes["pairs"]:
                self._sizes["pairs"] = int(2 * self._counts[1])
                grown.append("pairs")
            self._pack(tuple(grown))
        contact_count, pair_count = self._counts.tolist()
        # positional: StepOutput's fields in order (keywords cost ~1 us a step here)
        return StepOutput(*self._outputs, contact_count, pair_count)

    def last_contacts(self) -> LastContacts:
        """The particle-shape contacts of the last step, as the solve left them (views, valid until
        the next step): what a tactile reading bins (fingers/tactile.py)."""
        sc = self._scratch
        return LastContacts(int(self._counts[0]), sc["c_particle"], sc["c_inner"], sc["c_lambda"], sc["c_normal"],
                            sc["c_friction"], sc["c_patch"], sc["patch_slide"], sc["patch_change"], sc["c_shape"],
                            sc["c_friction_vel"], self.model.body_count * self._sizes["shapes"])  # fmt: skip

    def contact_normal_force(self, shape: int) -> np.ndarray:
        """Normal force each tissue body pressed on shape ``shape`` with during the last step [N],
        shape (bodies,). A contact's accumulated normal multiplier lambda is a positional impulse
        [kg m] (Mueller et al. 2020, eq. 6), so its force over the step is lambda / dt^2."""
        m = self.model
        out = np.zeros(m.body_count)
        nc = int(self._counts[0])
        sc = self._scratch
        _sum_contact_lambda(sc["c_shape"], sc["c_inner"], sc["c_particle"], sc["c_lambda"], nc, shape, m.particle_body,
                            out)  # fmt: skip
        return out / (self.sim.dt * self.sim.dt)

    def penetration(self, state: TissueState, col: Colliders) -> tuple[float, float]:
        """(deepest particle overlap with any other rigid shape, deepest outer-particle intrusion into
        its own core) at the colliders' current poses [m]."""
        m = self.model
        out = np.zeros(2)
        max_penetration(state.particle_x, state.particle_q, m.particle_radii, m.particle_body, m.particle_attached,
                        m.body_core_shape, col.shape_kind, col.shape_params, col.shape_rigid, col.shape_local_x,
                        col.shape_local_q, col.rigid_x, col.rigid_q, out, more_kinds_of(col.shape_kind))  # fmt: skip
        return float(out[0]), float(out[1])


@nb.njit(cache=True)
def _sum_contact_lambda(c_shape, c_inner, c_particle, c_lambda, nc, shape, particle_body, out):
    """out[body] += lambda of each of the first ``nc`` contacts with ``shape`` that is not a
    particle's contact with its own core, in contact order (the sums np.add.at made, a compiled
    loop: it runs every physics step)."""
    for i in range(nc):
        if c_shape[i] == shape and not c_inner[i]:
            out[particle_body[c_particle[i]]] += c_lambda[i]
