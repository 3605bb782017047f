"""The tissue's material solved over all its groups at once: one prefactored linear solve per pass
(the global step of projective dynamics, Bouaziz et al. 2014), in place of the Gauss-Seidel sweep
over the groups (compliant.continuum_groups).

Why: the sweep solves each group's part of the implicit step exactly, but the groups overlap, and
Gauss-Seidel over them closes the gap to the step's solution by a fixed fraction a pass (about
0.55 on the pads, free or pressed), which does not improve as the tissue is refined: finer pads
need more passes and shorter world steps. Solved together, the material's part is exact in one
pass whatever the resolution and whatever kappa dt^2.

The continuum group energy (compliant.continuum_groups, compliant.continuum_energy) is

    E = sum_g (k_g / 2) ||F_g - R_g||_F^2 + (beta_g / 2) sum_{j in g} m_j |x_j - c_g - F_g o_j|^2,

F_g = sum_j x_j b_j^T. With every R_g held (the local step: the polar factor of F_g, warm-started
from the group's last rotation, Mueller et al. 2016) E is quadratic in the positions, and its
Hessian is K (x) I_3 with one scalar N x N matrix

    K = sum_g [k_g B_g B_g^T + beta_g M_g (I - P_g)],

B_g the rows b_j^T, M_g the members' masses and P_g the mass-weighted affine fit,
(P_g)_jk = m_k / M_g + b_k . o_j. It is the same for x, y and z and constant over a run. The
implicit step's Newton system over the free particles is then

    (M + dt^2 K)_ff dx_f = -r_f,   r_j = m_j U_j + dt^2 dE/dx_j,

U_j the displacement the material has given particle j this step (contacts, friction and the
strain limit move particles outside it, as in the sweep, whose per-group displacements sum to
it). One sparse Cholesky factor of (M + dt^2 K)_ff, made once per step length, solves it for x, y
and z (an envelope factor in reverse Cuthill-McKee order: the pads are thin slabs, so the
envelope stays narrow).

A particle held by its core (compliant: ``fixed``, the thesis coupling's attached particles) does
not move in the solve. What is left of its residual after the free particles moved,
r_j + dt^2 (K dx)_j, goes to its core as an impulse (compliant.deliver_to_core), and its U takes
it up: sum_j m_j U_j = 0 after every pass, so momentum is kept exactly, as by the sweep
(sum_j dE/dx_j = 0: F ignores translation and the fit's misses sum to zero).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

from .compliant import deliver_to_core
from .jit import KERNEL
from .model import TissueModel
from .rotation import extract_rotation_unit_t, qmat
from .shape_matching import _turn_centre, group_pack


def material_matrix(model: TissueModel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """K of the module docstring as coordinate triplets (rows, cols, values) [N/m], duplicates
    summed: dE/dx = K x minus the rotations' part, x one coordinate of every particle. Raises ValueError unless every group has the continuum energy."""
    cont = model.group_continuum
    if cont is None or not bool((cont[:, 6] > 0.0).all()):
        raise ValueError("the global material solve needs the continuum group energy on every group "
                         "(TissueConfig.group_energy='continuum')")  # fmt: skip
    pack = group_pack(model)
    off = model.group_offsets.astype(np.int64)
    mem = model.group_members.astype(np.int64)
    rows, cols, vals = [], [], []
    for i in range(off.shape[0] - 1):
        e = slice(off[i], off[i + 1])
        j = mem[e]
        b = pack[e, 8:11]
        o = pack[e, 4:7]
        w = pack[e, 0]
        m = model.particle_mass[j]
        k, beta = cont[i, 6], cont[i, 7]
        block = k * (b @ b.T)
        if beta > 0.0:
            p = w[None, :] + o @ b.T  # (P)_jk = w_k + b_k . o_j
            block = block + beta * (np.diag(m) - m[:, None] * p)  # M (I - P), symmetric
        rows.append(np.repeat(j, j.size))
        cols.append(np.tile(j, j.size))
        vals.append(block.ravel())
    n = model.particle_count
    key = np.concatenate(rows) * n + np.concatenate(cols) if rows else np.zeros(0, dtype=np.int64)
    uniq, inv = np.unique(key, return_inverse=True)
    summed = np.zeros(uniq.size)
    np.add.at(summed, inv, np.concatenate(vals) if vals else np.zeros(0))
    return uniq // n, uniq % n, summed


