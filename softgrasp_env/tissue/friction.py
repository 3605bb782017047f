"""Coulomb friction of tissue contacts: static and kinetic, per contact patch, with anchors.

Friction acts at position level inside the Gauss-Seidel loop (Macklin et al. 2014, "Unified
Particle Physics for Real-Time Applications", eq. 23-24; Mueller et al. 2020, "Detailed Rigid
Body Simulation with Extended Position Based Dynamics", sec. 3.5), against a rigid body two-way
with its generalised inverse mass, like the normal contact. What decides whether a squeezed
cylinder is held (iff 2 mu_s N >= m g) lives here, so three points are made exact:

- **Anchors** (state.particle_anchor_*): a sticking contact holds its particle at the spot of the
  shape where it began to stick, not merely against the slip of this step. Static friction is then
  a position constraint over many steps: the part a 3-iteration solve leaves one step is taken back
  in the next, and a held cylinder does not creep (before: 13 deg of tilt after 22 s of holding).
- **Patches**: Coulomb's cone is applied to what one tissue body transmits to one shape as a whole
  (a soft-finger contact, friction_patches), so a pad breaks loose at mu_s, not when its lightest
  contacts do.
- **Kinetic friction half on positions, half on velocities**, which removes the v dt / 2 that
  position-level friction takes off every slide (friction_velocity_pass).
- **Cones per contact** (optional, TissueConfig.contact_cone): within a sticking patch, each
  contact's share of the self-equilibrated friction is bounded by its own cone, mu_s lambda_n, and
  what that sheds in the patch's plane goes to the patch's contacts by their normal loads, so the
  patch still transmits what its law decided (_apply_with_cones). Without it (the default,
  _apply_patch_law) a pad wrapped round the cylinder held it with friction alone after its squeeze
  was gone; with it a squeezed pad's compression moves with the iteration count (config.py,
  TissueConfig.contact_cone), which is why it is not the default yet.

- **Coulomb per contact** (TissueConfig.friction_law "contact"): every contact is a patch of its
  own, so the same decision bounds each contact by its own cone with its own stick/slide state and
  anchor; nothing self-equilibrated is left unbounded, and partial slip follows from the contacts'
  normal loads.

friction_pairs (tissue against tissue of another body) keeps the per-step, per-contact rule.

Per step: load_anchors -> friction_patches in every iteration -> (velocity update) ->
friction_velocity_pass -> store_anchors.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from .jit import KERNEL
from .rigid import generalized_inv_mass, rigid_apply, shape_world_pose
from .rotation import qconj, qrotate


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


# Like the contact kernels, each friction kernel loops over all its rows: one compiled call per
# pass (see contacts.py).
@nb.njit(**KERNEL)
def load_anchors(nc, c_particle, c_shape, c_inner, x0, p_body, shape_rigid, shape_local_x, shape_local_q, rig_x0,
                  rig_q0, anchor_shape, anchor_x, anchor_slide, ns, c_anchor, c_patch, patch_slide, patch_change,
                  patch_body, body_contact_law):  # fmt: skip
    """Give every contact its anchor and its patch. Under the patch law a patch is (tissue body,
    shape), row body * ns + shape; under the contact law (``body_contact_law``, TissueConfig.
    friction_law "contact") every contact is a patch of its own, row B * ns + c, so that Coulomb's
    law is decided per contact by the same code. ``patch_body`` gets each patch's body. A contact
    that stuck last step keeps its anchor; a new one anchors where the particle's centre was at the
    start of this step, in the shape's frame (the same displacement as 'slip since the step
    began'). A patch starts the step sliding if it ended the last one sliding (its contact did,
    under the contact law)."""
    for p in range(patch_slide.shape[0]):
        patch_slide[p] = False
        patch_change[p] = False
    base = body_contact_law.shape[0] * ns
    for c in range(nc):
        if c_inner[c]:
            c_patch[c] = -1
            continue
        i = c_particle[c]
        s = c_shape[c]
        b = p_body[i]
        p = base + c if body_contact_law[b] else b * ns + s
        c_patch[c] = p
        patch_body[p] = b
        found = False
        for k in range(anchor_shape.shape[1]):
            if anchor_shape[i, k] == s:
                for a in range(3):
                    c_anchor[c, a] = anchor_x[i, k, a]
                if anchor_slide[i, k]:
                    patch_slide[p] = True
                found = True
                break
        if not found:
            sx, sq = shape_world_pose(s, shape_rigid, shape_local_x, shape_local_q, rig_x0, rig_q0)
            loc = qrotate(qconj(sq), (x0[i, 0] - sx[0], x0[i, 1] - sx[1], x0[i, 2] - sx[2]))
            for a in range(3):
                c_anchor[c, a] = loc[a]


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _patch_lever(c, p, c_point, patch):
    """Contact c's lever arm from its patch's centre of pressure, in the plane of the patch's mean
    normal, and that unit normal: (rx, ry, rz, mx, my, mz) (pass 1 of friction_patches summed
    what they come from)."""
    inv_n = 1.0 / patch[p, 0]
    mx, my, mz = patch[p, 4], patch[p, 5], patch[p, 6]
    ml = math.sqrt(mx * mx + my * my + mz * mz)
    mx, my, mz = mx / ml, my / ml, mz / ml
    rx = c_point[c, 0] - patch[p, 1] * inv_n
    ry = c_point[c, 1] - patch[p, 2] * inv_n
    rz = c_point[c, 2] - patch[p, 3] * inv_n
    rd = rx * mx + ry * my + rz * mz
    return rx - rd * mx, ry - rd * my, rz - rd * mz, mx, my, mz


@nb.njit(**KERNEL)
def friction_patches(
    nc, c_particle, c_shape, c_patch, c_lambda, c_friction, c_friction_goal, c_normal, c_rn, c_anchor, c_point, xp, inv_mass,
    body_friction, ns, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q, rig_inv_mass, rig_inv_inertia,
    rig_axis, rig_move, imp_lin, imp_ang, dt, shape_pose, patch, patch_slide, patch_change, last, body_cone, c_slip,
    patch_body,
):  # fmt: skip
    """One Gauss-Seidel pass of Coulomb friction over all tissue-shape contacts.

    Each contact would cancel its particle's tangential offset from its anchor (static friction at
    position level, Mueller et al. 2020 sec. 3.5, but against the anchor rather than the step's
    start, so that an unconverged solve cannot creep: what one step leaves is taken back by the
    next). Coulomb's law is applied per patch, one tissue body against one shape, as for a soft
    finger (Howe & Cutkosky 1996): what the patch transmits is its net tangential force F and its
    moment M about the normal through its centre of pressure; the patch sticks while
    (|F| / (mu_s N))^2 + (M / (mu_s N e))^2 <= 1 (ellipsoidal limit surface; N the summed normal
    impulse, e = sum(lambda_n r) / N the pressure-weighted radius, so pure torsion is bounded by
    mu sum(lambda_n r) exactly). The rest of the contacts' friction is self-equilibrated (it keeps
    a squeezed pad from spreading) and transmits nothing: it is kept while the patch sticks and
    vanishes when it slides, as it does in gross sliding, when every contact slides the same way.
    Decided per contact instead, the lightly loaded contacts of a pad on a ramp fell to mu_k one by
    one and the pad broke loose at 0.84 mu_s; bounded by the sum of |f| per contact, the squeezed
    grasp lost 7 % of its hold to the pad's lateral friction.

    A sliding patch applies half of the kinetic impulse mu_k N here and half on the velocities
    (friction_velocity_pass): for constant deceleration that gives the exact displacement
    v dt - a dt^2 / 2 and velocity v - a dt, where friction at position level alone shortens every
    slide by v dt / 2 (-12 % from 0.25 m/s at 240 Hz).

    ``patch`` rows: 0 N, 1-3 sum lambda_n p, 4-6 sum lambda_n n, 7 e N, 8 J = sum lambda_n r^2,
    9-11 F, 12 M, 13 scale of the transmitted part, 14 1 if the self-equilibrated part is kept, 15-17
    what the contacts' cones shed, per unit normal load.

    Under the contact law (TissueConfig.friction_law "contact") each contact is its own patch
    (load_anchors): N is its normal impulse, F the tangential part of its friction, and there is no
    twist (a point contact transmits none about its normal; a pad's torsion is then the sum of its
    contacts' moments). The same decision is then Coulomb's law per contact, |f_t| <= mu_s lambda_n
    while it sticks and mu_k lambda_n while it slides, with each contact's own stick/slide state
    and anchor: no contact can borrow another's normal load, and partial slip follows from the
    contacts' loads."""
    npatch = patch.shape[0]
    single = body_friction.shape[0] * ns  # rows from here on are single contacts (the contact law)
    for p in range(npatch):
        for a in range(18):
            patch[p, a] = 0.0
    # pass 1: where each contact touches, and each patch's centre of pressure and mean normal
    for c in range(nc):
        p = c_patch[c]
        lam = c_lambda[c]
        if p < 0 or lam <= 0.0:
            continue
        i = np.uint64(c_particle[c])  # unsigned: no negative-index wraparound per access
        rn = c_rn[c]
        for a in range(3):
            c_point[c, a] = xp[i, a] - rn * c_normal[c, a]
            patch[p, 1 + a] += lam * c_point[c, a]
            patch[p, 4 + a] += lam * c_normal[c, a]
        patch[p, 0] += lam
    # pass 2: each contact's friction that would cancel its offset from its anchor; patch sums
    for c in range(nc):
        p = c_patch[c]
        lam = c_lambda[c]
        if p < 0 or lam <= 0.0:
            continue
        i = np.uint64(c_particle[c])
        s = np.uint64(c_shape[c])
        r = shape_rigid[s]
        if r >= 0 and rig_move[r]:
            sx, sq = shape_world_pose(s, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q)
        else:
            sx = (shape_pose[s, 0], shape_pose[s, 1], shape_pose[s, 2])
            sq = (shape_pose[s, 3], shape_pose[s, 4], shape_pose[s, 5], shape_pose[s, 6])
        aw = qrotate(sq, (c_anchor[c, 0], c_anchor[c, 1], c_anchor[c, 2]))
        ex = xp[i, 0] - (sx[0] + aw[0])
        ey = xp[i, 1] - (sx[1] + aw[1])
        ez = xp[i, 2] - (sx[2] + aw[2])
        nx, ny, nz = c_normal[c, 0], c_normal[c, 1], c_normal[c, 2]
        en = ex * nx + ey * ny + ez * nz
        ex -= en * nx
        ey -= en * ny
        ez -= en * nz
        fx, fy, fz = c_friction[c, 0], c_friction[c, 1], c_friction[c, 2]
        el = math.sqrt(ex * ex + ey * ey + ez * ez)
        if el > 1e-15:
            w = inv_mass[i]
            if r >= 0 and rig_move[r]:
                w += generalized_inv_mass(r, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, c_point[c, 0] - rig_x[r, 0],
                                           c_point[c, 1] - rig_x[r, 1], c_point[c, 2] - rig_x[r, 2], ex / el, ey / el,
                                           ez / el)  # fmt: skip
            fx -= ex / w
            fy -= ey / w
            fz -= ez / w
        c_friction_goal[c, 0] = fx
        c_friction_goal[c, 1] = fy
        c_friction_goal[c, 2] = fz
        if p >= single:
            # a single contact: no lever (its centre of pressure is its point; computed, the lever
            # would be rounding noise divided by itself)
            patch[p, 9] += fx
            patch[p, 10] += fy
            patch[p, 11] += fz
            continue
        rx, ry, rz, mx, my, mz = _patch_lever(c, p, c_point, patch)
        r2 = rx * rx + ry * ry + rz * rz
        patch[p, 7] += lam * math.sqrt(r2)
        patch[p, 8] += lam * r2
        patch[p, 9] += fx
        patch[p, 10] += fy
        patch[p, 11] += fz
        patch[p, 12] += mx * (ry * fz - rz * fy) + my * (rz * fx - rx * fz) + mz * (rx * fy - ry * fx)
    # the patch's decision: stick, clamp, slide or stop
    for p in range(npatch):
        patch[p, 13] = 1.0
        patch[p, 14] = 1.0
        nn = patch[p, 0]
        if nn <= 0.0:
            continue
        mx, my, mz = patch[p, 4], patch[p, 5], patch[p, 6]
        ml = math.sqrt(mx * mx + my * my + mz * mz)
        mx, my, mz = mx / ml, my / ml, mz / ml
        fx, fy, fz = patch[p, 9], patch[p, 10], patch[p, 11]
        fd = fx * mx + fy * my + fz * mz  # along the mean normal: self-equilibrated on a curved patch
        fx -= fd * mx
        fy -= fd * my
        fz -= fd * mz
        patch[p, 9], patch[p, 10], patch[p, 11] = fx, fy, fz
        load = fx * fx + fy * fy + fz * fz
        if patch[p, 7] > 0.0:
            er = patch[p, 7] / nn
            load += (patch[p, 12] / er) ** 2
        load = math.sqrt(load)  # the patch's transmitted friction, as a force on the limit surface
        if load <= 0.0:
            continue
        b = patch_body[p]
        if not patch_slide[p]:
            # Sticking: static friction up to mu_s N. The normal impulses are still growing over
            # the iterations, so whether the patch breaks loose is decided on what the last
            # iteration sees: it then slides, and that iteration already applies kinetic friction.
            lim = body_friction[b, 0] * nn
            if load <= lim:
                continue
            if not last:
                patch[p, 13] = lim / load
                continue
            patch_slide[p] = True
        patch[p, 14] = 0.0
        kin = body_friction[b, 1] * nn
        if p >= single:
            # A single contact (the contact law) slides at position level alone, capped at its
            # cone (Macklin et al. 2014 eq. 24): min(load, mu_k lambda_n). Split half on
            # velocities as a patch is, a contact held at its cone by the pad's elastic pull -
            # a position-level force - lost part of it every step it slid or stopped, and a
            # sliding strip carried ~0.85 mu P (benchmarks/partial_slip.py).
            patch_change[p] = load < kin
            patch[p, 13] = 1.0 if load < kin else kin / load
            continue
        if load < kin:
            # Stops within this step: with constant deceleration it covers (load / kin) / 2 of the
            # free slip, so load (1 - load / (2 kin)) is taken out here, the rest of the motion by
            # the velocity pass.
            patch_change[p] = True
            patch[p, 13] = 1.0 - 0.5 * load / kin
        else:
            patch_change[p] = False
            patch[p, 13] = 0.5 * kin / load
    cone_any = False
    for b in range(body_cone.shape[0]):
        cone_any = cone_any or body_cone[b]
    # Two compiled functions, not one with a branch per contact: the patch law alone then compiles
    # to the very instructions it did before the cones (fastmath contraction is decided per
    # function), and every id replays bit for bit (tests/test_trajectories.py).
    if cone_any:
        _apply_with_cones(nc, c_particle, c_shape, c_patch, c_lambda, c_friction, c_friction_goal, c_point, xp, inv_mass,
                          body_friction, patch_body, shape_rigid, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis,
                          rig_move, imp_lin, imp_ang, dt, patch, body_cone, last, c_slip)  # fmt: skip
    else:
        _apply_patch_law(nc, c_particle, c_shape, c_patch, c_lambda, c_friction, c_friction_goal, c_point, xp, inv_mass,
                         shape_rigid, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, dt,
                         patch)  # fmt: skip


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _transmitted_share(c, p, lam, c_point, patch):
    """Contact c's share of what its patch transmits: its normal load's share of F plus the torsion
    M / J lambda_n (m x r) (pass 2 of friction_patches summed them)."""
    inv_n = 1.0 / patch[p, 0]
    share = lam * inv_n
    gx = share * patch[p, 9]
    gy = share * patch[p, 10]
    gz = share * patch[p, 11]
    if patch[p, 8] > 0.0:
        rx, ry, rz, mx, my, mz = _patch_lever(c, p, c_point, patch)
        k = patch[p, 12] / patch[p, 8] * lam
        gx += k * (my * rz - mz * ry)
        gy += k * (mz * rx - mx * rz)
        gz += k * (mx * ry - my * rx)
    return gx, gy, gz


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _set_friction(c, i, r, tx, ty, tz, c_friction, c_point, xp, inv_mass, rig_x, rig_q, rig_inv_mass, rig_inv_inertia,
                  rig_axis, rig_move, imp_lin, imp_ang, dt):  # fmt: skip
    """Contact c's friction this step becomes (tx, ty, tz): the change applied to its particle and,
    reversed, to the body under it."""
    ix = tx - c_friction[c, 0]
    iy = ty - c_friction[c, 1]
    iz = tz - c_friction[c, 2]
    c_friction[c, 0] = tx
    c_friction[c, 1] = ty
    c_friction[c, 2] = tz
    wp = inv_mass[i]
    xp[i, 0] += wp * ix
    xp[i, 1] += wp * iy
    xp[i, 2] += wp * iz
    if r >= 0:
        rigid_apply(r, c_point[c, 0] - rig_x[r, 0], c_point[c, 1] - rig_x[r, 1], c_point[c, 2] - rig_x[r, 2], -ix, -iy,
                    -iz, rig_move[r], dt, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin, imp_ang)  # fmt: skip


@nb.njit(**KERNEL)
def _apply_patch_law(
    nc, c_particle, c_shape, c_patch, c_lambda, c_friction, c_friction_goal, c_point, xp, inv_mass, shape_rigid, rig_x,
    rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, dt, patch,
):  # fmt: skip
    """Pass 3 of friction_patches under the patch law alone (the default): each contact's transmitted
    share - its normal load's share of F plus the torsion M / J lambda_n (m x r) - scaled as the
    patch decided, and the rest of its friction, the self-equilibrated part, kept while the patch
    sticks; applied to the particle and the body."""
    for c in range(nc):
        p = c_patch[c]
        lam = c_lambda[c]
        if p < 0 or lam <= 0.0:
            continue
        i = np.uint64(c_particle[c])
        r = shape_rigid[c_shape[c]]
        sc = patch[p, 13]
        keep = patch[p, 14]
        tx, ty, tz = c_friction_goal[c, 0], c_friction_goal[c, 1], c_friction_goal[c, 2]
        if sc != 1.0 or keep != 1.0:
            gx, gy, gz = _transmitted_share(c, p, lam, c_point, patch)
            tx = keep * (tx - gx) + sc * gx
            ty = keep * (ty - gy) + sc * gy
            tz = keep * (tz - gz) + sc * gz
        _set_friction(c, i, r, tx, ty, tz, c_friction, c_point, xp, inv_mass, rig_x, rig_q, rig_inv_mass, rig_inv_inertia,
                      rig_axis, rig_move, imp_lin, imp_ang, dt)  # fmt: skip


@nb.njit(**KERNEL)
def _apply_with_cones(
    nc, c_particle, c_shape, c_patch, c_lambda, c_friction, c_friction_goal, c_point, xp, inv_mass, body_friction,
    patch_body, shape_rigid, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, dt, patch,
    body_cone, last, c_slip,
):  # fmt: skip
    """Pass 3 of friction_patches with Coulomb's cone on every contact as well (TissueConfig.
    contact_cone): as _apply_patch_law, then each contact's self-equilibrated part bounded by its
    own cone, and what that sheds in the patch's plane handed back to the patch's contacts."""
    npatch = patch.shape[0]
    for c in range(nc):
        if last:
            c_slip[c] = False
        p = c_patch[c]
        lam = c_lambda[c]
        if p < 0 or lam <= 0.0:
            continue
        sc = patch[p, 13]
        keep = patch[p, 14]
        b = patch_body[p]
        cone = body_cone[b] and keep == 1.0
        if sc == 1.0 and keep == 1.0 and not cone:
            continue  # the goal as it is
        tx, ty, tz = c_friction_goal[c, 0], c_friction_goal[c, 1], c_friction_goal[c, 2]
        gx, gy, gz = _transmitted_share(c, p, lam, c_point, patch)
        if not cone:
            c_friction_goal[c, 0] = keep * (tx - gx) + sc * gx
            c_friction_goal[c, 1] = keep * (ty - gy) + sc * gy
            c_friction_goal[c, 2] = keep * (tz - gz) + sc * gz
            continue
        sx, sy, sz = tx - gx, ty - gy, tz - gz  # the self-equilibrated part (kept: the patch sticks)
        gx, gy, gz = sc * gx, sc * gy, sc * gz  # the transmitted part
        # Coulomb per contact for the self-equilibrated part: it may not take the contact's
        # friction past mu_s lambda_n. Unbounded, the flanks of a pad wrapped round the cylinder
        # pulled it into the pad along their tangents - a squeeze the core never made - and a
        # pad whose core pushed 0.06 N held the cylinder with 1.4 N (benchmarks/
        # friction_glue.py). What a clamped contact sheds in the patch's plane is summed in
        # patch[15:18] and handed to the patch's contacts by their normal loads below.
        lim = body_friction[b, 0] * lam
        aa = sx * sx + sy * sy + sz * sz
        if (gx + sx) ** 2 + (gy + sy) ** 2 + (gz + sz) ** 2 > lim * lim and aa > 0.0:
            bb = gx * sx + gy * sy + gz * sz
            cc = gx * gx + gy * gy + gz * gz - lim * lim
            f = 0.0  # |g + f s| = lim: the largest f in [0, 1]; 0 if g alone reaches the cone
            if cc < 0.0:
                f = min(1.0, (-bb + math.sqrt(bb * bb - aa * cc)) / aa)
            patch[p, 15] += (1.0 - f) * sx
            patch[p, 16] += (1.0 - f) * sy
            patch[p, 17] += (1.0 - f) * sz
            sx, sy, sz = f * sx, f * sy, f * sz
            if last:
                c_slip[c] = True
        c_friction_goal[c, 0] = sx + gx
        c_friction_goal[c, 1] = sy + gy
        c_friction_goal[c, 2] = sz + gz
    # What the clamped contacts shed in the plane of the patch goes to all its contacts in
    # proportion to their normal loads, so that the patch transmits what its law decided: on
    # a pad over a ramp the lightly loaded contacts reach their cones first, and without this
    # the pad broke loose at 0.90 mu_s (3 iterations). Along the mean normal it is dropped: that
    # is the squeeze by friction the cone bounds.
    for p in range(npatch):
        if patch[p, 0] <= 0.0 or (patch[p, 15] == 0.0 and patch[p, 16] == 0.0 and patch[p, 17] == 0.0):
            continue
        mx, my, mz = patch[p, 4], patch[p, 5], patch[p, 6]
        ml = math.sqrt(mx * mx + my * my + mz * mz)
        mx, my, mz = mx / ml, my / ml, mz / ml
        dn = patch[p, 15] * mx + patch[p, 16] * my + patch[p, 17] * mz
        inv_n = 1.0 / patch[p, 0]
        patch[p, 15] = (patch[p, 15] - dn * mx) * inv_n
        patch[p, 16] = (patch[p, 16] - dn * my) * inv_n
        patch[p, 17] = (patch[p, 17] - dn * mz) * inv_n
    # pass 4: apply
    for c in range(nc):
        p = c_patch[c]
        lam = c_lambda[c]
        if p < 0 or lam <= 0.0:
            continue
        i = np.uint64(c_particle[c])
        r = shape_rigid[c_shape[c]]
        tx, ty, tz = c_friction_goal[c, 0], c_friction_goal[c, 1], c_friction_goal[c, 2]
        if body_cone[patch_body[p]]:
            tx += lam * patch[p, 15]
            ty += lam * patch[p, 16]
            tz += lam * patch[p, 17]
        _set_friction(c, i, r, tx, ty, tz, c_friction, c_point, xp, inv_mass, rig_x, rig_q, rig_inv_mass, rig_inv_inertia,
                      rig_axis, rig_move, imp_lin, imp_ang, dt)  # fmt: skip


@nb.njit(**KERNEL)
def friction_velocity_pass(
    nc, c_particle, c_shape, c_patch, c_lambda, c_friction, c_normal, c_rn, x, v, inv_mass, shape_rigid, rig_x0, rig_q0,
    rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, dt, patch_slide, patch_change,
    c_friction_vel, body_friction, ns,
):  # fmt: skip
    """The velocity half of kinetic friction (see friction_patches; Mueller et al. 2020 sec. 3.6
    apply dynamic friction on velocities, here it is split with the position level). A patch still
    sliding gives each contact the same impulse again, |f_c| / dt against the slip, never more
    than stops it; a patch that stops within the step has its contacts' remaining tangential
    relative velocity cancelled. Under the contact law (single-contact patches) kinetic friction
    is all at position level (friction_patches), so this pass leaves those contacts alone.
    ``c_friction_vel`` gets each contact's velocity half as a positional impulse (impulse x dt), so
    that a contact's whole friction of the step is ``c_friction + c_friction_vel``."""
    single = body_friction.shape[0] * ns
    for c in range(nc):
        c_friction_vel[c, 0] = 0.0
        c_friction_vel[c, 1] = 0.0
        c_friction_vel[c, 2] = 0.0
        p = c_patch[c]
        # p >= single: the contact law's kinetic friction is all at position level (friction_patches)
        if p < 0 or c_lambda[c] <= 0.0 or not patch_slide[p] or p >= single:
            continue
        i = c_particle[c]
        r = shape_rigid[c_shape[c]]
        nx, ny, nz = c_normal[c, 0], c_normal[c, 1], c_normal[c, 2]
        rn = c_rn[c]
        # Velocity of the body point under the contact over the step (from its predicted motion).
        ux, uy, uz = v[i, 0], v[i, 1], v[i, 2]
        lx = ly = lz = 0.0
        if r >= 0:
            lx = x[i, 0] - rn * nx - rig_x[r, 0]
            ly = x[i, 1] - rn * ny - rig_x[r, 1]
            lz = x[i, 2] - rn * nz - rig_x[r, 2]
            q1 = (rig_q[r, 0], rig_q[r, 1], rig_q[r, 2], rig_q[r, 3])
            q0 = (rig_q0[r, 0], rig_q0[r, 1], rig_q0[r, 2], rig_q0[r, 3])
            st = qrotate(q0, qrotate(qconj(q1), (lx, ly, lz)))
            ux -= (rig_x[r, 0] + lx - rig_x0[r, 0] - st[0]) / dt
            uy -= (rig_x[r, 1] + ly - rig_x0[r, 1] - st[1]) / dt
            uz -= (rig_x[r, 2] + lz - rig_x0[r, 2] - st[2]) / dt
        un = ux * nx + uy * ny + uz * nz
        ux -= un * nx
        uy -= un * ny
        uz -= un * nz
        if patch_change[p]:
            # stopped within the step: cancel what is left of the slip
            ul = math.sqrt(ux * ux + uy * uy + uz * uz)
            if ul < 1e-15:
                continue
            dx, dy, dz = -ux / ul, -uy / ul, -uz / ul
            need = ul
            cap = math.inf
        else:
            fl = math.sqrt(c_friction[c, 0] ** 2 + c_friction[c, 1] ** 2 + c_friction[c, 2] ** 2)
            if fl < 1e-300:
                continue
            dx, dy, dz = c_friction[c, 0] / fl, c_friction[c, 1] / fl, c_friction[c, 2] / fl
            need = -(ux * dx + uy * dy + uz * dz)  # slip speed against the friction direction
            if need <= 0.0:
                continue
            cap = fl / dt  # the same impulse again as at position level
        w = inv_mass[i]
        if r >= 0 and rig_move[r]:
            w += generalized_inv_mass(r, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, lx, ly, lz, dx, dy, dz)
        j = min(need / w, cap)
        c_friction_vel[c, 0] = j * dx * dt
        c_friction_vel[c, 1] = j * dy * dt
        c_friction_vel[c, 2] = j * dz * dt
        wp = inv_mass[i]
        v[i, 0] += wp * j * dx
        v[i, 1] += wp * j * dy
        v[i, 2] += wp * j * dz
        if r >= 0:
            # a velocity change of the body only (its predicted pose stays): the impulse -j d
            rigid_apply(r, lx, ly, lz, -j * dx * dt, -j * dy * dt, -j * dz * dt, False, dt, rig_x, rig_q,
                         rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin, imp_ang)  # fmt: skip


@nb.njit(**KERNEL)
def store_anchors(nc, c_particle, c_shape, c_patch, c_lambda, c_anchor, x, shape_rigid, shape_local_x, shape_local_q,
                   rig_x, rig_q, patch_slide, patch_change, anchor_shape, anchor_x, anchor_slide, c_slip):  # fmt: skip
    """Keep the anchors of touching contacts for the next step: a sticking patch keeps them where
    they are; a patch that slid this step (or stopped) anchors where its particles are now.
    ``patch_slide`` is the mode the step ended in, ``patch_change`` that a sliding patch stopped."""
    for i in range(anchor_shape.shape[0]):
        for k in range(anchor_shape.shape[1]):
            anchor_shape[i, k] = -1
            anchor_slide[i, k] = False
    for c in range(nc):
        p = c_patch[c]
        if p < 0 or c_lambda[c] <= 0.0:
            continue
        i = c_particle[c]
        s = c_shape[c]
        k = 0
        while k < anchor_shape.shape[1] and anchor_shape[i, k] >= 0:
            k += 1
        if k == anchor_shape.shape[1]:
            continue
        anchor_shape[i, k] = s
        if patch_slide[p]:
            # it slid (or stopped) this step: anchor where the particle is now
            sx, sq = shape_world_pose(s, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q)
            loc = qrotate(qconj(sq), (x[i, 0] - sx[0], x[i, 1] - sx[1], x[i, 2] - sx[2]))
            for a in range(3):
                anchor_x[i, k, a] = loc[a]
            anchor_slide[i, k] = patch_slide[p] != patch_change[p]
        elif c_slip[c]:
            # Its cone held it back on the last iteration (contact cones): it slipped, and anchors
            # where it is. Kept, the anchor it left pulled it back at its cone every step, and the
            # pad's compression under 3 N moved with the iterations (4.98 mm at 3, 4.23 at 20);
            # re-anchored, 5.38 and 5.28 mm (the patch law, with no bound per contact: 4.34, 4.32).
            sx, sq = shape_world_pose(s, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q)
            loc = qrotate(qconj(sq), (x[i, 0] - sx[0], x[i, 1] - sx[1], x[i, 2] - sx[2]))
            for a in range(3):
                anchor_x[i, k, a] = loc[a]
            anchor_slide[i, k] = False
        else:
            for a in range(3):
                anchor_x[i, k, a] = c_anchor[c, a]


@nb.njit(**KERNEL)
def friction_pairs(count, pair_i, pair_j, pair_lambda, pair_lambda_t, pair_normal, x0, xp, inv_mass, p_body, body_friction):
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

