"""What one pass of the global material solve costs as the pads are refined, by the envelope
Cholesky factor it runs on (softgrasp_env/tissue/global_step.py) and by a smoothed-aggregation
V-cycle (softgrasp_env/tissue/multigrid.py, not yet wired into the solver), on one pad of the
v4 tissue (its particles all free) at the world step the coupling rule gives the env at each
density.

    PYTHONPATH=. python benchmarks/solve_scaling.py [--densities 16000,64000,256000,1024000]
        [--envelope-up-to 256000] [--repeats 5]

Per density: the pad's particles, s = kappa dt^2 (the material's stiffness per unit mass over a
step), the matrix's entries per row, the factor's entries (reverse Cuthill-McKee's envelope, as
the solver stores it) and a minimum-degree order's fill (SuperLU's MMD on A^T + A: what a sparse
factor would hold), the envelope solve's time, the V-cycle's levels, its time and its A-norm
error after one and two cycles (a random right-hand side, against a sparse direct solve), and
each time's exponent in the particle count (a least-squares fit of the logs). Best of
``--repeats``. The envelope is built only up to ``--envelope-up-to`` (its factorisation grows
as the fill does: minutes past ~5,000 particles a pad).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from softgrasp_env.presets import v4_tissue
from softgrasp_env.tissue.builder import CoreShape, build_combined_body
from softgrasp_env.tissue.global_step import build_global_system, envelope_solve, rest_hessian
from softgrasp_env.tissue.multigrid import build_hierarchy, rigid_modes, solve

FACE = (0.008, 0.02, 0.03)
"""The pad's core face half extents [m] (SoftGrasp's finger core)."""

DT = {4_000.0: 1 / 480, 16_000.0: 1 / 480, 64_000.0: 1 / 480, 256_000.0: 1 / 720, 1_024_000.0: 1 / 720}
"""The world step the env runs at each density under the global solve (the coupling rule's:
2 world steps per 1/240 s up to 64,000 per m^2, 3 at 256,000; benchmarks/scaling.py)."""


def best(fn, repeats: int) -> float:
    out = np.inf
    for _ in range(repeats):
        tic = time.perf_counter()
        fn()
        out = min(out, time.perf_counter() - tic)
    return out


def measure(density: float, repeats: int, envelope: bool) -> dict:
    model = build_combined_body(CoreShape("box", half_extents=FACE), v4_tissue(particle_density=density), faces=("+x",))
    dt = DT.get(density, 1 / 720)
    n = model.particle_count
    r, c, v = rest_hessian(model)
    a = (sp.diags(np.repeat(model.particle_mass, 3)) + dt * dt * sp.csr_matrix((v, (r, c)), shape=(3 * n, 3 * n))).tocsr()
    rng = np.random.default_rng(0)
    rhs = rng.normal(size=3 * n)
    exact = sla.spsolve(a.tocsc(), rhs)

    def err(x: np.ndarray) -> float:
        e = x - exact
        return float(np.sqrt(e @ (a @ e) / (exact @ (a @ exact))))

    mmd = sla.splu(a.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    out = {"particles": n, "s": float(model.group_kappa.max()) * dt * dt, "per_row": a.nnz / a.shape[0],
           "mmd_fill": int(mmd.L.nnz), "envelope": np.nan, "envelope_us": np.nan}  # fmt: skip
    if envelope:
        system = build_global_system(model, dt)
        b = rhs.copy()
        envelope_solve(system.first, system.ptr, system.factor, b)
        out["envelope"] = system.envelope
        out["envelope_us"] = best(lambda: envelope_solve(system.first, system.ptr, system.factor, b), repeats) * 1e6
    h = build_hierarchy(a, rigid_modes(model.particle_rest_x))
    solve(h, rhs)
    out["levels"] = h.sizes()
    out["complexity"] = h.operator_complexity
    out["cycle_us"] = best(lambda: solve(h, rhs), repeats) * 1e6
    out["err1"], out["err2"] = err(solve(h, rhs, 1)), err(solve(h, rhs, 2))
    return out


def exponent(n: list[float], t: list[float]) -> float:
    keep = [i for i, y in enumerate(t) if np.isfinite(y)]
    if len(keep) < 2:
        return np.nan
    return float(np.polyfit(np.log([n[i] for i in keep]), np.log([t[i] for i in keep]), 1)[0])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--densities", default="16000,64000,256000,1024000")
    parser.add_argument("--envelope-up-to", type=float, default=256_000.0)
    parser.add_argument("--repeats", type=int, default=5)
    ns = parser.parse_args(argv)
    densities = [float(d) for d in ns.densities.split(",")]
    rows = []
    print(f"one v4 pad, all particles free; best of {ns.repeats}")
    print(f"{'density':>9} {'particles':>9} {'s':>5} {'per row':>7} {'envelope':>10} {'MMD fill':>10} {'env. us':>9} "
          f"{'levels':>22} {'cmplx':>5} {'V us':>8} {'err 1':>8} {'err 2':>8}")  # fmt: skip
    for d in densities:
        m = measure(d, ns.repeats, d <= ns.envelope_up_to)
        rows.append(m)
        print(f"{d:9.0f} {m['particles']:9d} {m['s']:5.1f} {m['per_row']:7.0f} {m['envelope']:10.0f} {m['mmd_fill']:10d} "
              f"{m['envelope_us']:9.0f} {str(m['levels']):>22} {m['complexity']:5.2f} {m['cycle_us']:8.0f} "
              f"{m['err1']:8.1e} {m['err2']:8.1e}", flush=True)  # fmt: skip
    n = [float(m["particles"]) for m in rows]
    print(f"exponents in the particles: envelope entries {exponent(n, [m['envelope'] for m in rows]):.2f}, "
          f"minimum-degree fill {exponent(n, [m['mmd_fill'] for m in rows]):.2f}, "
          f"envelope solve {exponent(n, [m['envelope_us'] for m in rows]):.2f}, "
          f"V-cycle {exponent(n, [m['cycle_us'] for m in rows]):.2f}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
