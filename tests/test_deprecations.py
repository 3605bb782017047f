"""The spellings before 0.3 keep working: each gives the same configuration as its new spelling
and says so with a DeprecationWarning (softgrasp_env/validation.py's ``deprecated``), and a
setting of another finger kind than the one chosen is an error, not silently lost. The rest of the
tests use the new spellings only."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import pytest

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.config import TissueConfig
from softgrasp_env.fingers import FINGERS, FemConfig, RigidConfig, SegmentedConfig, TissueFingerConfig
from softgrasp_env.scene import SceneConfig

# --- gym.make ---------------------------------------------------------------------------------------


def _args(env_id: str, **kwargs):
    """The validated arguments of an env (no scene is built before reset)."""
    env = gym.make(env_id, **kwargs)
    try:
        return env.unwrapped.args
    finally:
        env.close()


def _plan(args):
    from softgrasp_env.arguments import EnvPlan

    return EnvPlan.of(args)


@pytest.mark.parametrize(
    "env_id, old, new",
    [
        ("SoftGrasp-v5", dict(soft=False), dict(fingers="rigid")),
        ("SoftGraspRigid-v3", dict(soft=True), dict(fingers="tissue")),
        ("SoftGrasp-v5", dict(soft=True), dict(fingers="tissue")),
        ("SoftGrasp-v5", dict(soft=False, fingers="segmented"), dict(fingers="segmented")),  # a kind soft never named
        ("SoftGrasp-v5", dict(tissue_density=5000.0), dict(particle_density=5000.0)),
        ("SoftGraspRigid-v3", dict(soft=True, tissue_density=5000.0), dict(fingers="tissue", particle_density=5000.0)),
        ("SoftGrasp-v5", dict(gripper_speed=0.14), dict(arm_speed=0.14)),
        ("SoftGrasp-v5", dict(friction_dynamic=0.7), dict(friction_kinetic=0.7)),
        ("SoftGrasp-v5", dict(task="easy"), dict(start="easy")),
    ],
)
def test_gym_make_takes_the_old_arguments_with_a_warning(env_id, old, new):
    with pytest.warns(DeprecationWarning, match=r"the (soft|tissue_density|gripper_speed|friction_dynamic|task)= "
                                                r"argument.* is deprecated, use "):  # fmt: skip
        was = _args(env_id, **old)
    now = _args(env_id, **new)
    assert was == now and _plan(was).scene == _plan(now).scene and was.physics.tissue == now.physics.tissue
    assert _plan(was).scene.fingers == new.get("fingers", "tissue")


def test_old_gym_make_arguments_that_cannot_mean_one_thing_are_refused():
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="soft must be a bool"):
        gym.make("SoftGrasp-v5", soft="no")
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="soft=True contradicts fingers="):
        gym.make("SoftGrasp-v5", soft=True, fingers=RigidConfig())
    with pytest.raises(TypeError, match="not both"):
        gym.make("SoftGrasp-v5", tissue_density=5000.0, particle_density=5000.0)
    with pytest.raises(TypeError, match=r"give start= \(the new name of task=\), not both"):
        gym.make("SoftGrasp-v5", task="easy", start="easy")


def test_gym_make_takes_a_kinds_own_argument_only_with_that_kind():
    """``tissue_faces=`` and ``fem_resolution=`` are the kinds' settings as gym.make arguments: the
    same as the kind's config, and an error with another kind (it would be lost)."""
    assert _args("SoftGrasp-v5", tissue_faces="all") == _args("SoftGrasp-v5", fingers=TissueFingerConfig(faces="all"))
    assert _args("SoftGrasp-v5", fingers="fem", fem_resolution="fine") == _args(
        "SoftGrasp-v5", fingers=FemConfig(resolution="fine"))  # fmt: skip
    with pytest.raises(ValueError, match="tissue_faces is a setting of fingers='tissue', but fingers='rigid'"):
        gym.make("SoftGraspRigid-v3", tissue_faces="all")
    with pytest.raises(ValueError, match="fem_resolution is a setting of fingers='fem', but fingers='tissue'"):
        gym.make("SoftGrasp-v5", fem_resolution="fine")


# --- TissueConfig -------------------------------------------------------------------------------------


@pytest.mark.parametrize("old, new, value", [("density", "particle_density", 5000.0),
                                             ("tissue_density", "mass_density", 1200.0),
                                             ("friction_dynamic", "friction_kinetic", 0.7)])  # fmt: skip
