"""The tissue's particle-pair search between bodies (tissue/contacts.py collect_pairs) against the
all-pairs definition: the same pairs in the same order (the order the Gauss-Seidel pass projects
them in), whatever the bodies' layout."""

from __future__ import annotations

import numpy as np
import pytest

from softgrasp_env.tissue.contacts import collect_pairs as _collect_pairs
from softgrasp_env.tissue.contacts import pair_scratch_sizes


def collect_pairs(xp, x0, radii, off, margin, pi, pj):
    """collect_pairs with its scratch as the solver hands it over: reused, never cleared. It is
    filled with garbage first, so a search that read a stale entry would go wrong here."""
    ni, nf = pair_scratch_sizes(len(xp), len(off) - 1)
    grid, boxes = np.full(ni, -7, np.int32), np.full(nf, np.nan)
    return _collect_pairs(xp, x0, radii, off, margin, pi, pj, grid, boxes)


def _all_pairs(xp, x0, radii, body_off, margin):
    """Every (i, j) of bodies b1 < b2 with |x_i - x_j| < r_i + m_i + r_j + m_j + margin, where r is
    the particle's largest radius and m how far it moved; ordered by b1, b2, i, j."""
    r = radii.max(axis=1)
    m = np.sqrt(((xp - x0) ** 2).sum(axis=1))
    out = []
    nb = len(body_off) - 1
    for b1 in range(nb):
        for b2 in range(b1 + 1, nb):
            for i in range(body_off[b1], body_off[b1 + 1]):
                for j in range(body_off[b2], body_off[b2 + 1]):
                    d2 = ((xp[i] - xp[j]) ** 2).sum()
                    lim = r[i] + m[i] + r[j] + m[j] + margin
                    if d2 < lim * lim:
                        out.append((i, j))
    return out


def _slabs(rng, n_bodies, per_body, gap, jitter):
    """Bodies as jittered slabs of particles side by side along x, ``gap`` apart [m]."""
    xs, offs = [], [0]
    for b in range(n_bodies):
        g = rng.uniform(0.0, 1.0, size=(per_body, 3)) * np.array([0.004, 0.03, 0.02])
        g[:, 0] += b * (0.004 + gap)
        xs.append(g)
        offs.append(offs[-1] + per_body)
    x0 = np.concatenate(xs)
    xp = x0 + rng.normal(scale=jitter, size=x0.shape)
    radii = rng.uniform(0.0005, 0.0015, size=x0.shape)
    return xp, x0, radii, np.array(offs, dtype=np.int32)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("gap", [-0.001, 0.0, 0.002, 0.05])
def test_the_grid_search_finds_every_pair_in_order(seed, gap):
    rng = np.random.default_rng(seed)
    n_bodies = 2 + seed % 2
    xp, x0, radii, off = _slabs(rng, n_bodies, 150 + 40 * seed, gap, 2e-4)
    margin = 5e-4
    expected = _all_pairs(xp, x0, radii, off, margin)
    cap = len(expected) + 5
    pi, pj = np.empty(cap, np.int32), np.empty(cap, np.int32)
    n = collect_pairs(xp, x0, radii, off, margin, pi, pj)
    assert n == len(expected)
    assert list(zip(pi[:n].tolist(), pj[:n].tolist(), strict=True)) == expected
    if gap > 0.01:
        assert n == 0  # far apart: nothing to find
    else:
        assert n > 0


def test_a_full_buffer_reports_the_count_it_needs():
    rng = np.random.default_rng(7)
    xp, x0, radii, off = _slabs(rng, 2, 200, -0.001, 1e-4)
    expected = _all_pairs(xp, x0, radii, off, 5e-4)
    pi, pj = np.empty(10, np.int32), np.empty(10, np.int32)
    n = collect_pairs(xp, x0, radii, off, 5e-4, pi, pj)
    assert n == len(expected) > 10
    assert list(zip(pi.tolist(), pj.tolist(), strict=True)) == expected[:10]


def test_one_huge_particle_still_meets_its_partners():
    """The grid's cells are as wide as the widest reach; one large particle (or one that moved far)
    widens them for all, and must not miss a partner two small cells away."""
    rng = np.random.default_rng(3)
    xp, x0, radii, off = _slabs(rng, 2, 300, 0.003, 1e-4)
    radii[5] = 0.006
    x0[450] -= np.array([0.0, 0.004, 0.0])  # moved 4 mm this step
    expected = _all_pairs(xp, x0, radii, off, 5e-4)
    cap = len(expected) + 1
    pi, pj = np.empty(cap, np.int32), np.empty(cap, np.int32)
    n = collect_pairs(xp, x0, radii, off, 5e-4, pi, pj)
    assert n == len(expected) and any(i == 5 for i, _ in expected)
    assert list(zip(pi[:n].tolist(), pj[:n].tolist(), strict=True)) == expected
