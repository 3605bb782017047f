"""The tissue's material solved over all its groups at once (SimConfig.material_solve "global"):
one prefactored linear solve per pass, in place of the Gauss-Seidel sweep over the groups
(compliant.continuum_groups).

Why: the sweep solves each group's part of the implicit step exactly, but the groups overlap, and
Gauss-Seidel over them closes the gap to the step's solution by a fixed fraction a pass (about
0.55 on the pads, free or pressed), which does not improve as the tissue is refined: finer pads
need more passes and shorter world steps.

The continuum group energy (compliant.continuum_groups, compliant.continuum_energy) is

    E = sum_g (k_g / 2) ||F_g - R_g||_F^2 + (beta_g / 2) sum_{j in g} m_j |x_j - c_g - F_g o_j|^2,

F_g = sum_j x_j b_j^T, R_g the polar factor of F_g. Each pass takes a quasi-Newton step of the
implicit (backward Euler) step's equations for the free particles,

    (M + dt^2 K0)_ff dx_f = -r_f,   r_j = m_j U_j + dt^2 dE/dx_j,

U_j the displacement the material has given particle j this step (contacts, friction and the
strain limit move particles outside it, as in the sweep, whose per-group displacements sum to it)
and dE/dx the true gradient, every R_g the polar factor of its F_g (the local step: Newton's
method on tr(R^T F), warm-started from the group's last rotation, rotation.polar_rotation_unit_t).
K0 is E's Hessian at rest, the rotations' derivative included: near rest
||F - R||^2 = ||sym(F - I)||^2, so a pair (j, k) of a group's members has the block
(k_g / 2) [(b_j . b_k) I + b_k b_j^T] (the small-strain stiffness at Poisson's ratio 0), plus the
hourglass term's beta_g (M_g (I - P_g))_jk I, P_g the mass-weighted affine fit,
(P_g)_jk = m_k / M_g + b_k . o_j. Projective dynamics' global step (Bouaziz et al. 2014) holds
every R_g instead, and its matrix K (x) I_3 is twice as stiff as the material against the shears
that turn the groups: it converged at about 0.45 a pass, no faster than the sweep (the package's
documentation, Results: speed, "A solve across the groups"); K0 gains 40-250x a pass at every
resolution and step length. K0 is constant in each body's rest frame, so one factor, made once
per step length (an envelope Cholesky factor in reverse Cuthill-McKee order), serves the run:
residuals turn into the body's frame with its core, and the step turns back.

A particle held by its core (compliant: ``fixed``, the thesis coupling's attached particles) does
not move in the solve: its residual goes to its core as an impulse (compliant.deliver_to_core) at
every pass, and its U takes it up. After the last pass every particle's residual goes to its core
(global_finish), so momentum and angular momentum are exact every step (sum_j dE/dx_j = 0: F
ignores translation, the fit's misses sum to zero, and E does not change under a rotation).

Contacts and friction move a particle by its compliance in the whole pad, n . W_jj n with
W = (M + dt^2 K0)^-1 (project_contacts, friction_weights), and record their impulse in U, so that
the material's next pass reads the impulse as its load: moved by 1 / m, as the sweep moves them,
the material took back part of each correction and a pressed pad needed as many passes as under
the sweep. The solve's accuracy does not fall as kappa dt^2 grows, so the world runs in the
coupling rule's steps only (compliant.world_substeps).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field, replace

import numba as nb
import numpy as np

from .compliant import deliver_to_core
from .contacts import contact_reach
from .jit import KERNEL
from .model import TissueModel
from .multigrid import Hierarchy, build_levels, pack, probed_compliance, rigid_modes, v_cycle
from .rigid import generalized_inv_mass, rigid_apply
from .rotation import polar_rotation_unit_t, qmat
from .shape_matching import _turn_centre, group_pack

POLAR_ITERATIONS = 20
"""Most Newton iterations of a group's local step (rotation.polar_rotation_unit_t, stopping once
the step is below 1e-10 rad; from the last pass's rotation it takes two or three). The
quasi-Newton step trusts the gradient, so R must be the polar factor itself: one warm-started
sweep of Mueller et al.'s extraction a pass, as the group sweep takes, left a 16 % error in a pad's
static sag, and 20 of them still left 1e-5 rad at 60 % stretch (a third of the error an iteration)."""


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


@nb.njit(cache=True, error_model="numpy", fastmath={"contract", "reassoc"})
def _envelope_factor(first, ptr, val):
    """In place: the envelope (skyline) Cholesky factor L of a symmetric positive definite matrix
    stored by rows, row i holding columns first[i]..i at val[ptr[i]:ptr[i + 1]]; L takes the same
    envelope. Returns -1, or the first row whose pivot is not positive. Unsigned indices and
    reassociated dot products, as envelope_solve."""
    n = first.shape[0]
    for i in range(n):
        fi = np.uint64(first[i])
        ai = np.uint64(ptr[i])  # val[ai + (c - fi)]: row i, column c
        for j in range(fi, i + 1):
            fj = np.uint64(first[j])
            aj = np.uint64(ptr[j])
            c0 = max(fi, fj)
            s = 0.0
            for c in range(c0, j):
                s += val[ai + (c - fi)] * val[aj + (c - fj)]
            s = val[ai + (np.uint64(j) - fi)] - s
            if j < i:
                val[ai + (np.uint64(j) - fi)] = s / val[aj + (np.uint64(j) - fj)]
            elif s > 0.0:
                val[ai + (np.uint64(i) - fi)] = np.sqrt(s)
            else:
                return i
    return -1


@nb.njit(cache=True, error_model="numpy", fastmath={"contract", "reassoc"}, _nrt=False)
def envelope_solve(first, ptr, val, b):
    """Solve L L^T x = b in place (``b`` a vector), L from _envelope_factor. Compiled with
    reassociation, so that the forward substitution's dot products run in SIMD lanes, and indexed
    with unsigned integers: a signed index makes numba wrap negative ones around, a branch per load
    that kept LLVM from vectorising either loop (x7-14 at 450-1,200 particles). The same machine
    code gives the same result on every run."""
    envelope_solve_rows(first, ptr, val, b, 0, first.shape[0])


@nb.njit(cache=True, error_model="numpy", fastmath={"contract", "reassoc"}, _nrt=False)
def envelope_solve_rows(first, ptr, val, b, lo, n):
    """envelope_solve of the diagonal block of rows lo .. n - 1, which no row outside it reaches
    (first[i] >= lo for every row of the block: one body's rows, GlobalSystem.body_rows): its
    arithmetic, row by row, is the whole solve's."""
    for i in range(lo, n):  # L y = b, by rows
        a = np.uint64(ptr[i])
        c0 = np.uint64(first[i])
        m = np.uint64(i) - c0
        s = 0.0
        for k in range(m):
            s += val[a + k] * b[c0 + k]
        b[i] = (b[i] - s) / val[a + m]
    for i in range(n - 1, lo - 1, -1):  # L^T x = y, by the columns of L^T (the rows of L)
        a = np.uint64(ptr[i])
        c0 = np.uint64(first[i])
        m = np.uint64(i) - c0
        x = b[i] / val[a + m]
        b[i] = x
        for k in range(m):
            b[c0 + k] -= val[a + k] * x


def rest_hessian(model: TissueModel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """K0, the Hessian of E at rest with the rotations' derivative included, as coordinate
    triplets over the 3N coordinates (3 j + a: particle j's axis a) [N/m], duplicates summed. Near
    rest ||F - R||^2 = ||sym(F - I)||^2, so a pair (j, k) of a group's members has the block
    (k_g / 2) [(b_j . b_k) I + b_k b_j^T] (the small-strain stiffness at Poisson's ratio 0), plus
    the hourglass term's beta_g (M_g (I - P_g))_jk I. Constant over a run in the body's rest frame."""
    cont = model.group_continuum
    if cont is None or not bool((cont[:, 6] > 0.0).all()):
        raise ValueError("the global material solve needs the continuum group energy on every group "
                         "(TissueConfig.group_energy='continuum')")  # fmt: skip
    pack = group_pack(model)
    off = model.group_offsets.astype(np.int64)
    mem = model.group_members.astype(np.int64)
    eye = np.eye(3)
    rows, cols, vals = [], [], []
    for i in range(off.shape[0] - 1):
        e = slice(off[i], off[i + 1])
        j = mem[e]
        b = pack[e, 8:11]
        half = 0.5 * cont[i, 6]
        block = half * (np.einsum("jk,ac->jakc", b @ b.T, eye) + np.einsum("ka,jc->jakc", b, b))
        if cont[i, 7] > 0.0:
            m = model.particle_mass[j]
            p = pack[e, 0][None, :] + pack[e, 4:7] @ b.T  # (P)_jk = w_k + b_k . o_j
            block = block + np.einsum("jk,ac->jakc", cont[i, 7] * (np.diag(m) - m[:, None] * p), eye)
        dof = (3 * j[:, None] + np.arange(3)).ravel()
        rows.append(np.repeat(dof, dof.size))
        cols.append(np.tile(dof, dof.size))
        vals.append(block.reshape(dof.size, dof.size).ravel())
    n = 3 * model.particle_count
    key = np.concatenate(rows) * n + np.concatenate(cols) if rows else np.zeros(0, dtype=np.int64)
    uniq, inv = np.unique(key, return_inverse=True)
    summed = np.zeros(uniq.size)
    np.add.at(summed, inv, np.concatenate(vals) if vals else np.zeros(0))
    return uniq // n, uniq % n, summed


@dataclass(eq=False)
class GlobalSystem:
    """The prefactored system of one model at one step length (module docstring), and the pass's
    scratch. ``arrays()`` is what the kernel takes."""

    dt: float
    """The step length [s] the factor is for."""
    order: np.ndarray
    """(F,) int64: the free particle at each block of three rows of the factor."""
    first: np.ndarray
    """(3F,) int64: the first column of each row's envelope."""
    ptr: np.ndarray
    """(3F + 1,) int64: row i of the factor at factor[ptr[i]:ptr[i + 1]]."""
    factor: np.ndarray
    """The envelope Cholesky factor of (M + dt^2 K0)_ff, in the bodies' rest frames (under
    ``linear_solve`` 'multigrid' none: empty, ``first`` every row's own column, ``ptr`` zeros)."""
    held: np.ndarray
    """(H,) int64: the particles held by their cores."""
    displacement: np.ndarray
    """(N, 3) scratch: U, the displacement the material gave each particle this step [m]."""
    gradient: np.ndarray
    """(N, 3) scratch: dE/dx [N]."""
    rhs: np.ndarray
    """(3F,) scratch: the solve's right-hand side, then its solution (rest frames)."""
    frames: np.ndarray
    """(B, 9) scratch: each body's core rotation (row-major; identity without a core)."""
    compliance: np.ndarray
    """(N, 6) each free particle's block of (M + dt^2 K0)^-1 in its body's rest frame (xx, xy, xz,
    yy, yz, zz) [1/kg]: how far the whole pad lets it move under a unit impulse; zeros for the
    held. From the factor (_diagonal_blocks), or under 'multigrid' probed through the levels
    (multigrid.probed_compliance: within 0.3 % on the diagonal)."""
    friction_w: np.ndarray
    """(N,) scratch: each particle's compliance across its contact's normal, which friction moves
    it by (friction_weights) [1/kg]."""
    body_rows: np.ndarray
    """(B + 1,) int64: body b's free particles are order[body_rows[b]:body_rows[b + 1]], and its
    rows of the factor 3 body_rows[b] .. 3 body_rows[b + 1] - 1, a diagonal block no other row
    reaches."""
    body_held: np.ndarray
    """(B + 1,) int64: body b's held particles are held[body_held[b]:body_held[b + 1]]."""
    linear_solve: str = "direct"
    """How a pass solves the system (SimConfig.global_linear_solve): 'direct', by the factor;
    'multigrid', by ``cycles`` V-cycles of ``multigrid`` (multigrid.py), each body's block on its own."""
    multigrid: Hierarchy = field(default_factory=Hierarchy.empty)
    """Each body's block of (M + dt^2 K0)_ff in the factor's row order: its smoothed-aggregation
    levels (matrix b: body b; no levels where the solve is direct or a body has no free rows)."""
    body_levels: np.ndarray = field(default_factory=lambda: np.zeros(1, dtype=np.int64))
    """(B + 1,) int64: body b's levels in ``multigrid`` (none: the factor solves its block)."""
    cycles: np.ndarray = field(default_factory=lambda: np.ones(1, dtype=np.int64))
    """(1,) int64: V-cycles a pass."""

    def arrays(self) -> tuple:
        return (self.order, self.first, self.ptr, self.factor, self.held, self.displacement, self.gradient, self.rhs,
                self.frames, self.compliance, self.friction_w, self.body_rows, self.body_held,
                *self.multigrid.arrays(), self.body_levels, self.cycles)  # fmt: skip
    # (the multigrid's arrays flat, entries 13 to 24: numba's parallel loops take a tuple of arrays
    # but not a tuple holding another)

    @property
    def envelope(self) -> int:
        """Entries of the factor (its memory is 8 bytes each; a solve reads each twice)."""
        return int(self.factor.shape[0])


def build_global_system(model: TissueModel, dt: float, linear_solve: str = "direct", cycles: int = 1) -> GlobalSystem:
    """Assemble K0, order the free particles (reverse Cuthill-McKee on the particles, a particle's
    three coordinates together) and factor (M + dt^2 K0)_ff for a step of ``dt`` [s]; under
    ``linear_solve`` 'multigrid' instead each body's block's smoothed-aggregation levels,
    ``cycles`` V-cycles a pass, and the compliances probed through them (no factor). Held
    particles: attached, of a body with a core (anchors.mark_fixed). Raises ValueError unless
    every group has the continuum energy, if the matrix is not positive definite, or if
    ``linear_solve`` or ``cycles`` is not one the solver takes."""
    if not dt > 0.0:
        raise ValueError(f"dt must be positive, got {dt!r}")
    if linear_solve not in LINEAR_SOLVES:
        raise ValueError(f"linear_solve must be one of {LINEAR_SOLVES}, got {linear_solve!r}")
    if not (isinstance(cycles, int) and 1 <= cycles <= 20):
        raise ValueError(f"cycles must be an integer from 1 to 20, got {cycles!r}")
    r, c, v = rest_hessian(model)
    n = model.particle_count
    held_mask = model.particle_attached & (model.body_core_shape[model.particle_body] >= 0)
    free = np.flatnonzero(~held_mask)
    held = np.flatnonzero(held_mask)
    pr_all, pc_all = r // 3, c // 3
    ff = ~held_mask[pr_all] & ~held_mask[pc_all]
    # order the free particles on their pattern
    local = np.full(n, -1, dtype=np.int64)
    local[free] = np.arange(free.size)
    pairs = np.unique(local[pr_all[ff]] * max(free.size, 1) + local[pc_all[ff]])
    pr, pc = pairs // max(free.size, 1), pairs % max(free.size, 1)
    keep = pr != pc
    pr, pc = pr[keep], pc[keep]
    ptr = np.zeros(free.size + 1, dtype=np.int64)
    np.add.at(ptr, pr + 1, 1)
    ptr = np.cumsum(ptr)
    degree = np.diff(ptr)
    perm = _rcm(ptr, pc.astype(np.int64), degree.astype(np.int64), free.size) if free.size else np.zeros(0, np.int64)
    # each body's rows together, the bodies in their order (RCM orders each connected component as a
    # whole, and a body's groups stay inside it): a body's block of the factor is then reached by
    # no other row, and the bodies' passes can run one after the other or side by side
    body_off = model.body_particle_offsets.astype(np.int64)
    if body_off.size < 2 or body_off[0] != 0 or body_off[-1] != n:
        raise ValueError("the global material solve needs every particle in a body (TissueModel.body_particle_offsets "
                         f"from 0 to {n}, got {body_off.tolist()})")  # fmt: skip
    order = free[perm]
    order = order[np.argsort(model.particle_body[order], kind="stable")]
    body_rows = np.searchsorted(model.particle_body[order], np.arange(model.body_count + 1)).astype(np.int64)
    body_held = np.searchsorted(held, body_off).astype(np.int64)
    slot = np.full(n, -1, dtype=np.int64)
    slot[order] = np.arange(order.size)
    # the envelope of (M + dt^2 K0)_ff over the free coordinates, lower triangle by rows
    fr = 3 * slot[pr_all[ff]] + r[ff] % 3
    fc = 3 * slot[pc_all[ff]] + c[ff] % 3
    fv = dt * dt * v[ff]
    low = fc <= fr
    fr, fc, fv = fr[low], fc[low], fv[low]
    nd = 3 * order.size
    first = np.arange(nd, dtype=np.int64)
    np.minimum.at(first, fr, fc)
    row_body = np.repeat(model.particle_body[order], 3)
    if row_body.size and (row_body[first] != row_body).any():
        raise ValueError("the global material solve needs every group inside one body (a group spans two)")
    compliance = np.zeros((n, 6))
    multigrid, body_levels = Hierarchy.empty(), np.zeros(model.body_count + 1, dtype=np.int64)
    if linear_solve == "multigrid":
        # no factor: each body's levels, and the compliances probed through them (linear in the
        # particles, where the factor's fill grows faster); the envelope left empty, every row its
        # own first column (the kernel solves no body's rows through it)
        multigrid, body_levels = _body_levels(model, order, body_rows, fr, fc, fv)
        for b in range(model.body_count):
            if body_levels[b + 1] > body_levels[b]:
                w = probed_compliance(multigrid, int(np.searchsorted(np.flatnonzero(np.diff(body_levels)), b)))
                rows = order[body_rows[b] : body_rows[b + 1]]
                compliance[rows] = w[:, [0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2]]
        first, eptr, factor = np.arange(nd, dtype=np.int64), np.zeros(nd + 1, dtype=np.int64), np.zeros(0)
    else:
        eptr = np.zeros(nd + 1, dtype=np.int64)
        eptr[1:] = np.cumsum(np.arange(nd) - first + 1)
        factor = np.zeros(int(eptr[-1]))
        np.add.at(factor, eptr[fr] + (fc - first[fr]), fv)
        factor[eptr[:-1] + (np.arange(nd) - first)] += np.repeat(model.particle_mass[order], 3)
        bad = _envelope_factor(first, eptr, factor)
        if bad >= 0:
            raise ValueError(f"the material's matrix is not positive definite at particle {int(order[bad // 3])}")
        _diagonal_blocks(first, eptr, factor, order.astype(np.int64), compliance)
    return GlobalSystem(dt=float(dt), order=order.astype(np.int64), first=first, ptr=eptr, factor=factor,
                        held=held.astype(np.int64), displacement=np.zeros((n, 3)), gradient=np.zeros((n, 3)),
                        rhs=np.zeros(nd), frames=np.zeros((model.body_count, 9)), compliance=compliance,
                        friction_w=np.zeros(n), body_rows=body_rows, body_held=body_held, linear_solve=linear_solve,
                        multigrid=multigrid, body_levels=body_levels, cycles=np.array([cycles], dtype=np.int64))  # fmt: skip


def _body_levels(model: TissueModel, order, body_rows, fr, fc, fv) -> tuple[Hierarchy, np.ndarray]:
    """Each body's block of (M + dt^2 K0)_ff (its rows of the factor, in the factor's order and the
    body's rest frame) as smoothed-aggregation levels, the rigid motions of its free particles' rest
    positions as their near-null space; and each body's first level (body_levels)."""
    from .multigrid import _scipy_sparse

    sp = _scipy_sparse()
    nd = 3 * order.size
    # the lower triangle (fr >= fc) with the masses on the diagonal, made whole
    mass = np.repeat(model.particle_mass[order], 3)
    lower = sp.coo_matrix((np.concatenate([fv, mass]), (np.concatenate([fr, np.arange(nd)]),
                                                          np.concatenate([fc, np.arange(nd)]))), shape=(nd, nd)).tocsr()  # fmt: skip
    whole = (lower + sp.triu(lower.T, k=1)).tocsr()
    levels, body_levels = [], [0]
    for b in range(model.body_count):
        r0, r1 = 3 * int(body_rows[b]), 3 * int(body_rows[b + 1])
        if r1 > r0:
            levels.append(build_levels(whole[r0:r1, r0:r1], rigid_modes(model.particle_rest_x[order[r0 // 3 : r1 // 3]])))
        body_levels.append(body_levels[-1] + (len(levels[-1][0]) if r1 > r0 else 0))
    return pack(levels), np.array(body_levels, dtype=np.int64)


_FACTORS: dict[tuple, GlobalSystem] = {}
"""The factors made in this process, by model content and dt (global_system)."""
_FACTOR_CACHE_SIZE = 8


LINEAR_SOLVES: tuple[str, ...] = ("direct", "multigrid")
"""How a pass solves the material's system (SimConfig.global_linear_solve)."""


def _model_key(model: TissueModel, dt: float) -> tuple:
    """(dt, a digest of every model array the factor reads)."""
    digest = hashlib.sha1()
    for a in (model.particle_rest_x, model.particle_mass, model.particle_attached, model.particle_body,
              model.body_core_shape, model.group_offsets, model.group_members, model.group_rest_offset,
              model.group_continuum):  # fmt: skip
        digest.update(np.ascontiguousarray(a).tobytes())
        digest.update(str(a.shape).encode())
    return (float(dt), digest.hexdigest())


def global_system(model: TissueModel, dt: float, linear_solve: str = "direct", cycles: int = 1) -> GlobalSystem:
    """build_global_system, its factor shared with every earlier call in this process on a model of
    the same content and the same dt (an env rebuilds its pads at every reset; the factor takes
    0.04 / 0.2 / 10 s at 24 / 450 / 3,000 particles), its scratch arrays its own."""
    key = (*_model_key(model, dt), linear_solve, cycles)
    base = _FACTORS.get(key)
    if base is None:
        base = build_global_system(model, dt, linear_solve, cycles)
        if len(_FACTORS) >= _FACTOR_CACHE_SIZE:
            _FACTORS.pop(next(iter(_FACTORS)))
        _FACTORS[key] = base
    n = model.particle_count
    mg = base.multigrid
    mg = replace(mg, x=np.zeros_like(mg.x), b=np.zeros_like(mg.b), r=np.zeros_like(mg.r))
    return replace(base, displacement=np.zeros((n, 3)), gradient=np.zeros((n, 3)), rhs=np.zeros_like(base.rhs),
                   frames=np.zeros_like(base.frames), friction_w=np.zeros(n), multigrid=mg)  # fmt: skip


@nb.njit(cache=True, error_model="numpy", fastmath={"contract", "reassoc"})
def _diagonal_blocks(first, ptr, val, order, out):
    """The 3x3 diagonal blocks of the factored matrix's inverse Z = H^-1, H = L L^T, by Takahashi's
    recurrences (Takahashi, Fagan & Chen 1973; Erisman & Tinney 1975) over the envelope: from
    L^T Z = L^-1, column by column from the last,

        Z_cj = -(sum_k Z_ck L_kj) / L_jj  (c in S_j),   Z_jj = (1 / L_jj - sum_k L_kj Z_kj) / L_jj,

    S_j the rows below j in column j of the envelope (first[k] <= j). Every Z_ck it reads lies in
    the envelope (first[max(c, k)] <= j < min(c, k)), so Z is kept there only: the cost is the
    sum of |S_j|^2, about the factorisation's, where three substitutions per particle cost
    particles x the envelope (70 s at 3,000 particles)."""
    nd = first.shape[0]
    count = np.zeros(nd + 1, dtype=np.int64)
    for i in range(nd):
        for j in range(first[i], i):
            count[j + 1] += 1
    cptr = np.cumsum(count)
    rows = np.empty(cptr[nd], dtype=np.int64)
    fill = cptr[:nd].copy()
    for i in range(nd):  # ascending rows within each column
        for j in range(first[i], i):
            rows[fill[j]] = i
            fill[j] += 1
    z = np.zeros(val.shape[0])
    lcol = np.empty(nd)
    rbase = np.empty(nd, dtype=np.uint64)  # where each row of S_j starts in z, less its first column
    for j in range(nd - 1, -1, -1):
        a, b = cptr[j], cptr[j + 1]
        ljj = val[ptr[j] + j - first[j]]
        for p in range(a, b):
            k = rows[p]
            lcol[p - a] = val[ptr[k] + j - first[k]]
        for p in range(a, b):
            k = rows[p]
            rbase[p - a] = np.uint64(ptr[k] - first[k])
        for q in range(a, b):
            c = rows[q]
            row_c = np.uint64(ptr[c] - first[c])
            uc = np.uint64(c)
            s = 0.0
            # rows ascend: k < c before q (Z_ck in row c), k >= c from q on (Z_kc in row k);
            # branch-free, unsigned loops that vectorise (envelope_solve)
            for p in range(np.uint64(a), np.uint64(q)):
                s += z[row_c + np.uint64(rows[p])] * lcol[p - np.uint64(a)]
            for p in range(np.uint64(q), np.uint64(b)):
                s += z[rbase[p - np.uint64(a)] + uc] * lcol[p - np.uint64(a)]
            z[row_c + np.uint64(j)] = -s / ljj
        s = 0.0
        for p in range(a, b):
            k = rows[p]
            s += lcol[p - a] * z[ptr[k] + j - first[k]]
        z[ptr[j] + j - first[j]] = (1.0 / ljj - s) / ljj
    for r in range(order.shape[0]):
        i0 = 3 * r
        r0, r1, r2 = ptr[i0] - first[i0], ptr[i0 + 1] - first[i0 + 1], ptr[i0 + 2] - first[i0 + 2]
        out[order[r], 0] = z[r0 + i0]
        out[order[r], 1] = z[r1 + i0]
        out[order[r], 2] = z[r2 + i0]
        out[order[r], 3] = z[r1 + i0 + 1]
        out[order[r], 4] = z[r2 + i0 + 1]
        out[order[r], 5] = z[r2 + i0 + 2]


@nb.njit(**KERNEL)
def material_gradient(rot_iters, g_off, g_mem, g_pack, g_cont, xp, group_q, mass, grad):
    """grad = dE/dx at ``xp`` [N] with each group's R the polar factor of its F (warm-started from
    group_q, which takes it): the local step. The arithmetic of a group's F, R and residual is
    continuum_groups'."""
    material_gradient_of(0, g_off.shape[0] - 1, rot_iters, g_off, g_mem, g_pack, g_cont, xp, group_q, mass, grad)


@nb.njit(**KERNEL)
def material_gradient_of(lo, hi, rot_iters, g_off, g_mem, g_pack, g_cont, xp, group_q, mass, grad):
    """material_gradient of one body, particles and groups lo .. hi - 1 (a group is centred on a
    particle, and a body's groups have its particles only as members): grad's rows lo .. hi - 1."""
    grad[lo:hi] = 0.0
    for g in range(lo, hi):
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
        qr = polar_rotation_unit_t((f00, f01, f02, f10, f11, f12, f20, f21, f22),
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
def _frame_of(b, frames, body_core_shape, shape_rigid, rig_q):
    """Body b's core rotation (its rest frame in the world) into frames[b], identity without a core."""
    cs = body_core_shape[b]
    r00 = r11 = r22 = 1.0
    r01 = r02 = r10 = r12 = r20 = r21 = 0.0
    if cs >= 0 and shape_rigid[cs] >= 0:
        k = shape_rigid[cs]
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = qmat((rig_q[k, 0], rig_q[k, 1], rig_q[k, 2], rig_q[k, 3]))
    frames[b, 0], frames[b, 1], frames[b, 2] = r00, r01, r02
    frames[b, 3], frames[b, 4], frames[b, 5] = r10, r11, r12
    frames[b, 6], frames[b, 7], frames[b, 8] = r20, r21, r22


@nb.njit(**KERNEL)
def deliver_held(gsys, b, dt, mass, p_body, body_core_shape, shape_rigid, xp, rig_x, rig_q, rig_inv_mass,
                 rig_inv_inertia, rig_axis, imp_lin, imp_ang, coupling_imp):  # fmt: skip
    """Each held particle of body b: its residual m U + dt^2 dE/dx (the gradient in gsys, current)
    onto its core as an impulse, its U taking it up."""
    held, u, grad, body_held = gsys[4], gsys[5], gsys[6], gsys[12]
    h = dt * dt
    for hh in range(body_held[b], body_held[b + 1]):
        j = held[hh]
        m = mass[j]
        rx = m * u[j, 0] + h * grad[j, 0]
        ry = m * u[j, 1] + h * grad[j, 1]
        rz = m * u[j, 2] + h * grad[j, 2]
        core = shape_rigid[body_core_shape[p_body[j]]]
        deliver_to_core(j, -rx, -ry, -rz, core, xp, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin,
                        imp_ang, coupling_imp, dt)  # fmt: skip
        u[j, 0] -= rx / m
        u[j, 1] -= ry / m
        u[j, 2] -= rz / m


@nb.njit(**KERNEL)
def global_pass(gsys, rot_iters, dt, g_turn, body_off, g_off, g_mem, g_pack, g_cont, attached, rest_q, rest_moment, xp,
                qp, group_q, moment, mass, p_body, body_core_shape, shape_rigid, rig_x, rig_q, rig_inv_mass,
                rig_inv_inertia, rig_axis, imp_lin, imp_ang, coupling_imp):  # fmt: skip
    """One pass of the material over every group (module docstring), body after body
    (global_body_pass)."""
    for b in range(body_off.shape[0] - 1):
        global_body_pass(b, gsys, rot_iters, dt, g_turn, body_off, g_off, g_mem, g_pack, g_cont, attached, rest_q,
                         rest_moment, xp, qp, group_q, moment, mass, p_body, body_core_shape, shape_rigid, rig_x, rig_q,
                         rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin, imp_ang, coupling_imp)  # fmt: skip


@nb.njit(**KERNEL)
def global_body_pass(b, gsys, rot_iters, dt, g_turn, body_off, g_off, g_mem, g_pack, g_cont, attached, rest_q,
                     rest_moment, xp, qp, group_q, moment, mass, p_body, body_core_shape, shape_rigid, rig_x, rig_q,
                     rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin, imp_ang, coupling_imp):  # fmt: skip
    """One pass of the material over body b's groups: the local step (each group's R) and the
    gradient, the held particles' residuals onto the core, the quasi-Newton step of the free
    particles through the rest Hessian in the body's frame (its own block of the factor), and each
    free group centre's turn toward quat(R) q_bar (as the sweep turns them: sweep_body). It reads
    and writes body b's particles, groups, rows and core only, so the bodies' passes give the same
    result in any order or side by side (the solver's threads: where no two bodies share a core)."""
    order, first, ptr, factor, u, grad, rhs, frames, body_rows = (gsys[0], gsys[1], gsys[2], gsys[3], gsys[5], gsys[6],
                                                                   gsys[7], gsys[8], gsys[11])  # fmt: skip
    body_levels, cycles = gsys[25], gsys[26]
    lo, hi = body_off[b], body_off[b + 1]
    material_gradient_of(lo, hi, max(rot_iters, POLAR_ITERATIONS), g_off, g_mem, g_pack, g_cont, xp, group_q, mass,
                         grad)  # fmt: skip
    deliver_held(gsys, b, dt, mass, p_body, body_core_shape, shape_rigid, xp, rig_x, rig_q, rig_inv_mass,
                 rig_inv_inertia, rig_axis, imp_lin, imp_ang, coupling_imp)  # fmt: skip
    _frame_of(b, frames, body_core_shape, shape_rigid, rig_q)
    f = frames[b]
    h = dt * dt
    r0, r1 = body_rows[b], body_rows[b + 1]
    for r in range(r0, r1):
        j = order[r]
        m = mass[j]
        ex = -(m * u[j, 0] + h * grad[j, 0])
        ey = -(m * u[j, 1] + h * grad[j, 1])
        ez = -(m * u[j, 2] + h * grad[j, 2])
        rhs[3 * r] = f[0] * ex + f[3] * ey + f[6] * ez  # R^T e: into the body's rest frame
        rhs[3 * r + 1] = f[1] * ex + f[4] * ey + f[7] * ez
        rhs[3 * r + 2] = f[2] * ex + f[5] * ey + f[8] * ez
    if body_levels[b + 1] > body_levels[b]:  # V-cycles on the body's levels (multigrid.py)
        v_cycle(body_levels[b], body_levels[b + 1], gsys[13], gsys[14], gsys[15], gsys[16], gsys[17], gsys[18],
                gsys[19], gsys[20], gsys[21], gsys[22], gsys[23], gsys[24], rhs, 3 * r0, cycles[0])  # fmt: skip
    else:
        envelope_solve_rows(first, ptr, factor, rhs, 3 * r0, 3 * r1)
    for r in range(r0, r1):
        j = order[r]
        a, bb, c = rhs[3 * r], rhs[3 * r + 1], rhs[3 * r + 2]
        dx = f[0] * a + f[1] * bb + f[2] * c
        dy = f[3] * a + f[4] * bb + f[5] * c
        dz = f[6] * a + f[7] * bb + f[8] * c
        xp[j, 0] += dx
        xp[j, 1] += dy
        xp[j, 2] += dz
        u[j, 0] += dx
        u[j, 1] += dy
        u[j, 2] += dz
    for i in range(lo, hi):
        if not attached[i]:
            qr = (group_q[i, 0], group_q[i, 1], group_q[i, 2], group_q[i, 3])
            _turn_centre(i, qr, g_turn[i], rest_q, qp, rest_moment, moment)


@nb.njit(**KERNEL)
def global_finish(gsys, rot_iters, dt, body_off, g_off, g_mem, g_pack, g_cont, xp, group_q, mass, p_body,
                  body_core_shape, shape_rigid, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin, imp_ang,
                  coupling_imp):  # fmt: skip
    """After the step's last pass, body after body (global_body_finish)."""
    for b in range(body_off.shape[0] - 1):
        global_body_finish(b, gsys, rot_iters, dt, body_off, g_off, g_mem, g_pack, g_cont, xp, group_q, mass, p_body,
                           body_core_shape, shape_rigid, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis,
                           imp_lin, imp_ang, coupling_imp)  # fmt: skip


@nb.njit(**KERNEL)
def global_body_finish(b, gsys, rot_iters, dt, body_off, g_off, g_mem, g_pack, g_cont, xp, group_q, mass, p_body,
                       body_core_shape, shape_rigid, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin,
                       imp_ang, coupling_imp):  # fmt: skip
    """After the step's last pass: every particle of body b hands its residual m U + dt^2 dE/dx at
    the final positions to the body's core, at its spot. For a held particle that is the material's
    force where the step ends; for a free one it is what the passes left unsolved (zero once
    converged). Handing both over keeps momentum and angular momentum exact every step: the
    residuals sum to sum_j m_j U_j (the material's forces sum to zero and have no torque), which is
    what the material moved the tissue by. Left on the free particles it was a push on the core
    from nothing (1.4 % of a sagging pad's weight sideways at one pass a step)."""
    lo, hi = body_off[b], body_off[b + 1]
    material_gradient_of(lo, hi, max(rot_iters, POLAR_ITERATIONS), g_off, g_mem, g_pack, g_cont, xp, group_q, mass,
                         gsys[6])  # fmt: skip
    deliver_held(gsys, b, dt, mass, p_body, body_core_shape, shape_rigid, xp, rig_x, rig_q, rig_inv_mass,
                 rig_inv_inertia, rig_axis, imp_lin, imp_ang, coupling_imp)  # fmt: skip
    order, u, grad, body_rows = gsys[0], gsys[5], gsys[6], gsys[11]
    cs = body_core_shape[b]
    if cs < 0 or shape_rigid[cs] < 0:
        return
    core = shape_rigid[cs]
    h = dt * dt
    for r in range(body_rows[b], body_rows[b + 1]):
        j = order[r]
        m = mass[j]
        rx = m * u[j, 0] + h * grad[j, 0]
        ry = m * u[j, 1] + h * grad[j, 1]
        rz = m * u[j, 2] + h * grad[j, 2]
        deliver_to_core(j, -rx, -ry, -rz, core, xp, rig_x, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin,
                        imp_ang, coupling_imp, dt)  # fmt: skip


@nb.njit(**KERNEL)
def project_contacts(gsys, count, c_particle, c_shape, c_inner, c_lambda, c_normal, c_rn, xp, qp, radii, inv_mass,
                     p_body, shape_kind, shape_params, shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q,
                     rig_inv_mass, rig_inv_inertia, rig_axis, rig_move, imp_lin, imp_ang, dt, shape_pose, more_kinds):  # fmt: skip
    """contacts.project_shape_contacts with each free particle's compliance in its whole pad,
    w = n . W_jj n (W the factored matrix's inverse, GlobalSystem.compliance), instead of its own
    1 / m: the multiplier a contact needs once the material has answered, so that the passes do
    not have to find it at s / (1 + s) each. The multiplier may fall back (never below zero): an
    estimate from one particle's compliance overshoots where neighbouring contacts push together.
    The particle moves by w dl n, and its material displacement U by (w - 1 / m) dl n, so that the
    material's next pass reads the contact's impulse dl n, not the move, as the load."""
    u, frames, comp = gsys[5], gsys[8], gsys[9]
    for c in range(count):
        i, r, p, dist, n, rn = contact_reach(c, c_particle, c_shape, c_inner, xp, qp, radii, shape_kind, shape_params,
                                             shape_rigid, shape_local_x, shape_local_q, rig_x, rig_q, rig_move,
                                             shape_pose, more_kinds)  # fmt: skip
        pen = rn - dist
        if pen <= 0.0 and c_lambda[c] <= 0.0:
            continue
        c_normal[c, 0] = n[0]
        c_normal[c, 1] = n[1]
        c_normal[c, 2] = n[2]
        c_rn[c] = rn
        wp = inv_mass[i]
        if comp[i, 0] > 0.0:
            f = frames[p_body[i]]
            a0 = f[0] * n[0] + f[3] * n[1] + f[6] * n[2]  # n in the body's rest frame
            a1 = f[1] * n[0] + f[4] * n[1] + f[7] * n[2]
            a2 = f[2] * n[0] + f[5] * n[1] + f[8] * n[2]
            wp = (comp[i, 0] * a0 * a0 + comp[i, 3] * a1 * a1 + comp[i, 5] * a2 * a2
                  + 2.0 * (comp[i, 1] * a0 * a1 + comp[i, 2] * a0 * a2 + comp[i, 4] * a1 * a2))  # fmt: skip
        wb = 0.0
        rx = ry = rz = 0.0
        if r >= 0:
            rx = p[0] - dist * n[0] - rig_x[r, 0]
            ry = p[1] - dist * n[1] - rig_x[r, 1]
            rz = p[2] - dist * n[2] - rig_x[r, 2]
            if rig_move[r]:
                wb = generalized_inv_mass(r, rig_q, rig_inv_mass, rig_inv_inertia, rig_axis, rx, ry, rz, n[0], n[1], n[2])
        dl = pen / (wp + wb)
        if c_lambda[c] + dl < 0.0:
            dl = -c_lambda[c]
        c_lambda[c] += dl
        xp[i, 0] += wp * dl * n[0]
        xp[i, 1] += wp * dl * n[1]
        xp[i, 2] += wp * dl * n[2]
        if comp[i, 0] > 0.0:
            k = (wp - inv_mass[i]) * dl
            u[i, 0] += k * n[0]
            u[i, 1] += k * n[1]
            u[i, 2] += k * n[2]
        if r >= 0:
            rigid_apply(r, rx, ry, rz, -dl * n[0], -dl * n[1], -dl * n[2], rig_move[r], dt, rig_x, rig_q,
                        rig_inv_mass, rig_inv_inertia, rig_axis, imp_lin, imp_ang)  # fmt: skip


@nb.njit(**KERNEL)
def friction_weights(gsys, sign, count, c_particle, c_patch, c_lambda, c_normal, c_friction, inv_mass, p_body):
    """Before friction (``sign`` -1): each touching free particle's compliance across its contact's
    normal, w = (tr W_jj - n . W_jj n) / 2, into gsys's friction_w (1 / m elsewhere), which
    friction then moves it by instead of 1 / m (as project_contacts does along the normal); and U
    less (w - 1 / m) times each contact's friction so far. After friction (``sign`` +1): U plus
    (w - 1 / m) times its friction now. Together U changes by (w - 1 / m) times friction's change,
    so the material's next pass reads the friction's impulse, not its move, as the load."""
    u, frames, comp, fw = gsys[5], gsys[8], gsys[9], gsys[10]
    if sign < 0.0:
        for i in range(fw.shape[0]):
            fw[i] = inv_mass[i]
        for c in range(count):
            i = c_particle[c]
            if c_patch[c] < 0 or c_lambda[c] <= 0.0 or comp[i, 0] <= 0.0:
                continue
            f = frames[p_body[i]]
            n0, n1, n2 = c_normal[c, 0], c_normal[c, 1], c_normal[c, 2]
            a0 = f[0] * n0 + f[3] * n1 + f[6] * n2
            a1 = f[1] * n0 + f[4] * n1 + f[7] * n2
            a2 = f[2] * n0 + f[5] * n1 + f[8] * n2
            wn = (comp[i, 0] * a0 * a0 + comp[i, 3] * a1 * a1 + comp[i, 5] * a2 * a2
                  + 2.0 * (comp[i, 1] * a0 * a1 + comp[i, 2] * a0 * a2 + comp[i, 4] * a1 * a2))  # fmt: skip
            fw[i] = 0.5 * (comp[i, 0] + comp[i, 3] + comp[i, 5] - wn)
    for c in range(count):
        i = c_particle[c]
        k = sign * (fw[i] - inv_mass[i])
        if k != 0.0:
            u[i, 0] += k * c_friction[c, 0]
            u[i, 1] += k * c_friction[c, 1]
            u[i, 2] += k * c_friction[c, 2]
