"""Validation of TissueConfig, SimConfig and SceneConfig (a finger kind's own settings are checked
by tests/fingers/test_contract.py; the spellings before 0.3 by tests/test_deprecations.py)."""

from __future__ import annotations

import dataclasses
import math

import pytest

from softgrasp_env.config import COUPLING_MODES, SimConfig, TissueConfig, field_names, kinetic_friction, replace
from softgrasp_env.scene import SceneConfig

NAN = float("nan")
INF = float("inf")


def test_defaults_construct():
    t, s, c = TissueConfig(), SimConfig(), SceneConfig()
    assert isinstance(c.tissue, TissueConfig) and isinstance(c.sim, SimConfig)
    assert t.friction_kinetic is None and kinetic_friction(t) == t.friction_static == 0.9  # one coefficient, as pybullet
    assert s.coupling in COUPLING_MODES
    assert c.soft is True


def test_spacing_follows_density():
    assert TissueConfig().spacing == pytest.approx(0.0158, rel=1e-3)  # 4,000 per m^2
    assert TissueConfig(particle_density=10_000.0).spacing == pytest.approx(0.01)
    assert TissueConfig(particle_density=40_000.0).spacing == pytest.approx(0.005)
    assert TissueConfig(particle_density=2_500.0).spacing == pytest.approx(0.02)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(mass_density=3e4), "mass_density"),  # too heavy: tore under random actions
        (dict(group_size=2), "group_size"),
        (dict(group_size=17), "group_size"),  # bigger groups sagged and tore
        (dict(group_size=8.0), "group_size"),
        (dict(group_size=True), "group_size"),
        (dict(extrude=-1.0), "extrude"),
        (dict(extrude=0.0), "extrude"),
        (dict(extrude=NAN), "extrude"),
        (dict(extrude=INF), "extrude"),
        (dict(particle_density=50.0), "particle_density"),
        (dict(particle_density=NAN), "particle_density"),
        (dict(mass_density=0.0), "mass_density"),
        (dict(radius_scale=0.0), "radius_scale"),
        (dict(radius_scale=2.5), "radius_scale"),
        (dict(normal_radius=0.0), "normal_radius"),
        (dict(friction_static=-0.1, friction_kinetic=0.0), "friction_static"),
        (dict(friction_static=NAN), "friction_static"),
        (dict(friction_kinetic=0.95), "friction_kinetic"),
        (dict(friction_static=0.3, friction_kinetic=0.31), "friction_kinetic"),
        (dict(stiffness=0.5), "stiffness"),  # the retired per-step material's
        (dict(material="per_step"), "material"),  # retired: names 0.6.0
        (dict(shear_modulus=999.0), "shear_modulus"),
        (dict(max_deviation=0.031), "max_deviation"),  # past the 3 cm that counts as torn
        (dict(max_deviation=0.0), "max_deviation"),
        (dict(shear_modulus=1.1e6), "shear_modulus"),
        (dict(shear_modulus=NAN), "shear_modulus"),
        (dict(material="linear"), "material"),
    ],
)
def test_tissue_config_rejects(kwargs, field):
    with pytest.raises(ValueError, match=rf"TissueConfig\.{field}\b"):
        TissueConfig(**kwargs)


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(mass_density=1e4),
        dict(mass_density=100),  # int for a float field is fine
        dict(group_size=4),
        dict(group_size=16),
        dict(particle_density=100.0),
        dict(particle_density=1e7),
        dict(extrude=0.1),
        dict(friction_static=0.5, friction_kinetic=0.5),  # equal coefficients allowed
        dict(friction_static=0.0, friction_kinetic=0.0),
        dict(shear_modulus=1e3),
        dict(shear_modulus=1e6),
        dict(max_deviation=1e-3),
        dict(max_deviation=0.03),
    ],
)
def test_tissue_config_accepts_boundaries(kwargs):
    cfg = TissueConfig(**kwargs)
    for k, v in kwargs.items():
        assert getattr(cfg, k) == v


def test_the_materials_numbers_are_its_fields():
    """shear_modulus and max_deviation are numbers, their defaults the package's; the names that
    read them through None before 0.7 (modulus, deviation_limit, =None) warn and agree."""
    from softgrasp_env.config import DEFAULT_MAX_DEVIATION, DEFAULT_SHEAR_MODULUS

    tissue = TissueConfig()
    assert (tissue.shear_modulus, tissue.max_deviation) == (DEFAULT_SHEAR_MODULUS, DEFAULT_MAX_DEVIATION)
    assert TissueConfig(shear_modulus=8e3, max_deviation=0.01).shear_modulus == 8e3
    with pytest.warns(DeprecationWarning, match="shear_modulus"):
        assert TissueConfig(shear_modulus=8e3).modulus == 8e3
    with pytest.warns(DeprecationWarning, match="max_deviation"):
        assert TissueConfig(max_deviation=0.01).deviation_limit == 0.01
    with pytest.warns(DeprecationWarning, match="shear_modulus=None"):
        assert TissueConfig(shear_modulus=None) == tissue
    with pytest.raises(ValueError, match="TissueConfig.shear_modulus"):
        TissueConfig(shear_modulus=10.0)


