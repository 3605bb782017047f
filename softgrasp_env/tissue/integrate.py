"""Time integration of the particles: the prediction before the solve and the velocity update
after it (position-based dynamics, Mueller et al. 2007 Alg. 1 lines 5-11 and 18-21, with the
orientations of Mueller & Chentanez 2011 sec. 3).

    predict:  v += g dt; damp each particle's deviation from its body's rigid motion;
              x* = x + v dt; q* = [w_hat sin(|w| dt / 2), cos(|w| dt / 2)] q
    update:   v = (x* - x) / dt; w = axis angle(q* q^-1) / dt on the short arc
"""

from __future__ import annotations

import math

import numba as nb

from .linalg import solve_sym3
from .rotation import qconj, qexp, qlog, qmul, qnormalize
from .shape_matching import ORIENT_GOAL, refresh_moment


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


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def predict_particles(x, v, q, omega, group_q, mass, body_off, rest_moment, gx, gy, gz, damping, dt, orient_mode, xp,
                      qp, vd, wd, moment):  # fmt: skip
    """Predicted positions xp and orientations qp of every particle (PBD Alg. 1 lines 5-11; Mueller
    & Chentanez 2011 sec. 3): v += g dt; damping of the deviation from each body's rigid motion;
    x* = x + v dt; q* = [w_hat sin(|w| dt / 2), cos(|w| dt / 2)] q. Refreshes the cached particle
    moments (goal mode) and carries each group's warm-start rotation along."""
    n = x.shape[0]
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
            refresh_moment(i, qn, rest_moment, moment)
        # Warm start of group i's rotation, carried forward by its centre's spin: a stale warm start
        # lags a turning group, and every lagging projection brakes the rotation.
        gq = qnormalize(qmul(dq, (group_q[i, 0], group_q[i, 1], group_q[i, 2], group_q[i, 3])))
        for a in range(4):
            group_q[i, a] = gq[a]


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def update_velocities(x, v, q, omega, xp, qp, dt):
    """Velocities from positions (PBD Alg. 1 lines 18-21); angular velocity from q* q^-1 on the short
    arc (Mueller & Chentanez 2011 sec. 3). Then x = x*, q = q*."""
    n = x.shape[0]
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
