"""gym.make's keywords, checked in one place: the env card's table lists every one, a name the env
does not take is a TypeError naming the known ones, and the corners of the ranges are checked
without building a scene."""

from __future__ import annotations

from dataclasses import fields

import gymnasium as gym
import pytest

from softgrasp_env.arguments import EnvArguments, argument_table
from softgrasp_env.env import SoftGraspEnv


def test_the_card_lists_every_argument():
    table = argument_table()
    names = [f.name for f in fields(EnvArguments) if f.init]
    assert len(names) == len(table.splitlines()) - 2
    for name in names:
        assert f"| `{name}` |" in table and f"| `{name}` |" in SoftGraspEnv.__doc__


def test_an_unknown_argument_is_a_type_error_naming_the_known_ones():
    with pytest.raises(TypeError, match=r"unknown argument\(s\) \['cylinder_mas'\].*'cylinder_mass'"):
        gym.make("SoftGrasp-v3", cylinder_mas=0.2)


def test_the_arguments_make_the_scene_the_task_and_the_steps():
    args = EnvArguments.from_kwargs(fingers="rigid", cylinder_mass=0.2, control_frequency=40.0, start="easy")
    assert args.scene.fingers == "rigid" and args.scene.cylinder_mass == 0.2 and args.substeps == 6
    assert args.carry is False and args.obs_names[-1] == "gripper_yaw"  # the easy task has no carry
    assert type(args.make_task()).__name__ == "EasyTask"
    assert type(EnvArguments.from_kwargs().make_task()).__name__ == "CarryTest"


def test_range_corners_are_checked_without_building_scenes(monkeypatch):
    import softgrasp_env.scene.scene as scene_module

    def no_scene(*a, **k):
        raise AssertionError("a scene was built")

    monkeypatch.setattr(scene_module.GraspScene, "__init__", no_scene)
    EnvArguments.from_kwargs(cylinder_radius_range=0.005, yaw_range=0.5)
    with pytest.raises(ValueError, match="the randomisation ranges reach a scene that cannot start"):
        EnvArguments.from_kwargs(cylinder_radius=0.04, cylinder_radius_range=0.01, jaw_wedge_range=0.5)


def test_the_contact_cones_reach_the_tissue_model_and_bad_values_are_named():
    """tissue_contact_cone goes to TissueConfig.contact_cone (default False, the patch law) and into
    the solver's model per body; anything but a bool is a ValueError naming the field."""
    assert EnvArguments.from_kwargs().scene.tissue.contact_cone is False
    assert EnvArguments.from_kwargs(tissue_contact_cone=True).scene.tissue.contact_cone is True
    env = gym.make("SoftGraspEasy-v3", tissue_contact_cone=True)
    try:
        env.reset(seed=0)
        assert env.unwrapped.scene.world.solver.model.body_contact_cone.tolist() == [True, True]
    finally:
        env.close()
    with pytest.raises(ValueError, match="TissueConfig.contact_cone must be a bool, got 'yes'"):
        EnvArguments.from_kwargs(tissue_contact_cone="yes")