@nb.njit(cache=True)
def _rcm(ptr, idx, degree, n):
    """Reverse Cuthill-McKee order of a symmetric pattern in CSR (``ptr``, ``idx``; no self
    entries): breadth first from a node of least degree in each component, neighbours by degree,
    reversed (George & Liu 1981)."""
    order = np.empty(n, dtype=np.int64)
    seen = np.zeros(n, dtype=np.bool_)
    by_degree = np.argsort(degree, kind="mergesort")
    head = 0
    for s in by_degree:
        if seen[s]:
            continue
        # a pseudo-peripheral start: the farthest node of a breadth-first search, twice
        start = s
        for _ in range(2):
            level = np.full(n, -1, dtype=np.int64)
            queue = [start]
            level[start] = 0
            q = 0
            while q < len(queue):
                u = queue[q]
                q += 1
                for e in range(ptr[u], ptr[u + 1]):
                    v = idx[e]
                    if level[v] < 0:
                        level[v] = level[u] + 1
                        queue.append(v)
            far = queue[-1]
            for u in queue:  # of the last level, the least degree
                if level[u] == level[far] and degree[u] < degree[far]:
                    far = u
            start = far
        seen[start] = True
        order[head] = start
        tail = head + 1
        while head < tail:
            u = order[head]
            head += 1
            lo = tail
            for e in range(ptr[u], ptr[u + 1]):
                v = idx[e]
                if seen[v]:
                    continue
                seen[v] = True
                # insert by (degree, index) among those added from u
                k = tail
                while k > lo and (degree[order[k - 1]] > degree[v]
                                  or (degree[order[k - 1]] == degree[v] and order[k - 1] > v)):
                    order[k] = order[k - 1]
                    k -= 1
                order[k] = v
                tail += 1
    return order[::-1].copy()


@nb.njit(cache=True, error_model="numpy")
def _envelope_factor(first, ptr, val):
    """In place: the envelope (skyline) Cholesky factor L of a symmetric positive definite matrix
    stored by rows, row i holding columns first[i]..i at val[ptr[i]:ptr[i + 1]]; L takes the same
    envelope. Returns -1, or the first row whose pivot is not positive."""
    n = first.shape[0]
    for i in range(n):
        fi = first[i]
        pi = ptr[i] - fi  # val[pi + c]: row i, column c
        for j in range(fi, i + 1):
            pj = ptr[j] - first[j]
            s = val[pi + j]
            for c in range(max(fi, first[j]), j):
                s -= val[pi + c] * val[pj + c]
            if j < i:
                val[pi + j] = s / val[pj + j]
            elif s > 0.0:
                val[pi + i] = np.sqrt(s)
            else:
                return i
    return -1


@nb.njit(**KERNEL)
def envelope_solve(first, ptr, val, b):
    """Solve L L^T x = b in place for the columns of ``b`` (n, 3), L from _envelope_factor."""
    n = first.shape[0]
    for i in range(n):  # L y = b, by rows
        pi = ptr[i] - first[i]
        s0, s1, s2 = b[i, 0], b[i, 1], b[i, 2]
        for c in range(first[i], i):
            lv = val[pi + c]
            s0 -= lv * b[c, 0]
            s1 -= lv * b[c, 1]
            s2 -= lv * b[c, 2]
        d = val[pi + i]
        b[i, 0] = s0 / d
        b[i, 1] = s1 / d
        b[i, 2] = s2 / d
    for i in range(n - 1, -1, -1):  # L^T x = y, by the columns of L^T (the rows of L)
        pi = ptr[i] - first[i]
        d = val[pi + i]
        x0 = b[i, 0] / d
        x1 = b[i, 1] / d
        x2 = b[i, 2] / d
        b[i, 0] = x0
        b[i, 1] = x1
        b[i, 2] = x2
        for c in range(first[i], i):
            lv = val[pi + c]
            b[c, 0] -= lv * x0
            b[c, 1] -= lv * x1
            b[c, 2] -= lv * x2


