"""Coulomb friction at position level, static and kinetic, on the contacts of contacts.py
(Macklin et al. 2014, "Unified Particle Physics for Real-Time Applications", eq. 23-24; Mueller et al.
2020 sec. 3.5).

Each touched contact cancels its slip since the step began while the accumulated tangential
multiplier stays within mu_s times the normal one (stick), else slides with it capped at mu_k
times the normal one. Against a rigid body the slip is relative to the body point touched, and
the correction goes onto the body with its generalised inverse mass (two-way, like the normal
contact). Whether a squeezed cylinder can be lifted at all is decided here: held iff 2 mu N >= m g.
"""

from __future__ import annotations

import math

import numba as nb

from .rigid import generalized_inv_mass, rigid_apply
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
# Gauss-Seidel iteration (see contacts.py).
@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def friction_shape_contacts(
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
            wb = generalized_inv_mass(r, rig_q, rig_inv_mass, rig_inv_inertia, rx, ry, rz, tx, ty, tz)
        b = p_body[i]
        dl = _coulomb(tl / (wp + wb), c_lambda_t[c], lam_n, body_friction[b, 0], body_friction[b, 1])
        c_lambda_t[c] += dl
        xp[i, 0] -= wp * dl * tx
        xp[i, 1] -= wp * dl * ty
        xp[i, 2] -= wp * dl * tz
        if r >= 0:
            rigid_apply(r, rx, ry, rz, dl * tx, dl * ty, dl * tz, rig_move[r], dt, rig_x, rig_q, rig_inv_mass,
                        rig_inv_inertia, imp_lin, imp_ang)  # fmt: skip


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
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

