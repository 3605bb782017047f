"""The tissue's material: shape matching whose stiffness is a modulus in Pa, solved as the implicit
step it stands for, the same material at every dt and iteration count.

Shape matching (Mueller & Chentanez 2011 sec. 4) is the gradient of an energy: a group's fit - its
centre of mass c and rotation R (shape_matching._fit_group) - minimises
E = sum_j kappa m_j |x_j - g_j|^2 / 2, g_j = R q_j + c, so dE/dx_j = kappa m_j e_j, e_j = x_j - g_j.
With kappa = G / (rho l^2) (builder.group_kappa) that is an elastic force in N. (Moving each
member a fraction k of the way to its goal per step, as the thesis does, is a spring
kappa = k / dt^2: a different material at every dt.) Here each group's part of the implicit (backward Euler) step,
m (x - x*) = -dt^2 dE/dx, is solved by a Newton step per group and pass (the primal form of XPBD,
Macklin, Mueller & Chentanez 2016), Gauss-Seidel over the groups:

    rho_j = u_j + s e_j,  s = kappa dt^2       the residual of member j per unit mass, u_j the
                                               displacement this group gave it this step
    free members:      dx_j = -(rho_j + Y) / (1 + s)
    attached members:  held by their core (w = 0): their force goes to it (deliver_to_core)

with Y from one 3x3 solve (Woodbury; see project_group). A group alone is solved exactly in one
pass, whatever s, and every pass keeps momentum exactly. Across groups the passes are
Gauss-Seidel: a pad pressed on the cylinder closes the gap to the implicit step by about
s / (1 + s) a pass, so the world runs in steps short enough that s <= MAX_STEP_STIFFNESS
(substeps_for; world_substeps also keeps a pad's force on a light core, handed to pybullet a step
late, from ringing: MAX_COUPLING_FOLD).

An attached particle sits on its core through the solve (thesis 5.1.3, "the
core infinitely heavy inside the solve", taken literally): a group's force on it is an impulse on
the core at its spot. Under the consistent coupling the core slides inside the solve, and the
group's Newton step moves it (the core unknown of project_group and continuum_groups). Moving attached particles with their
own mass inside the solve and handing the error over afterwards (anchors.snap_attached) gives an
impulse m e / dt that can carry at most about m e / dt^2, a force that falls with dt^2 (pads
crushed at 1/120 s and stiff at 1/1000 s).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from .jit import KERNEL
from .linalg import inv_sym3, solve_sym3
from .model import TissueModel
from .rigid import rigid_apply
from .rotation import extract_rotation_unit_t, qmat
from .shape_matching import _fit_group, _turn_centre

MAX_STEP_STIFFNESS = 0.25
"""Largest s = kappa dt^2 of a compliant group in one step: the world runs in steps short enough
(substeps_for). Pressed on the cylinder, the pad's passes close the gap to the implicit step by a
factor of about s / (1 + s) each (what contacts and friction hold, a group's Newton step takes as
free), so 0.25 leaves 4 % after 2 iterations and under 1 % after 3 (the package's documentation,
Results: the v3 physics, "Convergence in dt and iterations", gives the measurements)."""


MAX_COUPLING_FOLD = 0.5
"""Largest K dt^2 / m_core of one step [-], K a compliant pad's stiffness against its core
(core_stiffness) and m_core the core's mass: the pad's force reaches a core that pybullet moves a
step late (thesis 5.2.2), and beyond about 1 it rings."""


def substeps_for(model: TissueModel, dt: float) -> int:
    """The fewest steps of dt / n that keep every group's s = kappa (dt / n)^2 at most
    MAX_STEP_STIFFNESS (kappa: the group's largest stiffness per unit mass, G / (rho l^2) for shape
    matching, the largest eigenvalue of M^-1/2 H M^-1/2 for a continuum group:
    builder.continuum_groups)."""
    if model.group_kappa.size == 0:
        return 1
    kappa = float(model.group_kappa.max())
    return max(1, math.ceil(dt * math.sqrt(kappa / MAX_STEP_STIFFNESS) - 1e-9))


def core_stiffness(model: TissueModel) -> np.ndarray:
    """(B,) each body's stiffness against its core [N/m]: its groups as springs in
    parallel, sum_i kappa_i m_fix m_free / M over the groups with attached and free members (a
    group of attached members, mass m_fix, and free ones, m_free, is a spring kappa m_fix m_free / M
    between them: project_group's column). 1,310 N/m for a default pad (G 4,000 Pa), against
    G A / extrude = 1,520 N/m for the layer it stands for."""
    out = np.zeros(model.body_count)
    cont = model.group_continuum
    for b in range(model.body_count):
        for i in range(int(model.body_particle_offsets[b]), int(model.body_particle_offsets[b + 1])):
            e = slice(int(model.group_offsets[i]), int(model.group_offsets[i + 1]))
            members = model.group_members[e]
            m = model.particle_mass[members]
            fix = model.particle_attached[members]
            if cont[i, 6] > 0.0:
                # continuum group (continuum_groups): its free members moved by d against the fixed
                # ones change F by d beta^T, beta = sum_free b_j, an energy of at most
                # G V |d|^2 |beta|^2: a spring 2 G V |beta|^2
                p = cont[i]
                ainv = np.array([[p[0], p[1], p[2]], [p[1], p[3], p[4]], [p[2], p[4], p[5]]])
                beta = ainv @ (m[~fix, None] * model.group_rest_offset[e][~fix]).sum(axis=0)
                out[b] += p[6] * float(beta @ beta)
                continue
            out[b] += model.group_kappa[i] * m[fix].sum() * m[~fix].sum() / m.sum()
    return out


def coupling_substeps(model: TissueModel, core_mass: np.ndarray, dt: float) -> int:
    """The fewest steps of dt / n that keep every body's K (dt / n)^2 / m_core at most
    MAX_COUPLING_FOLD; ``core_mass`` (B,) [kg], 0 or inf where a body has no moving core."""
    n = 1
    for k, m in zip(core_stiffness(model), core_mass, strict=True):
        if k > 0.0 and 0.0 < m < math.inf:
            n = max(n, math.ceil(dt * math.sqrt(k / (MAX_COUPLING_FOLD * m)) - 1e-9))
    return n


def world_substeps(model: TissueModel, core_mass: np.ndarray, dt: float, material_solve: str = "groups") -> int:
    """World steps (tissue and rigid bodies together) per step of dt: the larger of substeps_for
    and coupling_substeps; coupling_substeps alone under the global material solve
    (SimConfig.material_solve "global"), whose passes do not lose accuracy as s grows
    (global_step.py)."""
    if material_solve == "global":
        return coupling_substeps(model, core_mass, dt)
    return max(substeps_for(model, dt), coupling_substeps(model, core_mass, dt))


@nb.njit(cache=True, error_model="numpy")
def turn_rates(group_kappa, dt, iterations, out):
    """Each group's turn of its centre per pass, out[i] = 1 - (1 / (1 + s))^(1 / iterations) with
    s = kappa dt^2 (sweep_body): s / (1 + s) of the way over the step's passes. Once per step
    length, not per group and pass: the power is a libm call. Compiled without contraction, so that
    1 + s is rounded as the sweep rounded it when it computed this itself (a fused
    kappa dt * dt + 1 differs in the last bit for some groups), and every trajectory stays as it
    was."""
    for i in range(group_kappa.shape[0]):
        s = group_kappa[i] * dt * dt
        out[i] = 1.0 - (1.0 / (1.0 + s)) ** (1.0 / iterations)


@nb.njit(**KERNEL)
def compliant_sweep(g_turn, rot_iters, body_off, group_kappa, dt, g_off, g_mem, g_pack, frame,
                    attached, fixed, rest_q, rest_moment, xs, xp, qp, group_q, moment, g_u, g_raw, mass,
                    body_core_shape, shape_rigid, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move,
                    imp_lin, imp_ang, coupling_imp, continuum, g_cont):  # fmt: skip
    """One Gauss-Seidel sweep over the groups of every body, one body after the other
    (sweep_body)."""
    for b in range(body_off.shape[0] - 1):
        sweep_body(b, g_turn, rot_iters, body_off, group_kappa, dt, g_off, g_mem, g_pack, frame, attached, fixed,
                   rest_q, rest_moment, xs, xp, qp, group_q, moment, g_u, g_raw, mass, body_core_shape, shape_rigid,
                   rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, coupling_imp,
                   continuum, g_cont)  # fmt: skip


def bodies_independent(model: TissueModel, shape_rigid: np.ndarray) -> bool:
    """True if every tissue body has a core of its own (a rigid slot no other body's core is on):
    then a body's groups and its particles' core constraints touch only its own particles, group
    data and core, the bodies do not interact inside those passes, and they can run on threads
    with the result of one (solver._bodies_pass). ``shape_rigid``: the colliders' shape -> rigid
    slot."""
    cores = [int(shape_rigid[s]) if s >= 0 else -1 for s in model.body_core_shape]
    off = model.body_particle_offsets
    covered = len(off) > 1 and off[0] == 0 and off[-1] == model.particle_count  # every particle in a body
    return covered and all(c >= 0 for c in cores) and len(set(cores)) == len(cores)


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _all_continuum(lo, hi, g_cont):
    """True if every group lo..hi-1 has the continuum energy (g_cont[i, 6] > 0)."""
    for i in range(lo, hi):
        if not g_cont[i, 6] > 0.0:
            return False
    return True


@nb.njit(**KERNEL)
def sweep_body(b, g_turn, rot_iters, body_off, group_kappa, dt, g_off, g_mem, g_pack, frame, attached, fixed,
               rest_q, rest_moment, xs, xp, qp, group_q, moment, g_u, g_raw, mass, body_core_shape, shape_rigid, rig_x,
               rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, coupling_imp, continuum,
               g_cont):  # fmt: skip
    """One Gauss-Seidel sweep over body b's groups: project_group, or continuum_groups for a group
    with the continuum energy (``continuum`` and g_cont[i, 6] > 0; kappa then the group's largest
    stiffness per unit mass). A group's centre turns toward quat(R) q_bar by s / (1 + s) a step (the
    same implicit spring on its orientation, Mueller & Chentanez 2011 sec. 4.3's goal), spread over
    the iterations: g_turn[i] a pass (turn_rates)."""
    cs = body_core_shape[b]
    core = shape_rigid[cs] if cs >= 0 else -1
    m_att = 0.0
    for k in range(body_off[b], body_off[b + 1]):
        if fixed[k]:
            m_att += mass[k]
    lo, hi = body_off[b], body_off[b + 1]
    if continuum and _all_continuum(lo, hi, g_cont):
        # every group continuum (the v4 material): one call solves them all, then the centres turn.
        # The order is the serial one's: continuum_groups reads neither qp nor moment, which the turns
        # write, and a group's quat(R) (group_q) is written by its own solve only
        continuum_groups(lo, hi, core, lo, hi, m_att, rot_iters, g_cont, g_off, g_mem, g_pack, frame, xs, xp, group_q,
                         fixed, g_u, g_raw, mass, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move,
                         imp_lin, imp_ang, coupling_imp, dt)  # fmt: skip
        for i in range(lo, hi):
            if not attached[i]:
                qr = (group_q[i, 0], group_q[i, 1], group_q[i, 2], group_q[i, 3])
                _turn_centre(i, qr, g_turn[i], rest_q, qp, rest_moment, moment)
        return
    for i in range(lo, hi):
        s = group_kappa[i] * dt * dt
        if continuum and g_cont[i, 6] > 0.0:
            continuum_groups(i, i + 1, core, lo, hi, m_att, rot_iters, g_cont, g_off, g_mem, g_pack, frame, xs, xp,
                             group_q, fixed, g_u, g_raw, mass, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis,
                             rig_move, imp_lin, imp_ang, coupling_imp, dt)  # fmt: skip
            qr = (group_q[i, 0], group_q[i, 1], group_q[i, 2], group_q[i, 3])
        else:
            qr = project_group(i, s, core, lo, hi, m_att, rot_iters, g_off, g_mem, g_pack,
                               frame, xs, xp, group_q, moment, fixed, g_u, g_raw, mass, rig_x, rig_q, rig_inv_mass,
                               rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, coupling_imp, dt)  # fmt: skip
        if not attached[i]:
            _turn_centre(i, qr, g_turn[i], rest_q, qp, rest_moment, moment)


@nb.njit(**KERNEL)
def project_group(i, s, core, core_lo, core_hi, m_att, rot_iters, g_off, g_mem, g_pack, frame, xs, xp, group_q, moment,
                  fixed, g_u, g_raw, mass, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin,
                  imp_ang, coupling_imp, dt):  # fmt: skip
    """One Newton step of group i's implicit equations (module docstring); returns its rotation.

    Members held by their core (``fixed``) move only with it - not at all under the thesis
    coupling (the core infinitely heavy in the solve), along its joint axis a under the consistent
    one: the core, mass m_c, slides inside the solve with all its attached particles, M_att, one
    more unknown dc, with residual R_c = (m_c + M_att) U_c + s a . sum_fix m_j e_j (U_c what this
    group has moved it). With R held, the Hessian over the unknowns is
    diag((1 + s) m_j I, m_c + M_att + s M_fix) - (s / M) B B^T, the centre of mass moving with the
    members (B: rows m_j I for the free members and M_fix a^T; M the group's mass, w_j = m_j / M,
    f = sum_free w_j), and Woodbury gives its Newton step through one 3x3 solve:

        z_j = rho_j / (1 + s),  z_c = R_c / d_c,  d_c = m_c + M_att + s M_fix
        Y = [(1 / s - f / (1 + s)) I - (M_fix^2 / (M d_c)) a a^T]^-1 (sum w_j z_j + (M_fix / M) a z_c)
        dx_j = -(z_j + Y / (1 + s)),   dc = -(z_c + M_fix a . Y / d_c)

    (the thesis coupling: no core unknown, and the solve is a scalar). After it, each fixed member's
    force, what is left of its residual, goes to its core (what does not move the core along its
    joint, the joint takes). For a group alone every residual then vanishes and sum_j m_j u_j = 0:
    momentum is exact at every pass (a column of one attached and one outer particle moves
    s w_a / (1 + s w_a) of its stretch, a spring kappa m_a m_f / M to a fixed point). (Per member,
    each with its own multiplier, the members' constraints are redundant - they sum to zero - and
    a Jacobi update over them overshot by up to 2x with a fixed member; warm-started from the last
    step, the pad's force lagged its motion and pumped energy into the fingers.) A group with no
    fixed member is made free of momentum and angular momentum about the step's start positions
    instead (_apply_deformation)."""
    i = np.uint64(i)
    start = np.uint64(g_off[i])
    end = np.uint64(g_off[i + 1])
    qr, cx, cy, cz = _fit_group(i, rot_iters, g_off, g_mem, g_pack, xp, group_q, moment)
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = qmat(qr)
    inv = 1.0 / (1.0 + s)
    zx = zy = zz = 0.0  # sum w_j z_j over the free members
    f = 0.0  # their mass fraction
    fx = fy = fz = 0.0  # sum_fix m_j rho_j
    mfix = 0.0
    for e in range(start, end):
        j = np.uint64(g_mem[e])
        q0 = g_pack[e, 4]
        q1 = g_pack[e, 5]
        q2 = g_pack[e, 6]
        rx = g_u[e, 0] + s * (xp[j, 0] - (r00 * q0 + r01 * q1 + r02 * q2 + cx))
        ry = g_u[e, 1] + s * (xp[j, 1] - (r10 * q0 + r11 * q1 + r12 * q2 + cy))
        rz = g_u[e, 2] + s * (xp[j, 2] - (r20 * q0 + r21 * q1 + r22 * q2 + cz))
        g_raw[e, 0] = rx
        g_raw[e, 1] = ry
        g_raw[e, 2] = rz
        if fixed[j]:
            m = mass[j]
            mfix += m
            fx += m * rx
            fy += m * ry
            fz += m * rz
            continue
        w = g_pack[e, 0]
        f += w
        zx += w * inv * rx
        zy += w * inv * ry
        zz += w * inv * rz
    if mfix == 0.0:
        # no member held: dx_j = -rho_j / (1 + s) - s / (1 + s) sum w rho (= s sum w z), made a pure
        # deformation
        for e in range(start, end):
            g_raw[e, 0] = -g_raw[e, 0] * inv - s * zx
            g_raw[e, 1] = -g_raw[e, 1] * inv - s * zy
            g_raw[e, 2] = -g_raw[e, 2] * inv - s * zz
        _apply_deformation(i, start, end, g_mem, g_pack, frame, xs, xp, g_u, g_raw)
        return qr
    msum = frame[i, 9]
    a = 1.0 / s - f * inv  # the 3x3 matrix's isotropic part
    q00 = q01 = q02 = q11 = q12 = q22 = 0.0  # its core part
    # the core's own unknown, if it slides inside the solve along a joint axis
    ax = ay = az = 0.0
    zc = dcore = mcore = 0.0
    if rig_move[core] and rig_inv_mass[core] > 0.0:
        ax, ay, az = rig_axis[core, 0], rig_axis[core, 1], rig_axis[core, 2]
        if ax != 0.0 or ay != 0.0 or az != 0.0:
            mcore = 1.0 / rig_inv_mass[core]
            uc = 0.0  # U_c: along a, a fixed member's u is its core's move (what the joint took is across a)
            for e in range(start, end):
                if fixed[np.uint64(g_mem[e])]:
                    uc = ax * g_u[e, 0] + ay * g_u[e, 1] + az * g_u[e, 2]
                    break
            dcore = mcore + m_att + s * mfix
            zc = ((mcore + m_att - mfix) * uc + ax * fx + ay * fy + az * fz) / dcore
            k = mfix * mfix / (msum * dcore)
            q00, q01, q02 = k * ax * ax, k * ax * ay, k * ax * az
            q11, q12, q22 = k * ay * ay, k * ay * az, k * az * az
            k = mfix / msum * zc
            zx += k * ax
            zy += k * ay
            zz += k * az
    yx, yy, yz = solve_sym3(a - q00, -q01, -q02, a - q11, -q12, a - q22, zx, zy, zz)
    dc = 0.0
    if dcore > 0.0:
        dc = -(zc + mfix * (ax * yx + ay * yy + az * yz) / dcore)
    yx *= inv
    yy *= inv
    yz *= inv
    # the free members' step; dcx.. is the centre's move, sum w_j dx_j
    dcx = dcy = dcz = 0.0
    for e in range(start, end):
        j = np.uint64(g_mem[e])
        w = g_pack[e, 0]
        if fixed[j]:
            dcx += w * dc * ax
            dcy += w * dc * ay
            dcz += w * dc * az
            continue
        dx = g_raw[e, 0] * inv + yx
        dy = g_raw[e, 1] * inv + yy
        dz = g_raw[e, 2] * inv + yz
        xp[j, 0] -= dx
        xp[j, 1] -= dy
        xp[j, 2] -= dz
        g_u[e, 0] -= dx
        g_u[e, 1] -= dy
        g_u[e, 2] -= dz
        dcx -= w * dx
        dcy -= w * dy
        dcz -= w * dz
    if dc != 0.0:
        slide_core(core, dc, ax, ay, az, mcore, core_lo, core_hi, fixed, xp, rig_x, imp_lin, coupling_imp, dt)
    # each fixed member's force, the rest of its residual once the group moved (its own move, the
    # core's, enters u and e; the centre's shifts e by -dc), goes to its core
    for e in range(start, end):
        j = np.uint64(g_mem[e])
        if not fixed[j]:
            continue
        rx = g_raw[e, 0] - s * dcx
        ry = g_raw[e, 1] - s * dcy
        rz = g_raw[e, 2] - s * dcz
        if dcore > 0.0:
            k = (1.0 + s) * dc
            rx += k * ax
            ry += k * ay
            rz += k * az
            g_u[e, 0] += dc * ax
            g_u[e, 1] += dc * ay
            g_u[e, 2] += dc * az
            k = rx * ax + ry * ay + rz * az  # balanced by the core's inertia: m_c dc above
            rx -= k * ax
            ry -= k * ay
            rz -= k * az
        m = mass[j]
        deliver_to_core(j, -m * rx, -m * ry, -m * rz, core, xp, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis,
                        imp_lin, imp_ang, coupling_imp, dt)  # fmt: skip
        g_u[e, 0] -= rx
        g_u[e, 1] -= ry
        g_u[e, 2] -= rz
    return qr


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def slide_core(core, dc, ax, ay, az, mcore, core_lo, core_hi, fixed, xp, rig_x, imp_lin, coupling_imp, dt):
    """A core sliding along its joint axis a inside the solve (the consistent coupling) moves by dc
    with all its attached particles (``fixed`` in core_lo..core_hi): the impulse m_c dc on it,
    recorded for pybullet, which applies it too."""
    rig_x[core, 0] += dc * ax
    rig_x[core, 1] += dc * ay
    rig_x[core, 2] += dc * az
    k = mcore * dc / dt
    imp_lin[core, 0] += k * ax
    imp_lin[core, 1] += k * ay
    imp_lin[core, 2] += k * az
    coupling_imp[core, 0] += k * ax
    coupling_imp[core, 1] += k * ay
    coupling_imp[core, 2] += k * az
    for k in range(core_lo, core_hi):
        if fixed[k]:
            xp[k, 0] += dc * ax
            xp[k, 1] += dc * ay
            xp[k, 2] += dc * az


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def deliver_to_core(j, px, py, pz, core, xp, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin, imp_ang,
                    coupling_imp, dt):  # fmt: skip
    """The positional impulse P a group puts on fixed member j, onto its core at the member's spot,
    recorded for pybullet (a core that slides inside the solve has moved by its share already: the
    group's Newton step holds it as an unknown)."""
    rigid_apply(core, xp[j, 0] - rig_x[core, 0], xp[j, 1] - rig_x[core, 1], xp[j, 2] - rig_x[core, 2], px, py, pz,
                False, dt, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin, imp_ang)  # fmt: skip
    coupling_imp[core, 0] += px / dt
    coupling_imp[core, 1] += py / dt
    coupling_imp[core, 2] += pz / dt


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _apply_deformation(i, start, end, g_mem, g_pack, frame, xs, xp, g_u, g_raw):
    """Move group i's members by ``g_raw`` made a pure deformation: its mass-weighted mean and its
    turn about the step's start centre (I^-1 of frame) taken out, so momentum and angular momentum
    about the start positions - what PBD's velocities are differenced over - are kept exactly (the
    share the group's translation and rotation, which the Newton step holds, take)."""
    bx = by = bz = 0.0
    for e in range(start, end):
        w = g_pack[e, 0]
        bx += w * g_raw[e, 0]
        by += w * g_raw[e, 1]
        bz += w * g_raw[e, 2]
    csx, csy, csz = frame[i, 0], frame[i, 1], frame[i, 2]
    lx = ly = lz = 0.0  # sum_k w_k r_k x (raw_k - b)
    for e in range(start, end):
        j = np.uint64(g_mem[e])
        w = g_pack[e, 0]
        dx = g_raw[e, 0] - bx
        dy = g_raw[e, 1] - by
        dz = g_raw[e, 2] - bz
        rx = xs[j, 0] - csx
        ry = xs[j, 1] - csy
        rz = xs[j, 2] - csz
        lx += w * (ry * dz - rz * dy)
        ly += w * (rz * dx - rx * dz)
        lz += w * (rx * dy - ry * dx)
    msum = frame[i, 9]
    lx *= msum
    ly *= msum
    lz *= msum
    wx = frame[i, 3] * lx + frame[i, 4] * ly + frame[i, 5] * lz
    wy = frame[i, 4] * lx + frame[i, 6] * ly + frame[i, 7] * lz
    wz = frame[i, 5] * lx + frame[i, 7] * ly + frame[i, 8] * lz
    for e in range(start, end):
        j = np.uint64(g_mem[e])
        rx = xs[j, 0] - csx
        ry = xs[j, 1] - csy
        rz = xs[j, 2] - csz
        dx = g_raw[e, 0] - bx - (wy * rz - wz * ry)
        dy = g_raw[e, 1] - by - (wz * rx - wx * rz)
        dz = g_raw[e, 2] - bz - (wx * ry - wy * rx)
        xp[j, 0] += dx
        xp[j, 1] += dy
        xp[j, 2] += dz
        g_u[e, 0] += dx
        g_u[e, 1] += dy
        g_u[e, 2] += dz


# =================================================================================================
# the continuum group energy (TissueConfig.group_energy "continuum")
# =================================================================================================


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _held_step(b0, b1, b2, inv_m, zx, zy, zz, y00, y01, y02, y10, y11, y12, y20, y21, y22, hb, opm, gx, gy, gz):
    """The group solve's step of a free member (continuum_groups) with the core held: dx_j = -(z_j - Y^T b_j / m_j),
    with the hourglass term / (1 + hb) - t (sum m z - Y^T sum b) (g)."""
    dx = (y00 * b0 + y10 * b1 + y20 * b2) * inv_m - zx
    dy = (y01 * b0 + y11 * b1 + y21 * b2) * inv_m - zy
    dz = (y02 * b0 + y12 * b1 + y22 * b2) * inv_m - zz
    if hb > 0.0:
        dx = dx / opm - gx
        dy = dy / opm - gy
        dz = dz / opm - gz
    return dx, dy, dz


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _core_column(b0, b1, b2, inv_m, m, o0, o1, o2, h, hb, bf0, bf1, bf2, wfix, yc0, yc1, yc2, opm, tq):
    """The group solve's coupling of a free member (continuum_groups) to a sliding core: gamma_j (its residual's change
    per unit of the core's move, along the axis) and q_j (the free block's solve of that column,
    along the axis)."""
    gam = h * (b0 * bf0 + b1 * bf1 + b2 * bf2)
    if hb > 0.0:
        gam -= hb * m * (wfix + bf0 * o0 + bf1 * o1 + bf2 * o2)
    qj = ((yc0 * b0 + yc1 * b1 + yc2 * b2) - gam) * inv_m
    if hb > 0.0:
        qj = qj / opm - tq
    return gam, qj


@nb.njit(**KERNEL)
def continuum_groups(lo, hi, core, core_lo, core_hi, m_att, rot_iters, g_cont, g_off, g_mem, g_pack, frame, xs, xp, group_q,
                    fixed, g_u, g_raw, mass, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin,
                    imp_ang, coupling_imp, dt):  # fmt: skip
    """One Newton step of each group lo..hi-1's implicit equations under E = G V ||F - R||_F^2, one
    group after the other (Gauss-Seidel); each group i's quat(R) is left in group_q[i].

    The groups are looped here, not in the caller: a call into this kernel passes some twenty
    arrays, and one call per group was 15-20 % of the sweep; one per body costs nothing. The
    arithmetic is the same, so the results are the same to the bit.

    For group i:

    F = sum_j x_j b_j^T, b_j = A_qq^-1 m_j q_j (sum_j b_j = 0: F ignores translation), so with R
    held (the polar factor of F, warm-started from the group's last rotation, Mueller et al. 2016;
    its derivative drops out, as ||F - R|| is least over rotations there) the energy is quadratic:

        grad_j E = k (F - R) b_j,   d^2 E / dx_j dx_k = k (b_j . b_k) I,   k = 2 G V

    (the projective-dynamics strain energy, Bouaziz et al. 2014, per group; ARAP's). The group's
    part of the implicit step, m_j u_j + dt^2 grad_j E = 0 (u_j what this group moved member j this
    step), for the free members: (M + c B B^T) dx = -r, c = k dt^2, r_j = m_j u_j + dt^2 grad_j E,
    B the rows b_j^T. Woodbury, one symmetric 3 x 3 solve with three right-hand sides:

        z_j = r_j / m_j,   S = I / c + sum_free b_j b_j^T / m_j,   Y = S^-1 sum_free b_j z_j^T
        dx_j = -(z_j - Y^T b_j / m_j)

    exact for the group (R held). A member held by its core (``fixed``) does not move; what is left
    of its residual after the step goes to the core as an impulse (deliver_to_core), so
    sum_j m_j u_j = -dt^2 sum_j grad_j E = 0: momentum is exact every pass, as in project_group.

    Under the consistent coupling a core that slides along its joint axis a inside the solve (mass
    m_c, with all its attached particles, M_att) is one more unknown dc, as in project_group.
    Moving the fixed members by dc a changes free member j's residual by gamma_j dc a,
    gamma_j = h (b_j . beta_f) - hb m_j (W_f + beta_f . o_j) (h = k dt^2, hb = beta dt^2,
    beta_f = sum_fix b_j, W_f the fixed members' share of the fit centre, o_j the rest offset), and
    the core's own row is

        R_c = (m_c + M_att - M_fix) U_c + a . sum_fix m_j z_j
        H_c = m_c + M_att + h |beta_f|^2 + hb (M_fix (1 - W_f) - beta_f . sum_fix m_j o_j)

    (U_c what this group has moved the core this step). The Schur complement on the core gives
    dc = -(R_c + sum_j gamma_j a . dx_j) / (H_c + sum_j gamma_j q_j), where dx_j is the step above
    with the core held and q_j a the free block's solve of the column gamma a (the same S, one more
    3 x 3 solve); the members then step by dx_j + dc q_j a. The Newton step stays exact for the
    group, core included; the core's impulse m_c dc / dt reaches pybullet as project_group's does,
    and each fixed member's residual across a goes to the core (the joint takes it). A group with
    no fixed member is made free of momentum and angular momentum about the step's start
    positions (_apply_deformation)."""
    for g in range(lo, hi):
        i = np.uint64(g)
        start = np.uint64(g_off[i])
        end = np.uint64(g_off[i + 1])
        p00, p01, p02, p11, p12, p22 = g_cont[i, 0], g_cont[i, 1], g_cont[i, 2], g_cont[i, 3], g_cont[i, 4], g_cont[i, 5]
        k = g_cont[i, 6]
        c = k * dt * dt
        hb = g_cont[i, 7] * dt * dt  # the hourglass term's beta dt^2 (0: none)
        # A_pq = sum_j x_j (m_j q_j)^T (sum_j m_j q_j = 0: no centre needed); the centre for the
        # hourglass term's affine fit
        a00 = a01 = a02 = a10 = a11 = a12 = a20 = a21 = a22 = 0.0
        cx = cy = cz = 0.0
        for e in range(start, end):
            j = np.uint64(g_mem[e])
            x0 = xp[j, 0]
            x1 = xp[j, 1]
            x2 = xp[j, 2]
            if hb > 0.0:
                w = g_pack[e, 0]
                cx += w * x0
                cy += w * x1
                cz += w * x2
            q0 = g_pack[e, 1]
            q1 = g_pack[e, 2]
            q2 = g_pack[e, 3]
            a00 += x0 * q0
            a01 += x0 * q1
            a02 += x0 * q2
            a10 += x1 * q0
            a11 += x1 * q1
            a12 += x1 * q2
            a20 += x2 * q0
            a21 += x2 * q1
            a22 += x2 * q2
        # F = A_pq A_qq^-1
        f00 = a00 * p00 + a01 * p01 + a02 * p02
        f01 = a00 * p01 + a01 * p11 + a02 * p12
        f02 = a00 * p02 + a01 * p12 + a02 * p22
        f10 = a10 * p00 + a11 * p01 + a12 * p02
        f11 = a10 * p01 + a11 * p11 + a12 * p12
        f12 = a10 * p02 + a11 * p12 + a12 * p22
        f20 = a20 * p00 + a21 * p01 + a22 * p02
        f21 = a20 * p01 + a21 * p11 + a22 * p12
        f22 = a20 * p02 + a21 * p12 + a22 * p22
        qr = extract_rotation_unit_t((f00, f01, f02, f10, f11, f12, f20, f21, f22),
                                     (group_q[i, 0], group_q[i, 1], group_q[i, 2], group_q[i, 3]), rot_iters, 1e-10)  # fmt: skip
        group_q[i, 0] = qr[0]
        group_q[i, 1] = qr[1]
        group_q[i, 2] = qr[2]
        group_q[i, 3] = qr[3]
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = qmat(qr)
        # D = dt^2 k (F - R): the residual's elastic part is D b_j
        h = dt * dt * k
        d00, d01, d02 = h * (f00 - r00), h * (f01 - r01), h * (f02 - r02)
        d10, d11, d12 = h * (f10 - r10), h * (f11 - r11), h * (f12 - r12)
        d20, d21, d22 = h * (f20 - r20), h * (f21 - r21), h * (f22 - r22)
        s00 = s01 = s02 = s11 = s12 = s22 = 0.0  # sum_free b b^T / m
        w00 = w01 = w02 = w10 = w11 = w12 = w20 = w21 = w22 = 0.0  # sum_free b z^T, row a = b's component
        sb0 = sb1 = sb2 = 0.0  # sum_free b (the hourglass term's translation coupling; the core's column)
        mzx = mzy = mzz = 0.0  # sum_free m z
        m_free = 0.0
        m_all = 0.0
        held = False
        # a core that slides along its joint axis inside the solve (the consistent coupling): one more
        # unknown, dc (docstring); its sums over the members
        ax = ay = az = 0.0
        sliding = rig_move[core] and rig_inv_mass[core] > 0.0
        if sliding:
            ax, ay, az = rig_axis[core, 0], rig_axis[core, 1], rig_axis[core, 2]
            sliding = ax != 0.0 or ay != 0.0 or az != 0.0
        rc = uc = mfix = wfix = 0.0  # a . sum_fix m_j z_j, U_c, M_fix, W_f
        bf0 = bf1 = bf2 = 0.0  # beta_f = sum_fix b_j
        fo0 = fo1 = fo2 = 0.0  # sum_fix m_j o_j
        no0 = no1 = no2 = 0.0  # sum_free m_j o_j
        t00 = t01 = t02 = t10 = t11 = t12 = t20 = t21 = t22 = 0.0  # sum_free b_j o_j^T
        for e in range(start, end):
            j = np.uint64(g_mem[e])
            m = mass[j]
            b0 = g_pack[e, 8]
            b1 = g_pack[e, 9]
            b2 = g_pack[e, 10]
            if sliding:
                o0 = g_pack[e, 4]
                o1 = g_pack[e, 5]
                o2 = g_pack[e, 6]
                if fixed[j]:
                    mfix += m
                    wfix += g_pack[e, 0]
                    bf0 += b0
                    bf1 += b1
                    bf2 += b2
                    fo0 += m * o0
                    fo1 += m * o1
                    fo2 += m * o2
                    uc = ax * g_u[e, 0] + ay * g_u[e, 1] + az * g_u[e, 2]
                else:
                    no0 += m * o0
                    no1 += m * o1
                    no2 += m * o2
                    t00 += b0 * o0
                    t01 += b0 * o1
                    t02 += b0 * o2
                    t10 += b1 * o0
                    t11 += b1 * o1
                    t12 += b1 * o2
                    t20 += b2 * o0
                    t21 += b2 * o1
                    t22 += b2 * o2
            # z_j = u_j + D b_j / m_j (per unit mass)
            inv_m = g_pack[e, 7]
            zx = g_u[e, 0] + (d00 * b0 + d01 * b1 + d02 * b2) * inv_m
            zy = g_u[e, 1] + (d10 * b0 + d11 * b1 + d12 * b2) * inv_m
            zz = g_u[e, 2] + (d20 * b0 + d21 * b1 + d22 * b2) * inv_m
            if hb > 0.0:
                # + beta dt^2 r_j, r_j = x_j - c - F q_j the member's miss from the group's affine fit
                o0 = g_pack[e, 4]
                o1 = g_pack[e, 5]
                o2 = g_pack[e, 6]
                zx += hb * (xp[j, 0] - cx - (f00 * o0 + f01 * o1 + f02 * o2))
                zy += hb * (xp[j, 1] - cy - (f10 * o0 + f11 * o1 + f12 * o2))
                zz += hb * (xp[j, 2] - cz - (f20 * o0 + f21 * o1 + f22 * o2))
                m_all += m
            g_raw[e, 0] = zx
            g_raw[e, 1] = zy
            g_raw[e, 2] = zz
            if fixed[j]:
                held = True
                if sliding:
                    rc += m * (ax * zx + ay * zy + az * zz)
                continue
            sb0 += b0
            sb1 += b1
            sb2 += b2
            if hb > 0.0:
                mzx += m * zx
                mzy += m * zy
                mzz += m * zz
                m_free += m
            s00 += b0 * b0 * inv_m
            s01 += b0 * b1 * inv_m
            s02 += b0 * b2 * inv_m
            s11 += b1 * b1 * inv_m
            s12 += b1 * b2 * inv_m
            s22 += b2 * b2 * inv_m
            w00 += b0 * zx
            w01 += b0 * zy
            w02 += b0 * zz
            w10 += b1 * zx
            w11 += b1 * zy
            w12 += b1 * zz
            w20 += b2 * zx
            w21 += b2 * zy
            w22 += b2 * zz
        v00, v01, v02, v11, v12, v22 = s00, s01, s02, s11, s12, s22  # sum_free b b^T / m (the core's column)
        opm = 1.0
        t = 0.0
        if hb > 0.0:
            # the hourglass term: with D' = (1 + hb) M_f - (hb / M) m_f m_f^T (Sherman-Morrison:
            # D'^-1 v = v / ((1 + hb) m) + t sum v, t = sigma / (1 + hb)^2) and C3 = c I - hb A_qq
            # (positive definite for hourglass_stiffness < 2), S = C3^-1 + B^T D'^-1 B, w = B^T D'^-1 rho
            opm = 1.0 + hb
            sigma = (hb / m_all) / (1.0 - hb * m_free / (m_all * opm))
            t = sigma / (opm * opm)
            io = 1.0 / opm
            s00 = s00 * io + t * sb0 * sb0
            s01 = s01 * io + t * sb0 * sb1
            s02 = s02 * io + t * sb0 * sb2
            s11 = s11 * io + t * sb1 * sb1
            s12 = s12 * io + t * sb1 * sb2
            s22 = s22 * io + t * sb2 * sb2
            w00 = w00 * io + t * sb0 * mzx
            w01 = w01 * io + t * sb0 * mzy
            w02 = w02 * io + t * sb0 * mzz
            w10 = w10 * io + t * sb1 * mzx
            w11 = w11 * io + t * sb1 * mzy
            w12 = w12 * io + t * sb1 * mzz
            w20 = w20 * io + t * sb2 * mzx
            w21 = w21 * io + t * sb2 * mzy
            w22 = w22 * io + t * sb2 * mzz
            i00, i01, i02, i11, i12, i22 = inv_sym3(c - hb * g_cont[i, 8], -hb * g_cont[i, 9], -hb * g_cont[i, 10],
                                                    c - hb * g_cont[i, 11], -hb * g_cont[i, 12], c - hb * g_cont[i, 13])  # fmt: skip
            s00 += i00
            s01 += i01
            s02 += i02
            s11 += i11
            s12 += i12
            s22 += i22
        else:
            ic = 1.0 / c
            s00 += ic
            s11 += ic
            s22 += ic
        y00, y10, y20 = solve_sym3(s00, s01, s02, s11, s12, s22, w00, w10, w20)
        y01, y11, y21 = solve_sym3(s00, s01, s02, s11, s12, s22, w01, w11, w21)
        y02, y12, y22 = solve_sym3(s00, s01, s02, s11, s12, s22, w02, w12, w22)
        # the core's column: moving the fixed members by dc a changes free member j's residual by
        # gamma_j dc a, gamma_j = h (b_j . beta_f) - hb m_j (W_f + beta_f . o_j); the free block's
        # solve of that right-hand side is dx'_j = q_j a with q_j below (w' = sum_free b_j gamma_j / m_j)
        h = dt * dt * k
        yc0 = yc1 = yc2 = 0.0
        gsum = tq = 0.0
        if sliding and held:
            vw0 = h * (v00 * bf0 + v01 * bf1 + v02 * bf2)
            vw1 = h * (v01 * bf0 + v11 * bf1 + v12 * bf2)
            vw2 = h * (v02 * bf0 + v12 * bf1 + v22 * bf2)
            gsum = h * (bf0 * sb0 + bf1 * sb1 + bf2 * sb2)  # sum_free gamma_j
            if hb > 0.0:
                vw0 -= hb * (wfix * sb0 + t00 * bf0 + t01 * bf1 + t02 * bf2)
                vw1 -= hb * (wfix * sb1 + t10 * bf0 + t11 * bf1 + t12 * bf2)
                vw2 -= hb * (wfix * sb2 + t20 * bf0 + t21 * bf1 + t22 * bf2)
                gsum -= hb * (wfix * m_free + bf0 * no0 + bf1 * no1 + bf2 * no2)
                io = 1.0 / opm
                vw0 = vw0 * io + t * sb0 * gsum
                vw1 = vw1 * io + t * sb1 * gsum
                vw2 = vw2 * io + t * sb2 * gsum
            yc0, yc1, yc2 = solve_sym3(s00, s01, s02, s11, s12, s22, vw0, vw1, vw2)
            tq = t * (gsum - (yc0 * sb0 + yc1 * sb1 + yc2 * sb2))
        # the free members' step dx_j = -(z_j - Y^T b_j / m_j), and dF = sum_free dx_j b_j^T (times dt^2 k);
        # with the hourglass term dx_j = -(z_j - Y^T b_j / m_j) / (1 + hb) - t (sum m z - Y^T sum b)
        gx = t * (mzx - (y00 * sb0 + y10 * sb1 + y20 * sb2))
        gy = t * (mzy - (y01 * sb0 + y11 * sb1 + y21 * sb2))
        gz = t * (mzz - (y02 * sb0 + y12 * sb1 + y22 * sb2))
        dc = 0.0
        mcore = 0.0
        if sliding and held:
            # Schur complement on the core: dc = -(R_c + sum gamma_j a . dx_j) / (H_c + sum gamma_j q_j),
            # dx_j the free block's step with the core held (below), R_c and H_c as in the docstring
            mcore = 1.0 / rig_inv_mass[core]
            num = (mcore + m_att - mfix) * uc + rc
            den = mcore + m_att + h * (bf0 * bf0 + bf1 * bf1 + bf2 * bf2)
            if hb > 0.0:
                den += hb * (mfix * (1.0 - wfix) - (bf0 * fo0 + bf1 * fo1 + bf2 * fo2))
            for e in range(start, end):
                j = np.uint64(g_mem[e])
                if fixed[j]:
                    continue
                inv_m = g_pack[e, 7]
                b0 = g_pack[e, 8]
                b1 = g_pack[e, 9]
                b2 = g_pack[e, 10]
                dx, dy, dz = _held_step(b0, b1, b2, inv_m, g_raw[e, 0], g_raw[e, 1], g_raw[e, 2], y00, y01, y02, y10, y11,
                                        y12, y20, y21, y22, hb, opm, gx, gy, gz)  # fmt: skip
                gam, qj = _core_column(b0, b1, b2, inv_m, mass[j], g_pack[e, 4], g_pack[e, 5], g_pack[e, 6], h, hb, bf0,
                                       bf1, bf2, wfix, yc0, yc1, yc2, opm, tq)  # fmt: skip
                num += gam * (ax * dx + ay * dy + az * dz)
                den += gam * qj
            dc = -num / den
        mx = my = mz = 0.0  # sum_free (m_j / M) dx_j: the fit centre's move
        e00 = e01 = e02 = e10 = e11 = e12 = e20 = e21 = e22 = 0.0
        for e in range(start, end):
            j = np.uint64(g_mem[e])
            if fixed[j]:
                continue
            inv_m = g_pack[e, 7]
            b0 = g_pack[e, 8]
            b1 = g_pack[e, 9]
            b2 = g_pack[e, 10]
            dx, dy, dz = _held_step(b0, b1, b2, inv_m, g_raw[e, 0], g_raw[e, 1], g_raw[e, 2], y00, y01, y02, y10, y11, y12,
                                    y20, y21, y22, hb, opm, gx, gy, gz)  # fmt: skip
            if dc != 0.0:
                _, qj = _core_column(b0, b1, b2, inv_m, mass[j], g_pack[e, 4], g_pack[e, 5], g_pack[e, 6], h, hb, bf0, bf1,
                                     bf2, wfix, yc0, yc1, yc2, opm, tq)  # fmt: skip
                dx += dc * qj * ax
                dy += dc * qj * ay
                dz += dc * qj * az
            if hb > 0.0:
                w = g_pack[e, 0]
                mx += w * dx
                my += w * dy
                mz += w * dz
            g_raw[e, 0] = dx
            g_raw[e, 1] = dy
            g_raw[e, 2] = dz
            if held:
                xp[j, 0] += dx
                xp[j, 1] += dy
                xp[j, 2] += dz
                g_u[e, 0] += dx
                g_u[e, 1] += dy
                g_u[e, 2] += dz
                e00 += dx * b0
                e01 += dx * b1
                e02 += dx * b2
                e10 += dy * b0
                e11 += dy * b1
                e12 += dy * b2
                e20 += dz * b0
                e21 += dz * b1
                e22 += dz * b2
        if not held:
            _apply_deformation(i, start, end, g_mem, g_pack, frame, xs, xp, g_u, g_raw)
            continue
        if dc != 0.0:
            slide_core(core, dc, ax, ay, az, mcore, core_lo, core_hi, fixed, xp, rig_x, imp_lin, coupling_imp, dt)
        # each fixed member's residual once the free members moved, r_j = m_j u_j + dt^2 grad_j E:
        # z_j (before) + dt^2 k dF b_j / m_j; its force goes to the core and its u takes it up. A sliding
        # core's move changes it along a alone, where the core's own step has balanced it (its inertia:
        # m_c dc above)
        for e in range(start, end):
            j = np.uint64(g_mem[e])
            if not fixed[j]:
                continue
            m = mass[j]
            b0 = g_pack[e, 8]
            b1 = g_pack[e, 9]
            b2 = g_pack[e, 10]
            rx = g_raw[e, 0] + h * (e00 * b0 + e01 * b1 + e02 * b2) / m
            ry = g_raw[e, 1] + h * (e10 * b0 + e11 * b1 + e12 * b2) / m
            rz = g_raw[e, 2] + h * (e20 * b0 + e21 * b1 + e22 * b2) / m
            if hb > 0.0:
                # its miss from the fit moved by -(the centre's move + dF q_j): F = sum_k x_k b_k^T
                o0 = g_pack[e, 4]
                o1 = g_pack[e, 5]
                o2 = g_pack[e, 6]
                rx -= hb * (mx + e00 * o0 + e01 * o1 + e02 * o2)
                ry -= hb * (my + e10 * o0 + e11 * o1 + e12 * o2)
                rz -= hb * (mz + e20 * o0 + e21 * o1 + e22 * o2)
            if sliding:
                k = ax * rx + ay * ry + az * rz
                rx -= k * ax
                ry -= k * ay
                rz -= k * az
                g_u[e, 0] += dc * ax
                g_u[e, 1] += dc * ay
                g_u[e, 2] += dc * az
            deliver_to_core(j, -m * rx, -m * ry, -m * rz, core, xp, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis,
                            imp_lin, imp_ang, coupling_imp, dt)  # fmt: skip
            g_u[e, 0] -= rx
            g_u[e, 1] -= ry
            g_u[e, 2] -= rz


def continuum_energy(x: np.ndarray, mq: np.ndarray, ainv: np.ndarray, k: float, *, mass: np.ndarray | None = None,
                     beta: float = 0.0) -> tuple[float, np.ndarray, np.ndarray]:  # fmt: skip
    """One continuum group's energy, plain numpy (for tests and for reading: continuum_groups is the
    kernel): ``x`` (n, 3) its members' positions, ``mq`` (n, 3) their m_j q_j, ``ainv`` (3, 3)
    A_qq^+, ``k`` = 2 G V. Returns (E, dE/dx (n, 3), R): E = (k / 2) ||F - R||_F^2, F = sum_j x_j
    b_j^T, b_j = A_qq^+ m_j q_j, R = polar(F) (det +1); dE/dx_j = k (F - R) b_j (R held: the
    derivative through R vanishes, R minimising ||F - R|| over rotations). With ``beta`` > 0 (and
    the members' ``mass``) the hourglass term (beta / 2) sum_j m_j ||r_j||^2 is added, r_j = x_j - c -
    F q_j the member's miss from the group's affine fit (c the centre of mass, q_j = mq_j / m_j);
    its gradient is beta m_j r_j (the fit is the mass-weighted projection onto affine motions)."""
    b = mq @ ainv
    f = x.T @ b
    u, _, vt = np.linalg.svd(f)
    d = np.ones(3)
    d[2] = np.sign(np.linalg.det(u @ vt)) or 1.0
    r = (u * d) @ vt
    diff = f - r
    energy, grad = 0.5 * k * float((diff * diff).sum()), k * b @ diff.T
    if beta > 0.0:
        if mass is None:
            raise ValueError("the hourglass term needs the members' mass")
        c = (mass[:, None] * x).sum(axis=0) / mass.sum()
        miss = x - c - (mq / mass[:, None]) @ f.T
        energy += 0.5 * beta * float((mass[:, None] * miss * miss).sum())
        grad = grad + beta * mass[:, None] * miss
    return energy, grad, r
