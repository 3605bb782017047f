"""Validation of TissueConfig, SimConfig and SceneConfig (a finger kind's own settings are checked
by tests/fingers/test_contract.py; the spellings before 0.3 by tests/test_deprecations.py)."""

from __future__ import annotations

import dataclasses
import math

import pytest

from softgrasp_env.config import COUPLING_MODES, SimConfig, TissueConfig, field_names, replace
from softgrasp_env.scene import SceneConfig

NAN = float("nan")
INF = float("inf")


def test_defaults_construct():
    t, s, c = TissueConfig(), SimConfig(), SceneConfig()
    assert isinstance(c.tissue, TissueConfig) and isinstance(c.sim, SimConfig)
    assert t.friction_dynamic is None and t.friction_kinetic == t.friction_static == 0.9  # one coefficient, as pybullet
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
        (dict(material="per_step", stiffness=0.0), "stiffness"),
        (dict(material="per_step", stiffness=1.5), "stiffness"),
        (dict(material="per_step", stiffness=-0.1), "stiffness"),
        (dict(material="per_step", stiffness=NAN), "stiffness"),
        (dict(material="per_step", stiffness=0.03), "stiffness"),  # too slack: tore under random actions (issue 12)
        (dict(mass_density=3e4), "mass_density"),  # too heavy: tore under random actions
        (dict(group_size=2), "group_size"),
        (dict(group_size=17), "group_size"),  # bigger groups sagged and tore (issue 12)
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
        (dict(friction_static=-0.1, friction_dynamic=0.0), "friction_static"),
        (dict(friction_static=NAN), "friction_static"),
        (dict(friction_dynamic=0.95), "friction_dynamic"),
        (dict(friction_static=0.3, friction_dynamic=0.31), "friction_dynamic"),
        (dict(material="per_step", stiffness="0.5"), "stiffness"),
        (dict(stiffness=0.5), "stiffness"),  # the per-step material's, given to the compliant one
        (dict(material="per_step", shear_modulus=4e3), "shear_modulus"),  # the other way round
        (dict(shear_modulus=999.0), "shear_modulus"),
        (dict(max_deviation=0.031), "max_deviation"),  # past the 3 cm that counts as torn
        (dict(max_deviation=0.0), "max_deviation"),
        (dict(material="per_step", max_deviation=0.02), "max_deviation"),  # the compliant material's
        (dict(shear_modulus=1.1e6), "shear_modulus"),
        (dict(shear_modulus=NAN), "shear_modulus"),
        (dict(material="linear"), "material"),
        (dict(material="per_step", stiffness=True), "stiffness"),
    ],
)
def test_tissue_config_rejects(kwargs, field):
    with pytest.raises(ValueError, match=rf"TissueConfig\.{field}\b"):
        TissueConfig(**kwargs)


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(material="per_step", stiffness=1.0),  # closed upper end
        dict(material="per_step", stiffness=0.1),  # closed lower end
        dict(mass_density=1e4),
        dict(material="per_step", stiffness=1),  # int for a float field is fine
        dict(group_size=4),
        dict(group_size=16),
        dict(particle_density=100.0),
        dict(particle_density=1e7),
        dict(extrude=0.1),
        dict(friction_static=0.5, friction_dynamic=0.5),  # equal coefficients allowed
        dict(friction_static=0.0, friction_dynamic=0.0),
        dict(shear_modulus=1e3),
        dict(shear_modulus=1e6),
        dict(max_deviation=1e-3),
        dict(max_deviation=0.03),
        dict(material="per_step"),
    ],
)
def test_tissue_config_accepts_boundaries(kwargs):
    cfg = TissueConfig(**kwargs)
    for k, v in kwargs.items():
        assert getattr(cfg, k) == v


def test_the_materials_numbers_as_the_solver_reads_them():
    """None means the material's default; the other material's numbers do not apply (inf: no
    strain limit for the per-step material)."""
    from softgrasp_env.config import DEFAULT_MAX_DEVIATION, DEFAULT_SHEAR_MODULUS, DEFAULT_STEP_STIFFNESS

    compliant, per_step = TissueConfig(), TissueConfig(material="per_step")
    assert (compliant.modulus, compliant.deviation_limit) == (DEFAULT_SHEAR_MODULUS, DEFAULT_MAX_DEVIATION)
    assert TissueConfig(shear_modulus=8e3, max_deviation=0.01).modulus == 8e3
    assert TissueConfig(max_deviation=0.01).deviation_limit == 0.01
    assert per_step.step_stiffness == DEFAULT_STEP_STIFFNESS and per_step.deviation_limit == math.inf
    assert TissueConfig(material="per_step", stiffness=0.7).step_stiffness == 0.7


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(dt=0.0), "dt"),
        (dict(dt=0.1), "dt"),
        (dict(dt=0.05), "dt"),  # tore the tissue at the second step (issue 12)
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
        (dict(palm_force=0.0), "palm_force"),
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
                      tissue=TissueConfig(material="per_step", stiffness=0.2),
                      sim=SimConfig(coupling="consistent"))  # fmt: skip
    assert cfg.soft is False
    assert cfg.yaw == pytest.approx(math.pi / 4)
    assert cfg.tissue.stiffness == 0.2
    assert cfg.sim.coupling == "consistent"


def test_nested_configs_validate_on_their_own():
    with pytest.raises(ValueError, match=r"TissueConfig\.stiffness"):
        SceneConfig(tissue=TissueConfig(material="per_step", stiffness=2.0))


def test_error_message_names_the_range_and_the_value():
    with pytest.raises(ValueError) as info:
        TissueConfig(material="per_step", stiffness=1.5)
    msg = str(info.value)
    assert "[0.1, 1.0]" in msg and "1.5" in msg
    with pytest.raises(ValueError) as info:
        SimConfig(iterations=0)
    assert "[1, 200]" in str(info.value) and "0" in str(info.value)


def test_configs_are_frozen_and_replace_revalidates():
    cfg = TissueConfig(material="per_step")
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.stiffness = 0.9  # type: ignore[misc]
    assert replace(cfg, stiffness=0.9).stiffness == 0.9
    with pytest.raises(ValueError, match=r"TissueConfig\.stiffness"):
        replace(cfg, stiffness=0.0)
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
    assert names[:3] == ("particle_density", "extrude", "group_size")
    assert set(names) == {f.name for f in dataclasses.fields(TissueConfig)}
    assert "tissue" in field_names(SceneConfig) and "sim" in field_names(SceneConfig)
    assert "coupling" in field_names(SimConfig)
