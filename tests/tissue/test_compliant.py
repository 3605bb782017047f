"""The compliant material on its own (softgrasp_env/tissue/compliant.py): its group solve converges
to the implicit step, its stiffness is what its modulus says, its step limits."""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
import pytest

from softgrasp_env.config import SimConfig, TissueConfig
from softgrasp_env.tissue.builder import CoreShape, build_combined_body, group_kappa
from softgrasp_env.tissue.compliant import (
    MAX_COUPLING_FOLD,
    MAX_STEP_STIFFNESS,
    core_stiffness,
    coupling_substeps,
    substeps_for,
)
from softgrasp_env.tissue.model import TissueModel
from softgrasp_env.tissue.rigid import Colliders
from softgrasp_env.tissue.solver import TissueSolver
from softgrasp_env.tissue.state import state_at_rest

M_ATTACHED, M_OUTER, EXTRUDE = 0.8e-3, 0.8e-3, 0.008


def column(kappa: float) -> TissueModel:
    """Two particles on a core: one attached at the core's surface, its outer partner ``EXTRUDE``
    above it, in two groups of both (each particle centres one)."""
    rest_x = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, EXTRUDE]])
    mass = np.array([M_ATTACHED, M_OUTER])
    c = (mass[:, None] * rest_x).sum(axis=0) / mass.sum()
    members = np.array([0, 1, 1, 0], dtype=np.int32)
    return TissueModel(
        particle_rest_x=rest_x, particle_rest_q=np.tile([0.0, 0.0, 0.0, 1.0], (2, 1)),
        particle_radii=np.full((2, 3), 0.002), particle_mass=mass, particle_inv_mass=1.0 / mass,
        particle_body=np.zeros(2, dtype=np.int32), particle_partner=np.array([1, 0], dtype=np.int32),
        particle_attached=np.array([True, False]), group_offsets=np.array([0, 2, 4], dtype=np.int32),
        group_members=members, group_rest_offset=rest_x[members] - c, body_particle_offsets=np.array([0, 2], dtype=np.int32),
        body_core_shape=np.array([0], dtype=np.int32), body_friction=np.array([[0.9, 0.9]]),
        group_kappa=np.full(2, kappa),
    )  # fmt: skip


def fixed_core() -> Colliders:
    """A kinematic core (no mass: held) at the origin, a sphere the particles never reach."""
    return Colliders(
        rigid_x=np.zeros((1, 3)), rigid_q=np.array([[0.0, 0.0, 0.0, 1.0]]), rigid_v=np.zeros((1, 3)),
        rigid_w=np.zeros((1, 3)), rigid_inv_mass=np.zeros(1), rigid_inv_inertia=np.zeros((1, 3)),
        rigid_gravity=np.zeros(1, dtype=np.bool_), rigid_in_solve=np.zeros(1, dtype=np.bool_),
        shape_kind=np.array([1], dtype=np.int32), shape_params=np.array([[1e-4, 0.0, 0.0]]),
        shape_rigid=np.zeros(1, dtype=np.int32), shape_local_x=np.array([[0.0, 0.0, -0.01]]),
        shape_local_q=np.array([[0.0, 0.0, 0.0, 1.0]]),
    )  # fmt: skip


def _column_step(kappa: float, dt: float, iterations: int, stretch: float):
    model = column(kappa)
    state = state_at_rest(model, np.zeros((1, 3)), np.array([[0.0, 0.0, 0.0, 1.0]]))
    state.particle_x[1, 2] += stretch
    solver = TissueSolver(model, SimConfig(dt=dt, iterations=iterations, gravity=0.0, damping=0.0))
    out = solver.step(state, fixed_core())
    return state.particle_x[1, 2] - EXTRUDE, out.rigid_impulse[0, 2] + M_OUTER * state.particle_v[1, 2]


