"""Time integration of the particles: the prediction before the solve and the velocity update
after it (position-based dynamics, Mueller et al. 2007 Alg. 1 lines 5-11 and 18-21, with the
orientations of Mueller & Chentanez 2011 sec. 3).

    predict:  v += g dt; damp each particle's deviation from its body's rigid motion;
              x* = x + v dt; q* = [w_hat sin(|w| dt / 2), cos(|w| dt / 2)] q
    update:   v = (x* - x) / dt; w from the particle's angular momentum at its new orientation
"""

from __future__ import annotations

import math

import numba as nb

from .jit import KERNEL
from .linalg import solve_sym3
from .rotation import qconj, qexp, qmat, qmul, qnormalize, qrotate
from .shape_matching import refresh_moment


@nb.njit(cache=True, inline="always", error_model="numpy", fastmath={"contract"})
def _world_inertia(i, q, inertia):
    """Upper triangle of particle i's world inertia R diag(I_i) R^T."""
    r0, r1, r2, r3, r4, r5, r6, r7, r8 = qmat((q[i, 0], q[i, 1], q[i, 2], q[i, 3]))
    d0, d1, d2 = inertia[i, 0], inertia[i, 1], inertia[i, 2]
    return (d0 * r0 * r0 + d1 * r1 * r1 + d2 * r2 * r2, d0 * r0 * r3 + d1 * r1 * r4 + d2 * r2 * r5,
            d0 * r0 * r6 + d1 * r1 * r7 + d2 * r2 * r8, d0 * r3 * r3 + d1 * r4 * r4 + d2 * r5 * r5,
            d0 * r3 * r6 + d1 * r4 * r7 + d2 * r5 * r8, d0 * r6 * r6 + d1 * r7 * r7 + d2 * r8 * r8)  # fmt: skip


@nb.njit(**KERNEL)
def _damped_velocities(x, v, q, omega, mass, inertia, body_off, c, vd, wd):
    """Damp each particle's deviation from its body's rigid motion by the fraction c (Mueller et
    al. 2007 sec. 3.5): v_i += c (v_cm + W x r_i - v_i), w_i += c (W - w_i), with v_cm the body's
    centre-of-mass velocity and W its angular velocity, I^-1 L with the particles' own inertia and
    spin in both (I = sum m (r^2 1 - r r^T) + sum R_i I_i R_i^T, L = sum m r x v + sum R_i I_i R_i^T
    w_i). Rigid motion, so momentum and angular momentum, are kept exactly: a falling or spinning
    body is not slowed, unlike damping the absolute velocity."""
    for b in range(body_off.shape[0] - 1):
        _damped_body(b, x, v, q, omega, mass, inertia, body_off, c, vd, wd)


@nb.njit(**KERNEL)
def _damped_body(b, x, v, q, omega, mass, inertia, body_off, c, vd, wd):
    """_damped_velocities of body b."""
    s = body_off[b]
    e = body_off[b + 1]
    if c == 0.0:
        for i in range(s, e):
            for a in range(3):
                vd[i, a] = v[i, a]
                wd[i, a] = omega[i, a]
        return
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
        j00, j01, j02, j11, j12, j22 = _world_inertia(i, q, inertia)
        wx, wy, wz = omega[i, 0], omega[i, 1], omega[i, 2]
        lx += m * (ry * v[i, 2] - rz * v[i, 1]) + j00 * wx + j01 * wy + j02 * wz
        ly += m * (rz * v[i, 0] - rx * v[i, 2]) + j01 * wx + j11 * wy + j12 * wz
        lz += m * (rx * v[i, 1] - ry * v[i, 0]) + j02 * wx + j12 * wy + j22 * wz
        i00 += m * (ry * ry + rz * rz) + j00
        i11 += m * (rx * rx + rz * rz) + j11
        i22 += m * (rx * rx + ry * ry) + j22
        i01 += j01 - m * rx * ry
        i02 += j02 - m * rx * rz
        i12 += j12 - m * ry * rz
    wx, wy, wz = solve_sym3(i00, i01, i02, i11, i12, i22, lx, ly, lz)
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


@nb.njit(**KERNEL)
def predict_particles(x, v, q, omega, group_q, mass, inertia, body_off, rest_moment, gx, gy, gz, damping, dt, xp, qp,
                      q_pred, vd, wd, moment):  # fmt: skip
    """Predicted positions xp and orientations qp of every particle (PBD Alg. 1 lines 5-11; Mueller
    & Chentanez 2011 sec. 3): v += g dt; damping of the deviation from each body's rigid motion;
    x* = x + v dt; q* = [w_hat sin(|w| dt / 2), cos(|w| dt / 2)] q. Refreshes the cached particle
    moments and carries each group's warm-start rotation along; q_pred keeps the predicted
    orientations (what the group solve's turns are measured from)."""
    fd = math.exp(-damping * dt)
    _damped_velocities(x, v, q, omega, mass, inertia, body_off, 1.0 - fd, vd, wd)
    predict_particles_of(0, x.shape[0], x, q, group_q, rest_moment, gx, gy, gz, dt, xp, qp, q_pred, vd, wd, moment)


