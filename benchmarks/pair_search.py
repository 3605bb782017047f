"""Cost of the tissue's particle-pair search between the two fingers (tissue/contacts.py
collect_pairs) with the fingers closed face to face, against the exhaustive search over the
overlap box it replaced (kept here as the baseline), per particle density.

    PYTHONPATH=. python benchmarks/pair_search.py [--densities 4000,16000,64000,256000] [--layers auto]

The pads are SoftGraspEasy-v4's, built at each density; the second finger's particles are moved
along the line between the fingers until its pad's face overlaps the first's by 0.5 mm (closed on
nothing). Both searches see the same positions and must return the same pairs in the same order
(checked); printed: particles, pairs, us per call for each (best of repeats) and their ratio, and
the exponent of the new search's cost in the particle count. One thread. A measurement: timing
on a shared machine is noisy, hence best-of.
"""

from __future__ import annotations

import argparse
import math
import time

import numba as nb
import numpy as np

from softgrasp_env.tissue.contacts import collect_pairs, pair_scratch_sizes


@nb.njit(cache=True, error_model="numpy", fastmath={"contract"})
def exhaustive_pairs(xp, x0, radii, body_off, margin, pair_i, pair_j):
    """The search before the grid: every particle of one body in the bodies' overlap box against
    every particle of the other (the same rows in the same order)."""
    nb_ = body_off.shape[0] - 1
    cap = pair_i.shape[0]
    count = 0
    lo = np.full((nb_, 3), np.inf)
    hi = np.full((nb_, 3), -np.inf)
    reach = np.zeros(nb_)
    for b in range(nb_):
        for i in range(body_off[b], body_off[b + 1]):
            rmax = max(radii[i, 0], max(radii[i, 1], radii[i, 2]))
            mv = math.sqrt((xp[i, 0] - x0[i, 0]) ** 2 + (xp[i, 1] - x0[i, 1]) ** 2 + (xp[i, 2] - x0[i, 2]) ** 2)
            reach[b] = max(reach[b], rmax + mv)
            for a in range(3):
                lo[b, a] = min(lo[b, a], xp[i, a])
                hi[b, a] = max(hi[b, a], xp[i, a])
    for b1 in range(nb_):
        for b2 in range(b1 + 1, nb_):
            pad = reach[b1] + reach[b2] + margin
            olo = np.maximum(lo[b1], lo[b2]) - pad
            ohi = np.minimum(hi[b1], hi[b2]) + pad
            if (olo > ohi).any():
                continue
            for i in range(body_off[b1], body_off[b1 + 1]):
                if not (olo[0] <= xp[i, 0] <= ohi[0] and olo[1] <= xp[i, 1] <= ohi[1] and olo[2] <= xp[i, 2] <= ohi[2]):
                    continue
                ri = max(radii[i, 0], max(radii[i, 1], radii[i, 2]))
                mi = math.sqrt((xp[i, 0] - x0[i, 0]) ** 2 + (xp[i, 1] - x0[i, 1]) ** 2 + (xp[i, 2] - x0[i, 2]) ** 2)
                for j in range(body_off[b2], body_off[b2 + 1]):
                    rj = max(radii[j, 0], max(radii[j, 1], radii[j, 2]))
                    mj = math.sqrt((xp[j, 0] - x0[j, 0]) ** 2 + (xp[j, 1] - x0[j, 1]) ** 2 + (xp[j, 2] - x0[j, 2]) ** 2)
                    d2 = (xp[i, 0] - xp[j, 0]) ** 2 + (xp[i, 1] - xp[j, 1]) ** 2 + (xp[i, 2] - xp[j, 2]) ** 2
                    lim = ri + mi + rj + mj + margin
                    if d2 < lim * lim:
                        if count < cap:
                            pair_i[count] = i
                            pair_j[count] = j
                        count += 1
    return count


def closed_pads(density: float, layers: int):
    """The two pads' particle positions with the fingers closed face to face, their radii and body
    offsets, and the solver's contact margin [m]."""
    import gymnasium as gym

    import softgrasp_env  # noqa: F401  (registers the ids)

    env = gym.make("SoftGraspEasy-v4", particle_density=density, layers=layers)
    try:
        env.reset(seed=0)
        world = env.unwrapped.scene.world
        model = world.model
        x = world.state.particle_x.copy()
        off = model.body_particle_offsets.astype(np.int32)
        margin = world.sim.contact_margin
    finally:
        env.close()
    a, b = slice(off[0], off[1]), slice(off[1], off[2])
    axis = x[b].mean(axis=0) - x[a].mean(axis=0)
    axis /= np.linalg.norm(axis)
    gap = (x[b] @ axis).min() - (x[a] @ axis).max()
    x[b] -= (gap + 5e-4) * axis
    return x, model.particle_radii.copy(), off, margin


def time_call(fn, args, repeats: int) -> float:
    fn(*args)
    best = np.inf
    for _ in range(repeats):
        n = 0
        tic = time.perf_counter()
        while True:
            fn(*args)
            n += 1
            if time.perf_counter() - tic > 0.2:
                break
        best = min(best, (time.perf_counter() - tic) / n)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--densities", default="4000,16000,64000,256000")
    parser.add_argument("--layers", default="auto", help="one count, or 'auto' (1 / 1 / 2 / 4)")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    nb.set_num_threads(1)
    densities = [float(d) for d in args.densities.split(",")]
    auto = {4000.0: 1, 16000.0: 1, 64000.0: 2, 256000.0: 4}
    rows = []
    print(f"{'density':>9} {'layers':>6} {'particles':>9} {'pairs':>6} {'grid us':>9} {'exhaustive us':>13} {'ratio':>6}")
    for d in densities:
        layers = auto.get(d, 1) if args.layers == "auto" else int(args.layers)
        x, radii, off, margin = closed_pads(d, layers)
        x0 = x.copy()
        cap = 64 * len(x)
        pi, pj = np.empty(cap, np.int32), np.empty(cap, np.int32)
        qi, qj = np.empty(cap, np.int32), np.empty(cap, np.int32)
        ni, nf = pair_scratch_sizes(len(x), len(off) - 1)
        grid, boxes = np.empty(ni, np.int32), np.empty(nf)
        n = collect_pairs(x, x0, radii, off, margin, pi, pj, grid, boxes)
        m = exhaustive_pairs(x, x0, radii, off, margin, qi, qj)
        if n != m or not (np.array_equal(pi[:n], qi[:n]) and np.array_equal(pj[:n], qj[:n])):
            raise SystemExit(f"the two searches disagree at {d:.0f} per m^2: {n} against {m} pairs")
        t_grid = time_call(collect_pairs, (x, x0, radii, off, margin, pi, pj, grid, boxes), args.repeats)
        t_all = time_call(exhaustive_pairs, (x, x0, radii, off, margin, qi, qj), args.repeats)
        rows.append((len(x), t_grid))
        print(f"{d:9.0f} {layers:6d} {len(x):9d} {n:6d} {t_grid * 1e6:9.1f} {t_all * 1e6:13.1f} {t_all / t_grid:6.1f}")
    if len(rows) > 1:
        p = np.log([r[0] for r in rows])
        t = np.log([r[1] for r in rows])
        print(f"grid search cost ~ particles^{np.polyfit(p, t, 1)[0]:.2f} (fit over the densities)")


if __name__ == "__main__":
    main()
