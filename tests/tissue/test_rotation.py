"""Rotation extraction (Mueller et al. 2016) and the quaternion <-> matrix helpers."""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import pytest

from softgrasp_env.tissue.rotation import (
    extract_rotation,
    matrix_to_quat,
    polar_rotation_svd,
    polar_rotation_unit_t,
    quat_to_matrix,
)

IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])
SEEDS = range(40)


def random_quat(rng: np.random.Generator) -> np.ndarray:
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    return quat_to_matrix(random_quat(rng))


def axis_angle(axis, angle: float) -> np.ndarray:
    axis = np.asarray(axis, dtype=np.float64)
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def extract(a, q=IDENTITY, iterations=200, tol=1e-12) -> np.ndarray:
    q_out = extract_rotation(np.ascontiguousarray(a, dtype=np.float64), np.asarray(q, dtype=np.float64),
                             iterations, tol)  # fmt: skip
    return quat_to_matrix(q_out)


def assert_proper_rotation(r: np.ndarray) -> None:
    assert np.all(np.isfinite(r))
    assert abs(np.linalg.det(r) - 1.0) < 1e-12
    assert np.abs(r.T @ r - np.eye(3)).max() < 1e-12


# --- det R = +1 and orthonormal for every kind of input ------------------------------------------


def _random_matrix(seed):
    return np.random.default_rng(seed).normal(size=(3, 3))


def _planar_matrix(seed):
    rng = np.random.default_rng(1000 + seed)
    u, v = random_rotation(rng), random_rotation(rng)
    return u @ np.diag([rng.uniform(0.5, 3.0), rng.uniform(0.5, 3.0), 0.0]) @ v.T


def _collinear_matrix(seed):
    rng = np.random.default_rng(2000 + seed)
    return np.outer(rng.normal(size=3), rng.normal(size=3))


def _inverted_matrix(seed):
    a = np.random.default_rng(3000 + seed).normal(size=(3, 3))
    if np.linalg.det(a) > 0.0:
        a[:, 0] *= -1.0
    return a


@pytest.mark.parametrize("make", [_random_matrix, _planar_matrix, _collinear_matrix, _inverted_matrix],
                         ids=["random", "planar", "collinear", "inverted"])  # fmt: skip
def test_result_is_a_proper_rotation(make):
    for seed in SEEDS:
        a = make(seed)
        rng = np.random.default_rng(seed)
        for q0 in (IDENTITY, random_quat(rng)):
            assert_proper_rotation(extract(a, q0, iterations=50))


def test_zero_matrix_gives_proper_rotation_and_keeps_the_warm_start():
    rng = np.random.default_rng(11)
    for _ in range(20):
        q0 = random_quat(rng)
        q = extract_rotation(np.zeros((3, 3)), q0, 50, 1e-12)
        assert_proper_rotation(quat_to_matrix(q))
        assert np.abs(q - q0).max() < 1e-12


def test_unnormalised_warm_start_is_normalised():
    q0 = np.array([0.3, -0.2, 0.5, 0.8]) * 7.0
    q = extract_rotation(np.zeros((3, 3)), q0, 10, 1e-12)
    assert abs(np.linalg.norm(q) - 1.0) < 1e-14
    assert np.abs(q - q0 / np.linalg.norm(q0)).max() < 1e-14


# --- agreement with the SVD polar factor ---------------------------------------------------------


def _well_conditioned(seed):
    """R S with R a random rotation and S SPD with condition number < 10."""
    rng = np.random.default_rng(4000 + seed)
    r = random_rotation(rng)
    v = random_rotation(rng)
    s = rng.uniform(1.0, 9.5, size=3)
    stretch = v @ np.diag(s) @ v.T
    assert np.linalg.cond(stretch) < 10.0
    return r @ stretch, r


@pytest.mark.parametrize("seed", range(50))
def test_matches_svd_polar_factor_on_well_conditioned_input(seed):
    a, r_true = _well_conditioned(seed)
    r_svd = polar_rotation_svd(a)
    assert np.abs(r_svd - r_true).max() < 1e-9  # the reference itself is right
    r = extract(a, IDENTITY, iterations=200, tol=1e-12)
    assert np.abs(r - r_svd).max() < 1e-9


def test_pure_rotation_is_recovered_exactly():
    rng = np.random.default_rng(5)
    for _ in range(20):
        r0 = random_rotation(rng)
        assert np.abs(extract(r0) - r0).max() < 1e-10


def test_polar_factor_is_a_fixed_point_of_the_warm_start():
    """Started at the answer, one sweep leaves it there (warm starting costs nothing at rest)."""
    for seed in range(20):
        a, r_true = _well_conditioned(seed)
        q_true = matrix_to_quat(r_true)
        q = extract_rotation(a, q_true, 1, 1e-12)
        assert np.abs(quat_to_matrix(q) - r_true).max() < 1e-12