@dataclass(eq=False)
class GlobalSystem:
    """The prefactored system of one model at one step length (module docstring), and the pass's
    scratch. ``arrays()`` is what the kernel takes."""

    dt: float
    """The step length [s] the factor is for."""
    order: np.ndarray
    """(F,) int64: the free particle at each row of the factor."""
    first: np.ndarray
    """(F,) int64: the first column of each row's envelope."""
    ptr: np.ndarray
    """(F + 1,) int64: row i of the factor at factor[ptr[i]:ptr[i + 1]]."""
    factor: np.ndarray
    """The envelope Cholesky factor of (M + dt^2 K)_ff."""
    held: np.ndarray
    """(H,) int64: the particles held by their cores."""
    held_ptr: np.ndarray
    """(H + 1,) int64: held particle h's row of K over the free particles, at
    held_col / held_val[held_ptr[h]:held_ptr[h + 1]]."""
    held_col: np.ndarray
    """int64: the factor row of each entry's free particle."""
    held_val: np.ndarray
    """K's entries [kg/s^2]."""
    displacement: np.ndarray
    """(N, 3) scratch: U, the displacement the material gave each particle this step [m]."""
    gradient: np.ndarray
    """(N, 3) scratch: dE/dx [N]."""
    rhs: np.ndarray
    """(F, 3) scratch: the solve's right-hand sides, then its solution."""

    def arrays(self) -> tuple:
        return (self.order, self.first, self.ptr, self.factor, self.held, self.held_ptr, self.held_col, self.held_val,
                self.displacement, self.gradient, self.rhs)  # fmt: skip

    @property
    def envelope(self) -> int:
        """Entries of the factor (its memory is 8 bytes each; a solve reads each twice)."""
        return int(self.factor.shape[0])