def test_the_retired_material_keywords():
    """material="compliant" (the only material since 0.6.0) warns and is the default; the per-step
    material and its stiffness name release 0.6.0, which has them."""
    with pytest.warns(DeprecationWarning, match="material='compliant' is deprecated"):
        assert TissueConfig(material="compliant") == TissueConfig()
    with pytest.raises(ValueError, match=r"TissueConfig\.material='per_step' was retired; `pip install softgrasp-env==0\.6\.0`"):
        TissueConfig(material="per_step")
    with pytest.raises(ValueError, match=r"TissueConfig\.stiffness=0\.5 .* was retired.*==0\.6\.0"):
        TissueConfig(stiffness=0.5)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(dt=0.0), "dt"),
        (dict(dt=0.1), "dt"),
        (dict(dt=0.05), "dt"),  # tore the tissue at the second step (a former bug)
        (dict(dt=1.0 / 40.0), "dt"),
        (dict(dt=NAN), "dt"),
        (dict(iterations=0), "iterations"),
        (dict(iterations=201), "iterations"),
        (dict(iterations=4.0), "iterations"),
        (dict(iterations=True), "iterations"),
        (dict(rotation_iterations=0), "rotation_iterations"),
        (dict(rotation_iterations=False), "rotation_iterations"),
        (dict(gravity=-9.81), "gravity"),
        (dict(gravity=INF), "gravity"),
        (dict(damping=-0.1), "damping"),
        (dict(coupling="x"), "coupling"),
        (dict(coupling="Thesis"), "coupling"),
        (dict(orientation="x"), "orientation"),
        (dict(contact_margin=-0.001), "contact_margin"),
        (dict(contact_margin=0.2), "contact_margin"),
    ],
)
def test_sim_config_rejects(kwargs, field):
    with pytest.raises(ValueError, match=rf"SimConfig\.{field}\b"):
        SimConfig(**kwargs)


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(coupling="consistent"),
        dict(coupling="thesis"),
        dict(orientation="goal"),
        dict(iterations=1),
        dict(iterations=200),
        dict(gravity=0.0),
        dict(damping=0.0),
        dict(dt=1.0 / 60.0),
        dict(dt=1e-5),
    ],
)
def test_sim_config_accepts(kwargs):
    cfg = SimConfig(**kwargs)
    for k, v in kwargs.items():
        assert getattr(cfg, k) == v


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(cylinder_radius=-1.0), "cylinder_radius"),
        (dict(cylinder_radius=0.001), "cylinder_radius"),
        (dict(cylinder_radius=NAN), "cylinder_radius"),
        (dict(cylinder_height=1.0), "cylinder_height"),
        (dict(cylinder_mass=0.0), "cylinder_mass"),
        (dict(yaw=2.0), "yaw"),
        (dict(yaw=-1.0), "yaw"),
        (dict(lateral_offset=0.5), "lateral_offset"),
        (dict(finger_force=0.0), "finger_force"),
        (dict(finger_speed=0.0), "finger_speed"),
        (dict(arm_force=0.0), "arm_force"),
        (dict(ground_friction=-0.5), "ground_friction"),
        (dict(finger_half_extents=(0.008, 0.02)), "finger_half_extents"),
        (dict(finger_half_extents=(0.008, 0.0, 0.03)), r"finger_half_extents\[1\]"),
        (dict(finger_half_extents=(0.008, 0.02, NAN)), r"finger_half_extents\[2\]"),
        (dict(fingers="soft"), "fingers"),
        (dict(fingers=True), "fingers"),
        (dict(tissue=SimConfig()), "tissue"),
        (dict(sim=TissueConfig()), "sim"),
        (dict(sim=None), "sim"),
    ],
)
def test_scene_config_rejects(kwargs, field):
    with pytest.raises(ValueError, match=rf"SceneConfig\.{field}"):
        SceneConfig(**kwargs)


def test_scene_config_accepts():
    cfg = SceneConfig(fingers="rigid", yaw=math.pi / 4, lateral_offset=-0.1,
                      tissue=TissueConfig(shear_modulus=2e4),
                      sim=SimConfig(coupling="consistent"))  # fmt: skip
    assert cfg.soft is False
    assert cfg.yaw == pytest.approx(math.pi / 4)
    assert cfg.tissue.shear_modulus == 2e4
    assert cfg.sim.coupling == "consistent"


def test_nested_configs_validate_on_their_own():
    with pytest.raises(ValueError, match=r"TissueConfig\.shear_modulus"):
        SceneConfig(tissue=TissueConfig(shear_modulus=2e6))


def test_error_message_names_the_range_and_the_value():
    with pytest.raises(ValueError) as info:
        TissueConfig(shear_modulus=1.5)
    msg = str(info.value)
    assert "[1000.0, 1000000.0]" in msg and "1.5" in msg
    with pytest.raises(ValueError) as info:
        SimConfig(iterations=0)
    assert "[1, 200]" in str(info.value) and "0" in str(info.value)


def test_configs_are_frozen_and_replace_revalidates():
    cfg = TissueConfig()
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.max_deviation = 0.01  # type: ignore[misc]
    assert replace(cfg, max_deviation=0.01).max_deviation == 0.01
    with pytest.raises(ValueError, match=r"TissueConfig\.max_deviation"):
        replace(cfg, max_deviation=0.0)
    with pytest.raises(ValueError, match=r"TissueConfig\.shear_modulus"):
        replace(TissueConfig(), shear_modulus=10.0)
    with pytest.raises(ValueError, match=r"SimConfig\.dt"):
        replace(SimConfig(), dt=-1.0)


def test_default_factories_give_fresh_equal_configs():
    a, b = SceneConfig(), SceneConfig()
    assert a.tissue == b.tissue == TissueConfig()
    assert a.sim == b.sim == SimConfig()


def test_field_names():
    names = field_names(TissueConfig)
    assert names[:4] == ("particle_density", "extrude", "layers", "group_size")
    assert set(names) == {f.name for f in dataclasses.fields(TissueConfig)}
    assert "tissue" in field_names(SceneConfig) and "sim" in field_names(SceneConfig)
    assert "coupling" in field_names(SimConfig)
