"""How fast three ways of solving the tissue material's implicit step converge, pass by pass, on the
v4 pads: what a solve across the groups would have to beat.

    PYTHONPATH=. python benchmarks/implicit_step.py [--densities 4000,16000,64000]
        [--steps 480,240,120] [--passes 8]

One implicit (backward Euler) step of one pad on its held core, no contacts: the free particles
predicted at x* = x_rest + v dt with v 0.1 m/s into the core and 0.1 m/s down the face (a press and
a shear), the attached ones held. Its equations, for the free particles,

    r(x) = M (x - x*) + dt^2 dE/dx = 0,

E the continuum group energy with hourglass control (compliant.continuum_energy, R the polar
factor of each group's F), are solved from x = x* by

- ``sweep``: the package's solve, a Newton step per group, Gauss-Seidel over the overlapping
  groups (compliant.continuum_groups over all groups, one call a pass);
- ``pd``: projective dynamics' global step (Bouaziz et al. 2014): each group's R from its F, then
  (M + dt^2 K) dx = -r with K (x) I_3 the energy's Hessian with every R held, one matrix for x, y
  and z, constant over a run (prefactorable);
- ``k0``: the same with the energy's Hessian at rest instead, the rotations' derivative included
  (the small-strain stiffness at Poisson's ratio 0: (k / 2) [(b_j . b_k) I + b_k b_j^T] per group
  pair, plus the hourglass term), 3N x 3N and also constant: a quasi-Newton step.

Printed: max |r| after each pass over its value at x*, per density and dt. Dense numpy solves: a
measurement of convergence per pass, not of speed. One process, one thread, no assertions.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from softgrasp_env.presets import v4_tissue
from softgrasp_env.tissue.builder import CoreShape, build_combined_body
from softgrasp_env.tissue.compliant import continuum_energy, continuum_groups
from softgrasp_env.tissue.shape_matching import group_frames, group_pack

FACE = (0.008, 0.02, 0.03)
"""The scene's finger core (half-extents [m]); the pad on its +x face."""
PRESS = np.array([-0.1, 0.0, -0.1])
"""The free particles' velocity at the step's start [m/s]: into the core and down the face."""


def pad(density: float):
    """The v4 pad at ``density`` [1/m^2] (its layers as thick as the spacing)."""
    return build_combined_body(CoreShape("box", half_extents=FACE), v4_tissue(particle_density=density), faces=("+x",))


def _groups(model):
    pack = group_pack(model)
    off = model.group_offsets.astype(np.int64)
    for i in range(model.particle_count):
        e = slice(off[i], off[i + 1])
        yield i, model.group_members[e].astype(np.int64), pack[e]


def gradient(model, x: np.ndarray) -> np.ndarray:
    """dE/dx (N, 3) [N] at x, each group's R the polar factor of its F."""
    grad = np.zeros_like(x)
    for i, mem, pk in _groups(model):
        row = model.group_continuum[i]
        ainv = np.array([[row[0], row[1], row[2]], [row[1], row[3], row[4]], [row[2], row[4], row[5]]])
        _, g, _ = continuum_energy(x[mem], pk[:, 1:4], ainv, row[6], mass=model.particle_mass[mem], beta=row[7])
        np.add.at(grad, mem, g)
    return grad


def _hourglass(model, mem, pk, beta):
    m = model.particle_mass[mem]
    p = pk[:, 0][None, :] + pk[:, 4:7] @ pk[:, 8:11].T  # the affine fit: (P)_jk = w_k + b_k . o_j
    return beta * (np.diag(m) - m[:, None] * p)


def stiffness_pd(model) -> np.ndarray:
    """K (N x N): the Hessian of E with every R held, per coordinate."""
    n = model.particle_count
    k = np.zeros((n, n))
    for i, mem, pk in _groups(model):
        b = pk[:, 8:11]
        block = model.group_continuum[i, 6] * (b @ b.T)
        if model.group_continuum[i, 7] > 0.0:
            block = block + _hourglass(model, mem, pk, model.group_continuum[i, 7])
        k[np.ix_(mem, mem)] += block
    return k