def build_global_system(model: TissueModel, dt: float) -> GlobalSystem:
    """Assemble K, order the free particles (reverse Cuthill-McKee) and factor (M + dt^2 K)_ff for
    a step of ``dt`` [s]. Held particles: attached, of a body with a core (anchors.mark_fixed).
    Raises ValueError unless every group has the continuum energy, or if the matrix is not
    positive definite (it always is: M > 0 and K >= 0, so this would be a bug)."""
    if not dt > 0.0:
        raise ValueError(f"dt must be positive, got {dt!r}")
    r, c, v = material_matrix(model)
    n = model.particle_count
    held_mask = model.particle_attached & (model.body_core_shape[model.particle_body] >= 0)
    free = np.flatnonzero(~held_mask)
    held = np.flatnonzero(held_mask)
    slot = np.full(n, -1, dtype=np.int64)
    # order the free particles
    ff = ~held_mask[r] & ~held_mask[c]
    off_diag = ff & (r != c)
    local = np.full(n, -1, dtype=np.int64)
    local[free] = np.arange(free.size)
    pr, pc = local[r[off_diag]], local[c[off_diag]]
    srt = np.lexsort((pc, pr))
    pr, pc = pr[srt], pc[srt]
    ptr = np.zeros(free.size + 1, dtype=np.int64)
    np.add.at(ptr, pr + 1, 1)
    ptr = np.cumsum(ptr)
    degree = np.diff(ptr)
    perm = _rcm(ptr, pc.astype(np.int64), degree.astype(np.int64), free.size) if free.size else np.zeros(0, np.int64)
    order = free[perm]
    slot[order] = np.arange(order.size)
    # the envelope of (M + dt^2 K)_ff in that order, lower triangle by rows
    fr, fc, fv = slot[r[ff]], slot[c[ff]], dt * dt * v[ff]
    low = fc <= fr
    fr, fc, fv = fr[low], fc[low], fv[low]
    first = np.arange(order.size, dtype=np.int64)
    np.minimum.at(first, fr, fc)
    eptr = np.zeros(order.size + 1, dtype=np.int64)
    eptr[1:] = np.cumsum(np.arange(order.size) - first + 1)
    factor = np.zeros(int(eptr[-1]))
    np.add.at(factor, eptr[fr] + (fc - first[fr]), fv)
    factor[eptr[:-1] + (np.arange(order.size) - first)] += model.particle_mass[order]
    bad = _envelope_factor(first, eptr, factor)
    if bad >= 0:
        raise ValueError(f"the material's matrix is not positive definite at particle {int(order[bad])}")
    # the held particles' rows of K over the free ones
    hf = held_mask[r] & ~held_mask[c]
    hr, hc, hv = r[hf], slot[c[hf]], v[hf]
    hrow = np.searchsorted(held, hr)
    srt = np.lexsort((hc, hrow))
    hrow, hc, hv = hrow[srt], hc[srt], hv[srt]
    hptr = np.zeros(held.size + 1, dtype=np.int64)
    np.add.at(hptr, hrow + 1, 1)
    return GlobalSystem(dt=float(dt), order=order.astype(np.int64), first=first, ptr=eptr, factor=factor,
                        held=held.astype(np.int64), held_ptr=np.cumsum(hptr), held_col=hc.astype(np.int64),
                        held_val=hv, displacement=np.zeros((n, 3)), gradient=np.zeros((n, 3)),
                        rhs=np.zeros((order.size, 3)))  # fmt: skip


@nb.njit(**KERNEL)
def material_gradient(rot_iters, g_off, g_mem, g_pack, g_cont, xp, group_q, mass, grad):
    """grad = dE/dx at ``xp`` [N] with each group's R the polar factor of its F (warm-started from
    group_q, which takes it): the local step. The arithmetic of a group's F, R and residual is
    continuum_groups'."""
    grad[...] = 0.0
    for g in range(g_off.shape[0] - 1):
        i = np.uint64(g)
        start = np.uint64(g_off[i])
        end = np.uint64(g_off[i + 1])
        k = g_cont[i, 6]
        beta = g_cont[i, 7]
        f00 = f01 = f02 = f10 = f11 = f12 = f20 = f21 = f22 = 0.0
        cx = cy = cz = 0.0
        for e in range(start, end):
            j = np.uint64(g_mem[e])
            x0 = xp[j, 0]
            x1 = xp[j, 1]
            x2 = xp[j, 2]
            b0 = g_pack[e, 8]
            b1 = g_pack[e, 9]
            b2 = g_pack[e, 10]
            f00 += x0 * b0
            f01 += x0 * b1
            f02 += x0 * b2
            f10 += x1 * b0
            f11 += x1 * b1
            f12 += x1 * b2
            f20 += x2 * b0
            f21 += x2 * b1
            f22 += x2 * b2
            if beta > 0.0:
                w = g_pack[e, 0]
                cx += w * x0
                cy += w * x1
                cz += w * x2
        qr = extract_rotation_unit_t((f00, f01, f02, f10, f11, f12, f20, f21, f22),
                                     (group_q[i, 0], group_q[i, 1], group_q[i, 2], group_q[i, 3]), rot_iters, 1e-10)  # fmt: skip
        group_q[i, 0] = qr[0]
        group_q[i, 1] = qr[1]
        group_q[i, 2] = qr[2]
        group_q[i, 3] = qr[3]
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = qmat(qr)
        d00, d01, d02 = k * (f00 - r00), k * (f01 - r01), k * (f02 - r02)
        d10, d11, d12 = k * (f10 - r10), k * (f11 - r11), k * (f12 - r12)
        d20, d21, d22 = k * (f20 - r20), k * (f21 - r21), k * (f22 - r22)
        for e in range(start, end):
            j = np.uint64(g_mem[e])
            b0 = g_pack[e, 8]
            b1 = g_pack[e, 9]
            b2 = g_pack[e, 10]
            gx = d00 * b0 + d01 * b1 + d02 * b2
            gy = d10 * b0 + d11 * b1 + d12 * b2
            gz = d20 * b0 + d21 * b1 + d22 * b2
            if beta > 0.0:
                # + beta m_j (x_j - c - F o_j), the member's miss from the group's affine fit
                o0 = g_pack[e, 4]
                o1 = g_pack[e, 5]
                o2 = g_pack[e, 6]
                bm = beta * mass[j]
                gx += bm * (xp[j, 0] - cx - (f00 * o0 + f01 * o1 + f02 * o2))
                gy += bm * (xp[j, 1] - cy - (f10 * o0 + f11 * o1 + f12 * o2))
                gz += bm * (xp[j, 2] - cz - (f20 * o0 + f21 * o1 + f22 * o2))
            grad[j, 0] += gx
            grad[j, 1] += gy
            grad[j, 2] += gz