@pytest.mark.parametrize("dt", [1 / 1000, 1 / 240, 1 / 60])
def test_a_stretched_column_converges_to_the_implicit_step(dt):
    """A column of one attached and one outer particle, stretched by 1 mm and let go with no gravity
    and no damping: its two groups are springs of kappa m_a m_o / M each to the core (held), so the
    implicit (backward Euler) step leaves the stretch d / (1 + k dt^2 / m_o), k = 2 kappa m_a m_o / M,
    whatever dt - where the per-step material moved a fixed fraction of it. Each group's Newton step
    is exact for itself; the passes over the two, Gauss-Seidel, close the rest geometrically, every
    pass strictly closer (s = kappa dt^2 of 0.1, 5.8 and 28 here; at 28 by a factor 0.87 a pass,
    measured: 8e-9 m left after 60). The core takes the springs' force: what the particle gains,
    the core loses."""
    kappa, stretch = 1e5, 1e-3
    k = 2.0 * kappa * M_ATTACHED * M_OUTER / (M_ATTACHED + M_OUTER)
    expected = stretch / (1.0 + k * dt * dt / M_OUTER)
    errors = []
    for iterations in (1, 2, 5, 20, 60):
        got, momentum = _column_step(kappa, dt, iterations, stretch)
        errors.append(abs(got - expected))
        assert momentum == pytest.approx(0.0, abs=1e-15)
    assert all(b < a for a, b in itertools.pairwise(errors) if a > 1e-15), errors
    assert errors[-1] < 1e-5 * stretch, errors


def test_group_kappa_is_the_shear_wave_across_the_group():
    """kappa = G / (rho l^2): doubling G doubles it, doubling the density halves it; its square
    root over the group's radius of gyration l is the shear wave speed sqrt(G / rho)."""
    tissue = TissueConfig()
    model = build_combined_body(CoreShape("box", half_extents=(0.008, 0.02, 0.03)), tissue, faces=("+x", "-z"))
    k = model.group_kappa
    off, members = model.group_offsets, model.group_members
    for i in range(0, model.particle_count, 7):
        e = slice(off[i], off[i + 1])
        m = model.particle_mass[members[e]]
        l2 = (m * (model.group_rest_offset[e] ** 2).sum(axis=1)).sum() / m.sum()
        assert np.sqrt(k[i] * l2) == pytest.approx(np.sqrt(tissue.shear_modulus / tissue.mass_density), rel=1e-12)
    twice = group_kappa(off, members, model.group_rest_offset, model.particle_mass, 2 * tissue.shear_modulus,
                        tissue.mass_density)  # fmt: skip
    assert twice == pytest.approx(2 * k, rel=1e-12)


def test_the_pads_stiffness_against_its_core_is_the_layers():
    """core_stiffness of the default pad (G 4,000 Pa, the inner face and tip): its groups as springs
    in parallel, within 15 % of the layer it stands for, G A / extrude (1,310 against 1,520 N/m)."""
    tissue = TissueConfig()
    half = (0.008, 0.02, 0.03)
    model = build_combined_body(CoreShape("box", half_extents=half), tissue, faces=("+x", "-z"))
    area = 4 * half[1] * half[2] + 4 * half[0] * half[1]
    layer = tissue.shear_modulus * area / tissue.extrude
    assert core_stiffness(model)[0] == pytest.approx(layer, rel=0.15)


def test_step_limits_at_the_defaults():
    """The pads' steps at the defaults: their groups' s = kappa h^2 within MAX_STEP_STIFFNESS and
    their pull on a 50 g core within MAX_COUPLING_FOLD (1 step at 1/480 s, 2 at 1/240 s, 4 at
    1/120 s)."""
    model = build_combined_body(CoreShape("box", half_extents=(0.008, 0.02, 0.03)), TissueConfig(), faces=("+x", "-z"))
    core = np.array([0.05])
    for dt, n in ((1 / 1000, 1), (1 / 480, 1), (1 / 240, 2), (1 / 120, 4)):
        assert substeps_for(model, dt) == n
        h = dt / n
        assert model.group_kappa.max() * h * h <= MAX_STEP_STIFFNESS
        assert core_stiffness(model)[0] * h * h / 0.05 <= MAX_COUPLING_FOLD
        assert coupling_substeps(model, core, dt) <= n