def test_warm_start_near_the_answer_converges_linearly():
    """Each sweep shrinks the error (linear rate, slower with worse conditioning)."""
    for seed in range(20):
        a, r_true = _well_conditioned(seed)
        q_near = matrix_to_quat(axis_angle([1.0, 2.0, -0.5], 0.05) @ r_true)
        e0 = np.linalg.norm(quat_to_matrix(q_near) - r_true)
        errors = [np.linalg.norm(extract(a, q_near, iterations=k, tol=1e-15) - r_true) for k in (2, 5, 10, 30)]
        assert errors[0] < e0
        assert all(e1 < e0_ for e0_, e1 in pairwise(errors))
        assert errors[2] < 0.05 * e0
        assert errors[3] < 1e-5 * e0


@pytest.mark.parametrize("seed", range(20))
def test_planar_input_matches_svd_polar_factor(seed):
    """Rank 2: the third column is fixed by orthonormality, so the answer is still unique."""
    rng = np.random.default_rng(6000 + seed)
    u, v = random_rotation(rng), random_rotation(rng)
    s = np.array([rng.uniform(1.0, 3.0), rng.uniform(1.0, 3.0), 0.0])
    a = u @ np.diag(s) @ v.T
    r = extract(a, IDENTITY, iterations=300, tol=1e-13)
    assert_proper_rotation(r)
    assert np.abs(r - u @ v.T).max() < 1e-8
    assert np.abs(r - polar_rotation_svd(a)).max() < 1e-8


# --- degenerate input keeps the warm start -------------------------------------------------------


def test_rank_one_input_built_from_the_warm_start_returns_the_warm_start():
    rng = np.random.default_rng(21)
    ex = np.array([1.0, 0.0, 0.0])
    for _ in range(20):
        q0 = random_quat(rng)
        r0 = quat_to_matrix(q0)
        a = rng.uniform(0.1, 5.0) * r0 @ np.outer(ex, ex)
        r = extract(a, q0, iterations=100, tol=1e-12)
        assert np.abs(r - r0).max() < 1e-12


def test_rank_one_input_turns_the_warm_start_by_the_shortest_arc_only():
    """A = s a_hat e_x^T fixes only R e_x; the twist about a_hat is the warm start's (no snap to identity)."""
    rng = np.random.default_rng(22)
    ex = np.array([1.0, 0.0, 0.0])
    for _ in range(20):
        q0 = random_quat(rng)
        r0 = quat_to_matrix(q0)
        a_hat = axis_angle(rng.normal(size=3), rng.uniform(0.2, 1.2)) @ (r0 @ ex)  # 0.2..1.2 rad off
        a = rng.uniform(0.5, 2.0) * np.outer(a_hat, ex)
        r = extract(a, q0, iterations=200, tol=1e-13)
        assert_proper_rotation(r)
        assert np.abs(r @ ex - a_hat).max() < 1e-9
        # expected: the shortest-arc rotation taking r0 e_x to a_hat, applied after r0
        b = r0 @ ex
        axis = np.cross(b, a_hat)
        angle = np.arctan2(np.linalg.norm(axis), b @ a_hat)
        expected = axis_angle(axis, angle) @ r0
        assert np.abs(r - expected).max() < 1e-8


def test_rank_one_input_from_identity_and_from_a_twisted_start_differ():
    """The undetermined twist really comes from the warm start: two starts, two answers."""
    ex = np.array([1.0, 0.0, 0.0])
    a = 2.0 * np.outer(ex, ex)
    twisted = axis_angle(ex, 0.7)
    r_id = extract(a, IDENTITY)
    r_tw = extract(a, matrix_to_quat(twisted))
    assert np.abs(r_id - np.eye(3)).max() < 1e-12
    assert np.abs(r_tw - twisted).max() < 1e-12


# --- inverted input ------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(40))
def test_inverted_input_maximises_trace(seed):
    """det A < 0: the best proper rotation flips the smallest singular direction.

    Singular values are kept apart (s3 <= s2 / 2): the iteration's contraction on the flipped
    direction goes with s2 - s3, so nearly equal s2, s3 converge arbitrarily slowly (math, not a bug).
    """
    rng = np.random.default_rng(7000 + seed)
    u, v = random_rotation(rng), random_rotation(rng)
    s = np.array([rng.uniform(2.0, 4.0), rng.uniform(1.0, 2.0), rng.uniform(0.05, 0.5)])
    a = u @ np.diag([s[0], s[1], -s[2]]) @ v.T
    assert np.linalg.det(a) < 0.0
    r_svd = polar_rotation_svd(a)
    assert_proper_rotation(r_svd)
    assert abs(np.trace(r_svd.T @ a) - (s[0] + s[1] - s[2])) < 1e-9
    r = extract(a, IDENTITY, iterations=300, tol=1e-13)
    assert_proper_rotation(r)
    assert np.trace(r.T @ a) >= np.trace(r_svd.T @ a) - 1e-9


def test_inverted_input_random_matrices_never_exceed_the_svd_optimum():
    """Upper bound holds for any proper rotation; the lower bound (after many sweeps) for most."""
    for seed in SEEDS:
        a = _inverted_matrix(seed)
        r_svd = polar_rotation_svd(a)
        r = extract(a, IDENTITY, iterations=2000, tol=1e-13)
        assert np.trace(r.T @ a) <= np.trace(r_svd.T @ a) + 1e-9
        assert np.trace(r.T @ a) >= np.trace(r_svd.T @ a) - 1e-6