@nb.njit(**KERNEL)
def global_pass(gsys, rot_iters, dt, g_turn, g_off, g_mem, g_pack, g_cont, attached, rest_q, rest_moment, xp, qp,
                group_q, moment, mass, p_body, body_core_shape, shape_rigid, rig_x, rig_q, rig_inv_mass,
                rig_inv_inertia, rig_axis, imp_lin, imp_ang, coupling_imp):  # fmt: skip
    """One pass of the material over every group (module docstring): the local step (each group's
    R), the global solve for the free particles, the held particles' forces onto their cores, and
    each free group centre's turn toward quat(R) q_bar (as the sweep turns them: sweep_body)."""
    order, first, ptr, factor, held, held_ptr, held_col, held_val, u, grad, rhs = gsys
    material_gradient(rot_iters, g_off, g_mem, g_pack, g_cont, xp, group_q, mass, grad)
    h = dt * dt
    for r in range(order.shape[0]):
        j = order[r]
        m = mass[j]
        rhs[r, 0] = -(m * u[j, 0] + h * grad[j, 0])
        rhs[r, 1] = -(m * u[j, 1] + h * grad[j, 1])
        rhs[r, 2] = -(m * u[j, 2] + h * grad[j, 2])
    envelope_solve(first, ptr, factor, rhs)
    for r in range(order.shape[0]):
        j = order[r]
        for a in range(3):
            xp[j, a] += rhs[r, a]
            u[j, a] += rhs[r, a]
    # a held particle's residual after the free ones moved: m U + dt^2 (grad + K dx); its core takes it
    for hh in range(held.shape[0]):
        j = held[hh]
        m = mass[j]
        kx = ky = kz = 0.0
        for e in range(held_ptr[hh], held_ptr[hh + 1]):
            c = held_col[e]
            kv = held_val[e]
            kx += kv * rhs[c, 0]
            ky += kv * rhs[c, 1]
            kz += kv * rhs[c, 2]
        rx = m * u[j, 0] + h * (grad[j, 0] + kx)
        ry = m * u[j, 1] + h * (grad[j, 1] + ky)
        rz = m * u[j, 2] + h * (grad[j, 2] + kz)
        core = shape_rigid[body_core_shape[p_body[j]]]
        deliver_to_core(j, -rx, -ry, -rz, core, xp, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin,
                        imp_ang, coupling_imp, dt)  # fmt: skip
        u[j, 0] -= rx / m
        u[j, 1] -= ry / m
        u[j, 2] -= rz / m
    for i in range(g_off.shape[0] - 1):
        if not attached[i]:
            qr = (group_q[i, 0], group_q[i, 1], group_q[i, 2], group_q[i, 3])
            _turn_centre(i, qr, g_turn[i], rest_q, qp, rest_moment, moment)