def stiffness_rest(model) -> np.ndarray:
    """K0 (3N x 3N): the Hessian of E at rest, the rotations' derivative included."""
    n = model.particle_count
    k = np.zeros((3 * n, 3 * n))
    eye = np.eye(3)
    for i, mem, pk in _groups(model):
        b = pk[:, 8:11]
        half = 0.5 * model.group_continuum[i, 6]
        # (k / 2) [(b_j . b_k) I + b_k b_j^T]: block (j, k), rows a, columns c -> [j, a, k, c]
        block = half * (np.einsum("jk,ac->jakc", b @ b.T, eye) + np.einsum("ka,jc->jakc", b, b))
        if model.group_continuum[i, 7] > 0.0:
            block = block + np.einsum("jk,ac->jakc", _hourglass(model, mem, pk, model.group_continuum[i, 7]), eye)
        idx = (3 * mem[:, None] + np.arange(3)).ravel()
        k[np.ix_(idx, idx)] += block.reshape(3 * mem.size, 3 * mem.size)
    return k


def residual(model, free, x, x_star, dt) -> np.ndarray:
    """r (F, 3) of the free particles [N s^2 = kg m]."""
    return model.particle_mass[free, None] * (x[free] - x_star[free]) + dt * dt * gradient(model, x)[free]


def run(model, dt: float, passes: int) -> dict[str, list[float]]:
    """Each solve's max |r| after each pass, over its value at x*."""
    free = np.flatnonzero(~model.particle_attached)
    x_star = model.particle_rest_x.copy()
    x_star[free] += PRESS * dt
    r0 = float(np.abs(residual(model, free, x_star, x_star, dt)).max())
    out: dict[str, list[float]] = {}
    m = model.particle_mass[free]
    kpd = stiffness_pd(model)[np.ix_(free, free)]
    idx = (3 * free[:, None] + np.arange(3)).ravel()
    k0 = stiffness_rest(model)[np.ix_(idx, idx)]
    solves = {
        "pd": lambda r: np.linalg.solve(np.diag(m) + dt * dt * kpd, r),
        "k0": lambda r: np.linalg.solve(np.diag(np.repeat(m, 3)) + dt * dt * k0, r.ravel()).reshape(-1, 3),
    }
    for name, solve in solves.items():
        x = x_star.copy()
        trace = []
        for _ in range(passes):
            x[free] -= solve(residual(model, free, x, x_star, dt))
            trace.append(float(np.abs(residual(model, free, x, x_star, dt)).max()) / r0)
        out[name] = trace
    # the sweep: continuum_groups over every group, the core (slot 0) held still
    n = model.particle_count
    pack = group_pack(model)
    frame = np.zeros((n, 10))
    x = x_star.copy()
    group_frames(model.group_offsets, model.group_members, model.particle_mass, x.copy(), frame)
    group_q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    g_u = np.zeros((model.group_members.shape[0], 3))
    g_raw = np.zeros_like(g_u)
    fixed = model.particle_attached.copy()
    rig = [np.zeros((1, 3)), np.array([[0.0, 0.0, 0.0, 1.0]]), np.zeros(1), np.zeros((1, 3)), np.zeros((1, 3)),
           np.zeros(1, dtype=np.bool_), np.zeros((1, 3)), np.zeros((1, 3)), np.zeros((1, 3))]  # fmt: skip
    trace = []
    xs = x_star.copy()
    for _ in range(passes):
        continuum_groups(0, n, 0, 0, 0, 0.0, 10, model.group_continuum, model.group_offsets, model.group_members, pack,
                         frame, xs, x, group_q, fixed, g_u, g_raw, model.particle_mass, *rig, dt)  # fmt: skip
        trace.append(float(np.abs(residual(model, free, x, x_star, dt)).max()) / r0)
    out["sweep"] = trace
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--densities", default="4000,16000,64000", help="particles per m^2 of face, comma-separated")
    ap.add_argument("--steps", default="480,240,120", help="steps per second (dt = 1 / this), comma-separated")
    ap.add_argument("--passes", type=int, default=8)
    args = ap.parse_args(argv)
    if args.passes < 1:
        ap.error(f"--passes must be at least 1, got {args.passes}")
    print("max |r| after each pass / at x* (one implicit step of one v4 pad on its held core, no contacts)")
    for d in (float(s) for s in args.densities.split(",")):
        model = pad(d)
        for rate in (float(s) for s in args.steps.split(",")):
            res = run(model, 1.0 / rate, args.passes)
            for name in ("sweep", "pd", "k0"):
                print(f"{d:8.0f}/m^2 {model.particle_count:4d} particles dt 1/{rate:.0f} s {name:5s} "
                      + " ".join(f"{v:.1e}" for v in res[name]), flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