# --- quaternion <-> matrix -----------------------------------------------------------------------


def test_quat_matrix_round_trip():
    rng = np.random.default_rng(31)
    for _ in range(200):
        q = random_quat(rng)
        m = quat_to_matrix(q)
        assert_proper_rotation(m)
        q2 = matrix_to_quat(m)
        assert abs(np.linalg.norm(q2) - 1.0) < 1e-12
        assert min(np.abs(q2 - q).max(), np.abs(q2 + q).max()) < 1e-12
        assert np.abs(quat_to_matrix(q2) - m).max() < 1e-12


@pytest.mark.parametrize("axis", [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [1, 1, 1]])
def test_matrix_to_quat_near_half_turn(axis):
    """Every Shepperd branch, including trace <= 0 (angles near pi)."""
    for angle in (np.pi, np.pi - 1e-3, 2.5, 0.0, 1e-8):
        m = axis_angle(axis, angle)
        q = matrix_to_quat(m)
        assert np.abs(quat_to_matrix(q) - m).max() < 1e-12


def test_quat_to_matrix_known_values():
    s = np.sqrt(0.5)
    # +90 degrees about z: x -> y
    m = quat_to_matrix(np.array([0.0, 0.0, s, s]))
    assert np.allclose(m @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], atol=1e-15)
    assert np.allclose(m, axis_angle([0, 0, 1], np.pi / 2), atol=1e-15)
    assert np.allclose(quat_to_matrix(IDENTITY), np.eye(3), atol=0.0)
    # q and -q are the same rotation
    q = random_quat(np.random.default_rng(3))
    assert np.abs(quat_to_matrix(q) - quat_to_matrix(-q)).max() < 1e-15


# --- Newton's polar rotation (the global material solve's local step) -----------------------------


def _angle(r: np.ndarray, r_true: np.ndarray) -> float:
    """The angle between two rotations [rad], from the skew part of r r_true^T (arccos of the
    trace loses half the digits near zero)."""
    d = r @ r_true.T
    return float(np.arcsin(min(1.0, np.linalg.norm([d[2, 1] - d[1, 2], d[0, 2] - d[2, 0], d[1, 0] - d[0, 1]]) / 2)))


def polar_rotation(a: np.ndarray, q: np.ndarray, iterations: int, tol: float) -> np.ndarray:
    """polar_rotation_unit_t on arrays (the kernels pass tuples)."""
    return np.array(polar_rotation_unit_t(tuple(a.ravel()), tuple(q), iterations, tol))


def _stretched(rng: np.random.Generator, stretch: float) -> tuple[np.ndarray, np.ndarray]:
    """A = R S with S symmetric, eigenvalues within 1 -/+ stretch (positive): A's polar factor is R."""
    while True:
        s = np.eye(3) + stretch * rng.uniform(-1.0, 1.0, (3, 3))
        s = (s + s.T) / 2.0
        if np.linalg.eigvalsh(s).min() > 0.05:
            r = random_rotation(rng)
            return r @ s, r


@pytest.mark.parametrize("stretch", [0.0, 0.3, 0.6])
def test_newtons_polar_rotation_converges_quadratically_from_a_warm_start(stretch):
    """From 0.01 rad away, one Newton iteration leaves 2.5-2.9e-7 rad (measured, the worst of 30)
    and two reach the polar factor to round-off (< 7e-16 measured) at stretches up to 60 %;
    Mueller et al.'s iteration after the same two steps is still 4e-4 to 2e-3 rad away."""
    rng = np.random.default_rng(7)
    for _ in range(30):
        a, r_true = _stretched(rng, stretch)
        q0 = matrix_to_quat(axis_angle(rng.normal(size=3), 0.01) @ r_true)
        one = _angle(quat_to_matrix(polar_rotation(a, q0, 1, 1e-10)), r_true)
        two = _angle(quat_to_matrix(polar_rotation(a, q0, 2, 1e-10)), r_true)
        assert one < 1e-6
        assert two < 1e-14
        assert _angle(extract(a, q0, iterations=2, tol=1e-10), r_true) > 1e-4


def test_newtons_polar_rotation_takes_mueller_steps_far_from_the_answer():
    """Warm starts up to 3 rad away (where M is not positive definite or the Newton step would be
    longer than 1/2 rad) still reach the polar factor within 20 iterations, to the tolerance asked
    (1e-10 rad: the step it stops at is not taken; up to 9.6e-11 measured)."""
    rng = np.random.default_rng(8)
    for angle in (0.6, 1.5, 3.0):
        for _ in range(20):
            a, r_true = _stretched(rng, 0.3)
            q0 = matrix_to_quat(axis_angle(rng.normal(size=3), angle) @ r_true)
            r = quat_to_matrix(polar_rotation(a, q0, 20, 1e-10))
            assert_proper_rotation(r)
            assert _angle(r, r_true) < 1e-10
