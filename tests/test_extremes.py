"""Every accepted setting runs: the ends of the documented ranges, alone and in a small
grid of combinations, run episodes without divergence; a seeded fuzz over the documented ranges
gives no NaN and no exception but the documented ValueErrors, and no divergence. The ends and
combinations run on two physics: the thesis tissue the ranges were first measured on, and the
soft ids' latest (SoftGrasp-v5: the v4 tissue solved globally, what ``gym.make`` gives by
default), which refuses the consistent coupling by name (tested with the refusals below).

Where a range's end did not run it was narrowed, with the measurement in the docstring of the
setting (config.py: SimConfig.dt, TissueConfig.shear_modulus / mass_density / group_size; fingers/
tissue.py: the particle-width and consistent-squeeze rules of the tissue kind; arguments.py:
MAX_ARM_STEP)."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

from agents.scripted import ScriptedGraspPolicy
from softgrasp_env.config import SimConfig, TissueConfig
from softgrasp_env.registration import TISSUE_V3
from tests.helpers import SOFT_PHYSICS, run_episode, soft_physics


def _finite(obs, reward, term, trunc, info) -> None:
    assert np.isfinite(obs).all() and math.isfinite(reward)


def _episodes(kwargs: dict, *, seeds=(0,), scripted=(0,), physics: str = "thesis") -> list[str]:
    """Random-action episodes on ``seeds`` and scripted ones on ``scripted``, on ``physics``
    (tests.helpers.soft_physics: its id, its keywords under ``kwargs``); the divergences, each with its reason
    (empty when none). A divergence ends its episode: it is the last step."""
    env_id, keywords = soft_physics("SoftGrasp", physics)
    env = gym.make(env_id, **{**keywords, **kwargs})
    problems = []
    try:
        for mode, episode_seeds in (("random", seeds), ("scripted", scripted)):
            for seed in episode_seeds:
                rng = np.random.default_rng(seed)
                policy = ScriptedGraspPolicy() if mode == "scripted" else (
                    lambda obs, rng=rng: rng.uniform(-1, 1, 4).astype(np.float32))  # fmt: skip
                ep = run_episode(env, policy, seed=seed, max_steps=100, on_step=_finite)
                if ep.diverged:
                    problems.append(f"{mode} seed {seed} step {ep.steps - 1}: {ep.info['divergence']}")
    finally:
        env.close()
    return problems


# The ends of every documented range the env and the configs accept, each alone (the defaults
# otherwise). Where an end is not listed, the comment says why.
ENDS = {
    # SimConfig. dt's lower end 1e-5 s runs 5,000 substeps per env step: too slow for a test, 1/1200 stands in.
    "dt 1/60": dict(sim=SimConfig(dt=1 / 60)),
    "dt 1/1200": dict(sim=SimConfig(dt=1 / 1200)),
    "iterations 1": dict(sim=SimConfig(iterations=1)),
    "rotation_iterations 100": dict(sim=SimConfig(rotation_iterations=100)),
    "gravity 0": dict(sim=SimConfig(gravity=0.0)),
    "gravity 100": dict(sim=SimConfig(gravity=100.0)),
    "damping 0": dict(sim=SimConfig(damping=0.0)),
    "damping 1e4": dict(sim=SimConfig(damping=1e4)),
    "contact_margin 0": dict(sim=SimConfig(contact_margin=0.0)),
    "contact_margin 0.1": dict(sim=SimConfig(contact_margin=0.1)),
    "coupling consistent": dict(sim=SimConfig(coupling="consistent")),
    # TissueConfig. particle_density: the particle-width rule sets the low end at the default radius_scale
    # ((0.6 / 0.0125)^2 = 2,304 per m^2); the top end (1e7) is refused by the memory check or builds for minutes.
    "density 2304": dict(particle_density=2304.0),
    "density 20000": dict(particle_density=20_000.0),
    "extrude 0.001": dict(tissue=TissueConfig(extrude=0.001)),
    "extrude 0.02 (thickest pad that fits)": dict(tissue=TissueConfig(extrude=0.02)),
    "group_size 4": dict(tissue=TissueConfig(group_size=4)),
    "group_size 16": dict(tissue=TissueConfig(group_size=16)),
    "tissue mass density 100": dict(tissue=TissueConfig(mass_density=100.0)),
    "tissue mass density 1e4": dict(tissue=TissueConfig(mass_density=1e4)),
    "shear_modulus 1e3 (the softest)": dict(shear_modulus=1e3),
    "shear_modulus 1e6 (the stiffest)": dict(shear_modulus=1e6),
    "radius_scale 0.05": dict(tissue=TissueConfig(radius_scale=0.05)),
    "radius_scale 0.79 (widest at the default density)": dict(tissue=TissueConfig(radius_scale=0.79)),
    "normal_radius 1e-4": dict(tissue=TissueConfig(normal_radius=1e-4)),
    "normal_radius 0.01": dict(tissue=TissueConfig(normal_radius=0.01)),
    "friction 0": dict(friction_static=0.0, friction_kinetic=0.0),
    "friction 10": dict(friction_static=10.0, friction_kinetic=10.0),
    # The env and the scene.
    "cylinder_mass 0.001": dict(cylinder_mass=0.001),
    "cylinder_mass 10": dict(cylinder_mass=10.0),
    "cylinder_radius 0.005": dict(cylinder_radius=0.005),
    "cylinder_radius 0.045 (widest with the wedge range)": dict(cylinder_radius=0.045),
    "cylinder_height 0.01": dict(cylinder_height=0.01),
    "cylinder_height 0.14 (tallest for the reach start)": dict(cylinder_height=0.14),
    "finger_force 0.01": dict(finger_force=0.01),
    "finger_force 1000": dict(finger_force=1000.0),
    "arm_speed 2": dict(arm_speed=2.0),
    "control_frequency 240": dict(control_frequency=240.0),
    "cylinder_position_range 0.08": dict(cylinder_position_range=0.08),
    "lateral_offset_range 0.05": dict(lateral_offset_range=0.05),
    "yaw_range pi/4 with jaw_wedge_range pi/6": dict(jaw_wedge_range=math.pi / 6),
    "friction_range 0.9": dict(friction_range=0.9),
    "cylinder_mass_range 0.9": dict(cylinder_mass_range=0.9),
    "cylinder_radius_range 0.015": dict(cylinder_radius_range=0.015),
}

# Combinations of the ends that stress the solver together (each pair ran alone above).
COMBINATIONS = {
    "dt 1/60, 1 iteration": dict(sim=SimConfig(dt=1 / 60, iterations=1)),
    "dt 1/60, group_size 16": dict(sim=SimConfig(dt=1 / 60), tissue=TissueConfig(group_size=16)),
    "dt 1/60, no damping, the softest tissue": dict(sim=SimConfig(dt=1 / 60, damping=0.0), shear_modulus=1e3),
    "dt 1/60, the stiffest tissue": dict(sim=SimConfig(dt=1 / 60), shear_modulus=1e6),
    "consistent, dt 1/60, finger_force 7.5 (its strongest at 1/60)": dict(
        sim=SimConfig(dt=1 / 60, coupling="consistent"), finger_force=7.5),  # fmt: skip
    "consistent, finger_force 30, arm_speed 2": dict(sim=SimConfig(coupling="consistent"), finger_force=30.0,
                                                         arm_speed=2.0),  # fmt: skip
    "1 iteration, group_size 16, the softest tissue": dict(sim=SimConfig(iterations=1),
                                                           tissue=TissueConfig(group_size=16, shear_modulus=1e3)),  # fmt: skip
    "heaviest and softest tissue": dict(tissue=TissueConfig(mass_density=1e4, shear_modulus=1e3)),
    "lightest and stiffest tissue": dict(tissue=TissueConfig(mass_density=100.0, shear_modulus=1e6)),
    "gravity 100, heaviest tissue": dict(sim=SimConfig(gravity=100.0), tissue=TissueConfig(mass_density=1e4)),
    "cylinder 10 kg, finger_force 1000": dict(cylinder_mass=10.0, finger_force=1000.0),
    "cylinder 1 g, finger_force 1000": dict(cylinder_mass=0.001, finger_force=1000.0),
    "every randomisation range wide": dict(cylinder_position_range=0.08, lateral_offset_range=0.02,
                                           jaw_wedge_range=0.2, friction_range=0.9, cylinder_mass_range=0.9,
                                           cylinder_radius_range=0.01),  # fmt: skip
}


SLOW_COMBINATIONS = {
    # Its scripted seed-0 episode snags a particle on the rim (3.0 cm, the known failure); the
    # slow test's eight other episodes ran without one.
    "dt 1/60, finger_force 1000, arm_speed 0.5 (its fastest at 1/60)": dict(sim=SimConfig(dt=1 / 60),
                                                                                 finger_force=1000.0, arm_speed=0.5),  # fmt: skip
}


def _cases(table: dict[str, dict]) -> list:
    """(physics, name) for every setting of ``table`` on every physics, but the consistent
    coupling's on v5's global solve, which refuses it when the env is made."""
    return [pytest.param(physics, name, id=f"{physics}-{name}") for physics in SOFT_PHYSICS for name, kw in table.items()
            if not (physics == "v5" and getattr(kw.get("sim"), "coupling", "thesis") == "consistent")]  # fmt: skip


@pytest.mark.parametrize(("physics", "name"), _cases(ENDS))
def test_each_end_of_each_range_runs(physics, name):
    assert _episodes(ENDS[name], physics=physics) == []


@pytest.mark.parametrize(("physics", "name"), _cases(COMBINATIONS))
def test_combinations_of_ends_run(physics, name):
    assert _episodes(COMBINATIONS[name], physics=physics) == []


@pytest.mark.slow
@pytest.mark.parametrize(("physics", "name"), _cases({**ENDS, **COMBINATIONS, **SLOW_COMBINATIONS}))
def test_ends_and_combinations_run_over_more_seeds(physics, name):
    """Eight more episodes each (5 random-action, 3 scripted): at most one ends in the one known
    failure, a tissue particle snagged over the cylinder's rim and torn just past the 3 cm limit
    (at the defaults about once in 10,000 random-action steps, README). Measured over the 56
    settings of release 0.6.0 (six of them the per-step material's, retired since): 54 none;
    'lightest tissue, stiffness 0.1' (per-step) one, 'every randomisation range wide' one (scripted seed 2, 3.3 cm; none with jaw_wedge_range 0.15 or without the radius range).
    On SoftGrasp-v5 (the global solve) every one of the 54 settings it accepts ran its eight
    episodes without a divergence (one run), the wide ranges' snag included.
    Fixing the snag is physics left to do; any other divergence, or a second, fails."""
    problems = _episodes({**ENDS, **COMBINATIONS, **SLOW_COMBINATIONS}[name], seeds=range(1, 6), scripted=range(1, 4),
                         physics=physics)  # fmt: skip
    assert len(problems) <= 1 and all("tissue torn: a particle 3." in p for p in problems), problems


@pytest.mark.slow
@pytest.mark.parametrize("kwargs", [dict(sim=SimConfig(iterations=200)), dict(control_frequency=0.5)],
                         ids=["iterations 200", "control_frequency 0.5"])  # fmt: skip
def test_slow_ends_run(kwargs):
    assert _episodes(kwargs) == []


@pytest.mark.parametrize("kwargs, match", [
    (dict(sim=SimConfig(dt=1 / 60), arm_speed=2.0), r"arm_speed=2 m/s with sim\.dt=0\.0166667 s .* at most 0\.5 m/s"),
    (dict(tissue=TissueConfig(radius_scale=2.0)), r"particles are too wide.*0\.0316 m.*at least 25600 per m\^2"),
    (dict(particle_density=900.0), r"particles are too wide.*0\.0200 m"),
    (dict(tissue=TissueConfig(normal_radius=0.03)), r"tissue pad \(0\.038 m\)"),
    (dict(tissue=TissueConfig(extrude=0.1)), r"does not fit between the open fingers.*tissue pad \(0\.103 m\)"),
    # the consistent coupling is the sweep's (the global solve refuses it by name)
    (dict(sim=SimConfig(dt=1 / 60, coupling="consistent"), material_solve="groups", finger_force=30.0),
     r"coupling='consistent' with finger_force=30 N .* at most 7\.5 N"),
    (dict(cylinder_mass=9.0, cylinder_mass_range=0.9), r"cylinder_mass_range=0\.9, cylinder_mass=9\b.*got 17\."),
])  # fmt: skip
def test_settings_that_did_not_run_are_refused_naming_the_rule(kwargs, match):
    with pytest.raises(ValueError, match=match):
        gym.make("SoftGrasp-v5", **kwargs)


def _draw(rng: np.random.Generator) -> dict:
    """Random settings over the documented ranges (log-uniform for the scales)."""

    def lu(lo, hi):
        return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))

    rate = int(rng.choice([60, 120, 240, 480]))
    mu_s = lu(0.05, 10.0)
    return dict(
        fingers=str(rng.choice(["tissue", "tissue", "rigid", "segmented"])),
        sim=SimConfig(dt=1.0 / rate, iterations=int(rng.integers(1, 8)), damping=lu(1e-3, 1e4),
                      coupling=str(rng.choice(["thesis", "consistent"])), gravity=float(rng.uniform(0, 20))),
        # (rng.uniform(), ...)[1]: the draw that once chose a retired material, kept so that every
        # other setting is drawn as before
        tissue=TissueConfig(particle_density=lu(2304, 2e4), shear_modulus=(rng.uniform(), lu(1e3, 1e6))[1],
                            mass_density=lu(100, 1e4), group_size=int(rng.integers(4, 17)),
                            radius_scale=float(rng.uniform(0.05, 1.0)), normal_radius=lu(1e-4, 0.01), extrude=lu(0.002, 0.02), friction_static=mu_s,
                            friction_kinetic=mu_s * float(rng.uniform(0.3, 1.0))),
        cylinder_mass=lu(0.001, 10.0), finger_force=lu(0.01, 1000.0), arm_speed=float(rng.uniform(0.01, 2.0)),
        control_frequency=float(rng.choice([f for f in (10, 20, 30, 60) if rate % f == 0])),
        cylinder_position_range=float(rng.uniform(0, 0.08)), yaw_range=float(rng.uniform(0, math.pi / 4)),
        jaw_wedge_range=float(rng.uniform(0, math.pi / 6)), lateral_offset_range=float(rng.uniform(0, 0.05)),
        friction_range=float(rng.uniform(0, 0.9)), cylinder_mass_range=float(rng.uniform(0, 0.9)),
        cylinder_radius_range=float(rng.uniform(0, 0.02)),
    )  # fmt: skip


def _fuzz(env_id: str, draws: int, keywords: dict, *, coupling: str | None = None) -> tuple[int, int, list]:
    """``draws`` seeded draws of :func:`_draw` (``coupling`` in place of the drawn one if given),
    made as ``env_id`` with ``keywords`` under them, 100 random-action steps each: (steps run,
    draws refused by gym.make's ValueError, the divergences as (draw, fingers, reason)). Asserts no
    NaN on the way."""
    from dataclasses import replace

    rng = np.random.default_rng(12)
    ran = refused = 0
    problems = []
    for k in range(draws):
        kwargs = _draw(rng)
        if coupling is not None:
            kwargs["sim"] = replace(kwargs["sim"], coupling=coupling)
        try:
            env = gym.make(env_id, **{**keywords, **kwargs})
        except ValueError:
            refused += 1
            continue
        try:
            obs, _ = env.reset(seed=k)
            for _ in range(100):
                obs, reward, term, trunc, info = env.step(rng.uniform(-1, 1, 4).astype(np.float32))
                ran += 1
                assert np.isfinite(obs).all() and math.isfinite(reward)
                if info["diverged"]:
                    problems.append((k, kwargs["fingers"], info["divergence"]))
                    break
                if term or trunc:
                    obs, _ = env.reset(seed=1000 + k)
        finally:
            env.close()
    return ran, refused, problems


def test_fuzz_over_the_documented_ranges():
    """30 seeded draws of every setting at once, 100 random-action steps each (1,000 steps in all
    once the refused draws are left out: 20 of the 30 are, each by a rule of its own): no NaN, no
    exception but gym.make's ValueError for a combination outside the rules, and no divergence (on
    SoftGrasp-v4 with the thesis tissue, TISSUE_V3, where the draws were measured).
    (Ten more draws found the segmented kind turning a segment at 100 rad/s, past its 90 rad/s
    divergence limit, at draw 36: the kind's own limit, not the tissue's; noted, not chased here.)"""
    ran, refused, problems = _fuzz("SoftGrasp-v4", 30, TISSUE_V3)
    assert ran >= 1000 and refused < 25, (ran, refused)
    assert problems == []


def test_fuzz_over_the_documented_ranges_on_the_soft_ids_latest_physics():
    """The same draws on SoftGrasp-v5 (the v4 tissue solved globally), each with the thesis coupling
    (the global solve refuses the consistent one by name), 40 draws for enough that run: measured
    1,208 steps from the 13 of 40 not refused, no NaN, and one divergence, the segmented kind's own:
    draw 36 turns a finger segment at 100 rad/s, past that kind's 90 rad/s limit (as on the thesis
    tissue above; the tissue has no part in it). Any other divergence fails."""
    ran, refused, problems = _fuzz("SoftGrasp-v5", 40, {}, coupling="thesis")
    assert ran >= 1000 and refused < 35, (ran, refused)
    assert all(fingers == "segmented" and "finger segment turning" in why for _, fingers, why in problems), problems