def test_tissue_config_takes_and_reads_the_old_names_with_a_warning(old, new, value):
    with pytest.warns(DeprecationWarning, match=rf"TissueConfig\({old}=\.\.\.\) is deprecated, use TissueConfig\({new}="):
        cfg = TissueConfig(**{old: value})
    assert cfg == TissueConfig(**{new: value})
    with pytest.warns(DeprecationWarning, match=rf"TissueConfig\.{old} is deprecated, use TissueConfig\.{new}"):
        assert getattr(cfg, old) == value == getattr(cfg, new)
    with pytest.raises(TypeError, match="not both"):
        TissueConfig(**{old: value, new: value})


def test_a_bad_value_under_an_old_tissue_name_is_reported_under_the_new_one():
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match=r"TissueConfig\.particle_density\b"):
        TissueConfig(density=50.0)
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match=r"TissueConfig\.mass_density\b"):
        TissueConfig(tissue_density=3e4)


# --- SceneConfig's flat finger settings ------------------------------------------------------------

LEGACY = [
    ("finger_segments", 4, SegmentedConfig(segments=4)),
    ("segment_stiffness_pitch", 0.2, SegmentedConfig(stiffness_pitch=0.2)),
    ("segment_stiffness_yaw", 0.02, SegmentedConfig(stiffness_yaw=0.02)),
    ("segment_damping_pitch", 0.001, SegmentedConfig(damping_pitch=0.001)),
    ("segment_damping_yaw", 1e-4, SegmentedConfig(damping_yaw=1e-4)),
    ("segment_spring", "torque", SegmentedConfig(spring="torque")),
    ("fem_resolution", "fine", FemConfig(resolution="fine")),
    ("fem_substeps", 4, FemConfig(substeps=4)),
    ("tissue_faces", "all", TissueFingerConfig(faces="all")),
]
"""(the flat SceneConfig field of 0.2, a value, the kind's config it means)."""


@pytest.mark.parametrize("old, value, new", LEGACY, ids=[c[0] for c in LEGACY])
def test_scene_config_takes_and_reads_a_flat_finger_setting_with_a_warning(old, value, new):
    with pytest.warns(DeprecationWarning, match=rf"SceneConfig\({old}=\.\.\.\) is deprecated, use SceneConfig\(fingers="
                                                rf"{type(new).__name__}\("):  # fmt: skip
        cfg = SceneConfig(fingers=new.kind, **{old: value})
    assert cfg == SceneConfig(fingers=new)
    assert type(cfg.fingers) is type(new) and cfg.fingers == new
    with pytest.warns(DeprecationWarning, match=rf"SceneConfig\.{old} is deprecated, use SceneConfig\.fingers\."):
        assert getattr(cfg, old) == value
    # dataclasses.replace passes it on as well (the old tests' way of varying one setting)
    with pytest.warns(DeprecationWarning):
        assert dataclasses.replace(SceneConfig(fingers=new.kind), **{old: value}) == cfg


@pytest.mark.parametrize("old, value, new", LEGACY, ids=[c[0] for c in LEGACY])
def test_a_flat_setting_of_another_kind_than_fingers_is_an_error(old, value, new):
    other = "rigid" if new.kind != "rigid" else "tissue"
    with pytest.warns(DeprecationWarning), pytest.raises(
            ValueError, match=rf"SceneConfig\.{old} is a setting of fingers='{new.kind}', but fingers='{other}'"):  # fmt: skip
        SceneConfig(fingers=other, **{old: value})


def test_flat_settings_combine_and_the_default_kind_takes_only_its_own():
    with pytest.warns(DeprecationWarning):
        cfg = SceneConfig(fingers="segmented", finger_segments=4, segment_spring="torque")
    assert cfg.fingers == SegmentedConfig(segments=4, spring="torque")
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="but fingers='tissue'"):
        SceneConfig(finger_segments=4)  # fingers left at its default, the tissue
    with pytest.warns(DeprecationWarning):
        assert SceneConfig(tissue_faces="all").fingers == TissueFingerConfig(faces="all")
    # reading another kind's flat setting gives that kind's default, as the flat field of 0.2 held it
    with pytest.warns(DeprecationWarning):
        assert SceneConfig(fingers="rigid").finger_segments == SegmentedConfig().segments


@pytest.mark.parametrize("old, new, value", [("finger_max_opening", "finger_stroke", 0.07), ("palm_force", "arm_force", 60.0)])
def test_scene_config_takes_and_reads_the_old_names_with_a_warning(old, new, value):
    with pytest.warns(DeprecationWarning, match=rf"SceneConfig\({old}=\.\.\.\) is deprecated, use SceneConfig\({new}="):
        cfg = SceneConfig(fingers="rigid", **{old: value})
    assert cfg == SceneConfig(fingers="rigid", **{new: value})
    with pytest.warns(DeprecationWarning, match=rf"SceneConfig\.{old} is deprecated, use SceneConfig\.{new}"):
        assert getattr(cfg, old) == value == getattr(cfg, new)