@pytest.mark.parametrize("limit", [0.005, 0.02])
def test_the_strain_limit_holds_a_particle_within_reach_of_its_core(limit):
    """anchors.limit_deviation: the outer particle of a slack column (kappa 10: its groups barely
    pull in one step), let go 5 cm from its spot with no velocity, ends the step at the body's
    max_deviation from it - the limit is the last projection of the iteration - and the core takes
    the reaction: the momentum the particle gained is the impulse on the core, exactly."""
    model = replace(column(10.0), body_max_deviation=np.array([limit]))
    state = state_at_rest(model, np.zeros((1, 3)), np.array([[0.0, 0.0, 0.0, 1.0]]))
    state.particle_x[1, 2] += 0.05
    solver = TissueSolver(model, SimConfig(dt=1 / 240, gravity=0.0, damping=0.0))
    out = solver.step(state, fixed_core())
    assert state.particle_x[1, 2] - EXTRUDE == pytest.approx(limit, rel=1e-9)
    assert out.rigid_impulse[0, 2] + M_OUTER * state.particle_v[1, 2] == pytest.approx(0.0, abs=1e-15)
    assert state.particle_v[1, 2] < 0.0  # pulled back toward the core


def test_two_rows_on_the_tip_round_its_groups_and_halve_the_world_steps():
    """TissueConfig.min_rows: at 4,000 per m^2 the v4 pad's 16 mm tip has one row of particles, so
    the groups across the tip and the inner face are flat (rest moments' eigenvalue ratio 0.03) and
    stiff across their thin side, and the step rule takes 6 world steps at 1/240 s from them. Two
    rows (6 particles more a pad) round them: 3 steps, what the inner face alone needs. Where the
    spacing gives two rows already (16,000 per m^2) nothing changes."""
    from softgrasp_env.presets import TISSUE_V4

    base = replace(TissueConfig(**{k: v for k, v in TISSUE_V4.items() if k != "layers"}), layers=1)
    half = (0.008, 0.02, 0.03)

    def pad(**kw):
        return build_combined_body(CoreShape("box", half_extents=half), replace(base, **kw), faces=("+x", "-z"))

    def flattest(model):
        ratios = []
        for i in range(model.particle_count):
            e = slice(int(model.group_offsets[i]), int(model.group_offsets[i + 1]))
            q, m = model.group_rest_offset[e], model.particle_mass[model.group_members[e]]
            w = np.linalg.eigvalsh((m[:, None, None] * q[:, :, None] * q[:, None, :]).sum(axis=0))
            ratios.append(w[0] / w[2])
        return min(ratios)

    one, two, face = pad(), pad(min_rows=2), build_combined_body(CoreShape("box", half_extents=half), base, faces=("+x",))
    assert (one.particle_count, two.particle_count) == (30, 36)
    assert flattest(one) < 0.03 and flattest(two) > 0.1
    assert substeps_for(one, 1 / 240) == 6 and substeps_for(two, 1 / 240) == substeps_for(face, 1 / 240) == 3
    assert two.group_kappa.max() < 0.3 * one.group_kappa.max()
    fine = replace(base, particle_density=16_000.0)
    a = build_combined_body(CoreShape("box", half_extents=half), fine, faces=("+x", "-z"))
    b = build_combined_body(CoreShape("box", half_extents=half), replace(fine, min_rows=2), faces=("+x", "-z"))
    np.testing.assert_array_equal(a.particle_rest_x, b.particle_rest_x)
    np.testing.assert_array_equal(a.group_kappa, b.group_kappa)
    with pytest.raises(ValueError, match="min_rows"):
        replace(base, min_rows=5)


def test_two_rows_on_the_tip_carry_the_cylinder_in_the_env():
    """SoftGrasp-v4 with tissue_min_rows=2 (3 world steps a physics step): the scripted grasp lifts
    the cylinder and carries it through the carry test, at the default iterations and friction."""
    import gymnasium as gym

    import softgrasp_env  # noqa: F401  (registers the ids)
    from softgrasp_env.policies import ScriptedGraspPolicy

    env = gym.make("SoftGrasp-v4", tissue_min_rows=2)
    policy = ScriptedGraspPolicy.for_env(env)
    obs, _ = env.reset(seed=0)
    assert env.unwrapped.scene.world.substeps == 3
    done = False
    while not done:
        obs, _, term, trunc, info = env.step(policy(obs))
        done = term or trunc
    assert info["is_success"] and not info["diverged"]
    env.close()
