"""gym.make's keywords, checked in one place: the env card's table lists every one, a name the env
does not take is a TypeError naming the known ones, and the corners of the ranges are checked
without building a scene."""

from __future__ import annotations

import dataclasses
import inspect

import gymnasium as gym
import pytest

from softgrasp_env.arguments import GROUPS, KEYWORDS, EnvArguments, EnvPlan, argument_table
from softgrasp_env.env import SoftGraspEnv
from softgrasp_env.registration import TISSUE_V3


def test_the_card_lists_every_argument_once():
    table = argument_table()
    names = [k.name for k in KEYWORDS]
    assert len(names) == len(set(names)) == len(table.splitlines()) - 2
    for name in names:
        assert table.count(f"| `{name}` |") == 1 and f"| `{name}` |" in SoftGraspEnv.__doc__


def test_every_keyword_reaches_its_config_and_its_default_is_the_configs():
    """gym.make's flat keywords go into the nested configs: a keyword that is a config's field
    keeps that field's default (the table cannot drift from the configs)."""
    args = EnvArguments.from_kwargs()
    for k in KEYWORDS:
        assert k.group in GROUPS, k
    from softgrasp_env.arguments import _FLAT

    for name, (group, attr) in _FLAT.items():
        default = next(k.default for k in KEYWORDS if k.name == name)
        if default is not None:
            assert getattr(getattr(args, group), attr) == default, name


def test_the_configs_are_frozen_and_not_changed_after_they_are_made():
    args = EnvArguments.from_kwargs(carry_frequency=[1.5, 2.0], tactile=[2, 3], fingers="rigid")
    assert args.carry_test.frequency == (1.5, 2.0) and args.observation.tactile == (2, 3)
    for name in GROUPS:
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(args, name, None)
    with pytest.raises(dataclasses.FrozenInstanceError):
        args.control.arm_speed = 1.0  # type: ignore[misc]
    import softgrasp_env.arguments as module

    assert "object.__setattr__" not in inspect.getsource(module)


def test_each_config_validates_itself():
    from softgrasp_env.arguments import CameraConfig, CarryConfig, ControlConfig, LiftConfig
    from softgrasp_env.tasks import StartRanges

    with pytest.raises(ValueError, match="arm_speed must be in"):
        ControlConfig(arm_speed=3.0)
    with pytest.raises(ValueError, match=r"carry_frequency must be \(low, high\) with low <= high"):
        CarryConfig(frequency=(3.0, 1.0))
    with pytest.raises(ValueError, match="render_camera must be one of"):
        CameraConfig(mode="orbit")
    with pytest.raises(ValueError, match="start must be one of"):
        LiftConfig(start="fly")
    with pytest.raises(ValueError, match="yaw_range must be in"):
        StartRanges(0.07, 0.005, 1.0, 0.15, 0.0, 0.0, 0.0)


def test_the_old_flat_attributes_read_with_a_warning():
    args = EnvArguments.from_kwargs()
    with pytest.warns(DeprecationWarning, match=r"EnvArguments\.finger_force is deprecated, use "
                                                r"EnvArguments\.control\.finger_force"):  # fmt: skip
        assert args.finger_force == args.control.finger_force == 3.0


def test_an_unknown_argument_is_a_type_error_naming_the_known_ones():
    with pytest.raises(TypeError, match=r"unknown argument\(s\) \['cylinder_mas'\].*'cylinder_mass'"):
        gym.make("SoftGrasp-v5", cylinder_mas=0.2)


def test_the_arguments_make_the_scene_the_task_and_the_steps():
    args = EnvArguments.from_kwargs(fingers="rigid", cylinder_mass=0.2, control_frequency=40.0, start="easy")
    plan = EnvPlan.of(args)
    assert plan.scene.fingers == "rigid" and plan.scene.cylinder_mass == 0.2 and plan.substeps == 6
    assert args.carry_test.on is False and plan.obs_names[-1] == "gripper_yaw"  # the easy start has no carry
    assert type(plan.make_task()).__name__ == "EasyTask"
    assert type(EnvPlan.of(EnvArguments.from_kwargs()).make_task()).__name__ == "CarryTest"


def test_range_corners_are_checked_without_building_scenes(monkeypatch):
    import softgrasp_env.scene.scene as scene_module

    def no_scene(*a, **k):
        raise AssertionError("a scene was built")

    monkeypatch.setattr(scene_module.GraspScene, "__init__", no_scene)
    EnvPlan.of(EnvArguments.from_kwargs(cylinder_radius_range=0.005, yaw_range=0.5))
    with pytest.raises(ValueError, match="the randomisation ranges reach a scene that cannot start"):
        EnvPlan.of(EnvArguments.from_kwargs(cylinder_radius=0.04, cylinder_radius_range=0.01, jaw_wedge_range=0.5))


def test_the_contact_cones_reach_the_tissue_model_and_bad_values_are_named():
    """tissue_contact_cone goes to TissueConfig.contact_cone (default False, the patch law) and into
    the solver's model per body (on the patch law's SoftGraspEasy-v4 with the thesis tissue,
    TISSUE_V3: under Coulomb per contact there is no patch to bound); anything but a bool is a
    ValueError naming the field."""
    assert EnvArguments.from_kwargs().physics.tissue.contact_cone is False
    assert EnvArguments.from_kwargs(tissue_contact_cone=True).physics.tissue.contact_cone is True
    env = gym.make("SoftGraspEasy-v4", tissue_contact_cone=True, **TISSUE_V3)
    try:
        env.reset(seed=0)
        assert env.unwrapped.scene.world.solver.model.body_contact_cone.tolist() == [True, True]
    finally:
        env.close()
    with pytest.raises(ValueError, match="TissueConfig.contact_cone must be a bool, got 'yes'"):
        EnvArguments.from_kwargs(tissue_contact_cone="yes")


def test_the_material_keywords_reach_the_tissue_and_auto_layers_follow_the_final_density():
    """group_energy, hourglass_stiffness and layers go to TissueConfig; layers='auto' (given, or a
    preset's) is resolved for the density the tissue ends up with; bad values are named."""
    t = EnvArguments.from_kwargs(group_energy="continuum", hourglass_stiffness=0.5, layers=3).physics.tissue
    assert (t.group_energy, t.hourglass_stiffness, t.layers) == ("continuum", 0.5, 3)
    assert EnvArguments.from_kwargs(layers="auto", particle_density=256_000.0).physics.tissue.layers == 4
    # the preset's 'auto' follows a density given beside it; a layers count given wins
    conv = EnvArguments.from_kwargs(preset="converged").physics.tissue
    assert (conv.particle_density, conv.layers, conv.group_energy) == (64_000.0, 2, "continuum")
    assert EnvArguments.from_kwargs(preset="converged", particle_density=256_000.0).physics.tissue.layers == 4
    assert EnvArguments.from_kwargs(preset="converged", layers=1).physics.tissue.layers == 1
    # a whole TissueConfig given is taken as it is (its own layers)
    from softgrasp_env.config import TissueConfig

    assert EnvArguments.from_kwargs(preset="converged", tissue=TissueConfig()).physics.tissue.layers == 1
    for bad, match in ((dict(layers="two"), "layers must be an int from 1 to 8 or 'auto', got 'two'"),
                       (dict(layers=True), "layers must be an int"),
                       (dict(layers=9), "TissueConfig.layers"),
                       (dict(group_energy="fem"), "group_energy must be one of"),
                       (dict(hourglass_stiffness=0.5), "acts on the continuum group energy only")):  # fmt: skip
        with pytest.raises(ValueError, match=match):
            EnvArguments.from_kwargs(**bad)