@nb.njit(**KERNEL)
def predict_body(b, x, v, q, omega, group_q, mass, inertia, body_off, rest_moment, gx, gy, gz, damping, dt, xp, qp,
                 q_pred, vd, wd, moment):  # fmt: skip
    """predict_particles of body b alone (its particles are body_off[b] .. body_off[b + 1] - 1)."""
    fd = math.exp(-damping * dt)
    _damped_body(b, x, v, q, omega, mass, inertia, body_off, 1.0 - fd, vd, wd)
    predict_particles_of(body_off[b], body_off[b + 1], x, q, group_q, rest_moment, gx, gy, gz, dt, xp, qp, q_pred, vd,
                         wd, moment)  # fmt: skip


@nb.njit(**KERNEL)
def predict_particles_of(lo, hi, x, q, group_q, rest_moment, gx, gy, gz, dt, xp, qp, q_pred, vd, wd, moment):
    """predict_particles' prediction of particles lo .. hi - 1 from their damped velocities vd, wd."""
    for i in range(lo, hi):
        for a in range(3):
            g = gx if a == 0 else (gy if a == 1 else gz)
            xp[i, a] = x[i, a] + (vd[i, a] + g * dt) * dt
        dq = qexp((wd[i, 0] * dt, wd[i, 1] * dt, wd[i, 2] * dt))
        qn = qnormalize(qmul(dq, (q[i, 0], q[i, 1], q[i, 2], q[i, 3])))
        for a in range(4):
            qp[i, a] = qn[a]
            q_pred[i, a] = qn[a]
        refresh_moment(i, qn, rest_moment, moment)
        # Warm start of group i's rotation, carried forward by its centre's spin: a stale warm start
        # lags a turning group, and every lagging projection brakes the rotation.
        gq = qnormalize(qmul(dq, (group_q[i, 0], group_q[i, 1], group_q[i, 2], group_q[i, 3])))
        for a in range(4):
            group_q[i, a] = gq[a]


@nb.njit(**KERNEL)
def update_velocities(x, v, q, omega, xp, qp, wd, inertia, spin_kick, attached, dt):
    """Velocities from positions (PBD Alg. 1 lines 18-21). Angular velocities from angular momentum:
    each particle's own angular momentum l = R_0 I R_0^T w (the rotation it was predicted with,
    at the step's start orientation) plus the angular impulses of its turns (spin_kick / dt), and
    w = R I^-1 R^T l at the new orientation, as a rigid body turns: force-free it keeps l, not w.
    (The paper's w = axis angle(q* q^-1) / dt agrees to first order; it is l that shape matching's
    torque balance conserves, so it is l that is carried.) Then x = x*, q = q*. Attached particles
    take their core's velocities after pybullet's step (coupling.sync_attached): theirs are left."""
    update_velocities_of(0, x.shape[0], x, v, q, omega, xp, qp, wd, inertia, spin_kick, attached, dt)


@nb.njit(**KERNEL)
def update_velocities_of(lo, hi, x, v, q, omega, xp, qp, wd, inertia, spin_kick, attached, dt):
    """update_velocities of particles lo .. hi - 1."""
    inv_dt = 1.0 / dt
    for i in range(lo, hi):
        for a in range(3):
            v[i, a] = (xp[i, a] - x[i, a]) * inv_dt
            x[i, a] = xp[i, a]
        if attached[i]:
            for a in range(4):
                q[i, a] = qp[i, a]
            continue
        q0 = (q[i, 0], q[i, 1], q[i, 2], q[i, 3])
        q1 = (qp[i, 0], qp[i, 1], qp[i, 2], qp[i, 3])
        u = qrotate(qconj(q0), (wd[i, 0], wd[i, 1], wd[i, 2]))
        lw = qrotate(q0, (inertia[i, 0] * u[0], inertia[i, 1] * u[1], inertia[i, 2] * u[2]))
        lx = lw[0] + spin_kick[i, 0] * inv_dt
        ly = lw[1] + spin_kick[i, 1] * inv_dt
        lz = lw[2] + spin_kick[i, 2] * inv_dt
        u = qrotate(qconj(q1), (lx, ly, lz))
        w = qrotate(q1, (u[0] / inertia[i, 0], u[1] / inertia[i, 1], u[2] / inertia[i, 2]))
        for a in range(3):
            omega[i, a] = w[a]
        for a in range(4):
            q[i, a] = qp[i, a]