def test_the_default_arm_force_is_still_the_grippers_weight_plus_the_push():
    """``arm_force=None`` (the default, as ``palm_force=None`` was): the force in force is the
    gripper's weight plus ARM_PUSH."""
    from softgrasp_env.scene import arm_force_limit
    from softgrasp_env.scene.config import ARM_PUSH

    cfg = SceneConfig()
    assert cfg.arm_force is None
    assert arm_force_limit(cfg) == ARM_PUSH + (cfg.palm_mass + 2 * cfg.finger_mass) * cfg.sim.gravity
    assert arm_force_limit(SceneConfig(arm_force=60.0)) == 60.0


@pytest.mark.parametrize("old, new", [("TASKS", "STARTS"), ("LeastSqueeze", "GripForceTask")])
def test_the_tasks_old_names_import_with_a_warning(old, new):
    import softgrasp_env.tasks as tasks

    with pytest.warns(DeprecationWarning, match=rf"softgrasp_env\.tasks\.{old} is deprecated, use softgrasp_env\.tasks\.{new}"):
        assert getattr(tasks, old) is getattr(tasks, new)


def test_gripper_actions_take_max_force_with_a_warning():
    from softgrasp_env.scene import GripperActions, Workspace

    ws = Workspace.of(SceneConfig(fingers="rigid"))
    with pytest.warns(DeprecationWarning, match=r"GripperActions\(max_force=\.\.\.\) is deprecated"):
        old = GripperActions(0.15, 20.0, ws, 0.06, finger="force", max_force=6.0)
    assert old.finger_force == 6.0 == GripperActions(0.15, 20.0, ws, 0.06, finger="force", finger_force=6.0).finger_force


# --- moved names ------------------------------------------------------------------------------------


def test_names_moved_out_of_softgrasp_env_config_still_import_with_a_warning():
    with pytest.warns(DeprecationWarning, match=r"softgrasp_env\.config\.SceneConfig moved to softgrasp_env\.scene"):
        from softgrasp_env.config import SceneConfig as Old
    assert Old is SceneConfig
    with pytest.warns(DeprecationWarning, match=r"FINGER_KINDS moved to softgrasp_env\.fingers"):
        from softgrasp_env.config import FINGER_KINDS
    assert FINGER_KINDS == tuple(FINGERS)


def test_the_demo_takes_its_old_density_flags(monkeypatch):
    """``python -m softgrasp_env.demo --density N --tissue-density M`` (0.2's flags) builds the scene
    ``--particle-density N --mass-density M`` does (the scene is captured, not simulated)."""
    from softgrasp_env import demo

    built = []

    class Built(Exception):
        pass

    def capture(cfg, **kwargs):
        built.append(cfg)
        raise Built

    monkeypatch.setattr(demo, "GraspScene", capture)
    for argv in (["--density", "5000", "--tissue-density", "1200"], ["--particle-density", "5000", "--mass-density", "1200"]):
        with pytest.raises(Built):
            demo.main(argv)
    old, new = built
    assert old == new and old.tissue.particle_density == 5000.0 and old.tissue.mass_density == 1200.0


# --- the keywords retired after 0.6.0, when one choice was left ------------------------------------


@pytest.mark.parametrize("kept", [dict(arm="smooth"), dict(tissue_material="compliant"), dict(carry_direction="any")])
def test_the_only_choice_left_warns_and_changes_nothing(kept):
    """``arm="smooth"``, ``tissue_material="compliant"``, ``carry_direction="any"``: what happens
    anyway since the other choices were retired; one DeprecationWarning, the same arguments."""
    with pytest.warns(DeprecationWarning, match=f"{next(iter(kept))}={next(iter(kept.values()))!r} is deprecated") as got:
        old = _args("SoftGrasp-v5", **kept)
    assert len([w for w in got if issubclass(w.category, DeprecationWarning) and "is deprecated" in str(w.message)]) == 1
    assert old == _args("SoftGrasp-v5")


@pytest.mark.parametrize("retired", [dict(arm="jump"), dict(tissue_material="per_step"), dict(carry_direction="across"),
                                     dict(carry_amplitude=0.01), dict(carry_slide_limit=None)])  # fmt: skip
def test_a_retired_choice_names_the_release_that_has_it(retired):
    with pytest.raises(ValueError, match=r"was retired; `pip install softgrasp-env==0\.6\.0` \(git tag v0\.6\.0\)"):
        gym.make("SoftGrasp-v5", **retired)
