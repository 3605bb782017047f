"""The finger interface's contract, for every kind in FINGERS: it builds with a config of its own,
every setting of that config is validated, the scripted policy lifts and holds the cylinder with
it, it is deterministic and reset leaves no trace, an rgb_array frame shows what it reports to
draw, and a blown-up state ends the episode cleanly. A new kind gets all of this by its registry
entry alone; kind-specific physics lives in each kind's own test file."""

from __future__ import annotations

import math
from dataclasses import fields

import numpy as np
import pytest

from softgrasp_env.accuracy import GraspPlan, run_grasp
from softgrasp_env.fingers import FINGERS, FingerConfig
from softgrasp_env.render import SceneRenderer
from softgrasp_env.scene import GraspScene, SceneConfig
from tests.helpers import assert_same, rollout, run_episode, soft_physics

SLOW_KINDS = {"fem"}
"""pybullet's FEM pads run at a few env steps per second (8 substeps of explicit elasticity):
their whole-episode checks run in the slow selection only."""


def _kinds(*, slow_too: bool = True):
    return [pytest.param(name, marks=pytest.mark.slow) if slow_too and name in SLOW_KINDS else name
            for name in FINGERS if slow_too or name not in SLOW_KINDS]  # fmt: skip


@pytest.mark.parametrize("name", FINGERS)
def test_a_kind_builds_from_its_name_or_its_config(name):
    kind = FINGERS[name]
    cfg = SceneConfig(fingers=name)
    assert type(cfg.fingers) is kind.config_type and cfg.kind is kind
    assert cfg.fingers == name and cfg.fingers != "none of them"  # a config reads as its kind's name
    assert SceneConfig(fingers=kind.config_type()) == cfg
    assert cfg.pad_thickness == kind.pad_thickness(cfg.fingers, cfg.tissue) >= 0.0
    assert cfg.soft is kind.has_tissue
    sc = GraspScene(cfg)
    try:
        assert isinstance(sc.fingers, kind)
        links = sc.fingers.finger_links
        assert links[0][0] == 0 and links[1][0] == 1  # each finger's core first
        for _ in range(5):  # fingers open around the cylinder's top: nothing touches
            sc.step()
            assert sc.divergence() is None
        np.testing.assert_array_equal(sc.finger_forces(), [0.0, 0.0])
        assert sc.penetration() == (0.0, 0.0)
        drawn = [v for v in sc.visuals() if v.kind == "box" and v.body == sc.gripper.body and v.link in (0, 1)]
        assert len(drawn) == 2  # every kind draws its cores
    finally:
        sc.close()


def _bad_values(value):
    if isinstance(value, bool):
        return ["yes"]
    if isinstance(value, (int, float)):
        return [math.nan, "1"]
    return ["no such setting", 7]


@pytest.mark.parametrize("name", FINGERS)
def test_every_setting_of_a_kind_is_validated(name):
    cls = FINGERS[name].config_type
    assert issubclass(cls, FingerConfig) and cls.kind == name
    for f in fields(cls):
        for bad in _bad_values(getattr(cls(), f.name)):
            with pytest.raises(ValueError, match=rf"{cls.__name__}\.{f.name}"):
                cls(**{f.name: bad})
    with pytest.raises(ValueError, match="fingers must be one of"):
        SceneConfig(fingers=name + "-x")


@pytest.mark.parametrize(("name", "physics"), [
    *(pytest.param(name, "thesis", marks=[pytest.mark.slow] if name in SLOW_KINDS else []) for name in FINGERS),
    ("tissue", "v5")])  # fmt: skip
def test_the_scripted_policy_lifts_and_holds(name, physics, make_env, scripted):
    """The gentle start (aligned fingers, where every kind holds; SoftGraspEasy-v4 with the thesis
    tissue, TISSUE_V3, and the tissue on the soft ids' latest physics): the cylinder is lifted past
    the success height and held to the end, nothing diverges on the way."""
    env_id, keywords = soft_physics("SoftGraspEasy", physics)
    env = make_env(env_id, fingers=name, **keywords)
    ep = run_episode(env, scripted, seed=3, on_step=lambda o, r, term, trunc, info: _healthy(info))
    assert ep.steps == 100 and ep.success and ep.successes >= 40
    assert ep.info["lift_height"] >= 0.05


def _healthy(info) -> None:
    assert not info["diverged"], info["divergence"]


@pytest.mark.parametrize("name", _kinds())
def test_the_scene_level_grasp_holds_without_slip(name):
    plan = GraspPlan()
    sc = GraspScene(SceneConfig(fingers=name))
    try:
        rec = run_grasp(sc, plan)
    finally:
        sc.close()
    assert rec.held(plan) and rec.holds_without_slip(plan)


@pytest.mark.parametrize("name", FINGERS)
def test_same_seed_same_trajectory_and_reset_leaves_no_trace(name, make_env):
    steps = 1 if name in SLOW_KINDS else 15
    a = make_env("SoftGrasp-v5", fingers=name)
    b = make_env("SoftGrasp-v5", fingers=name)
    run_a = rollout(a, seed=11, steps=steps, action_seed=5)
    rollout(b, seed=3, steps=steps, action_seed=9)  # b lives through another episode first
    run_b = rollout(b, seed=11, steps=steps, action_seed=5)
    assert_same(run_a, run_b)
    assert a.unwrapped.scene.client.getNumBodies() == b.unwrapped.scene.client.getNumBodies()


def _changed_pixels(a: np.ndarray, b: np.ndarray) -> int:
    return int((np.abs(a.astype(int) - b.astype(int)).max(axis=-1) > 8).sum())


@pytest.mark.parametrize("name", FINGERS)
def test_a_frame_shows_what_the_kind_reports(name):
    """Every visual of the kind is drawn: hiding its cores, and then whatever else it adds
    (particles, segments, pad nodes), each changes the picture."""
    sc = GraspScene(SceneConfig(fingers=name))
    renderer = SceneRenderer(160, 120)
    try:
        visuals = sc.visuals()
        full = renderer.render(sc)
        assert full.shape == (120, 160, 3) and full.dtype == np.uint8
        cores = [v for v in visuals if v.kind == "box" and v.body == sc.gripper.body and v.link in (0, 1)]
        extra = [v for v in visuals[len(visuals) - len(sc.fingers.visuals()):] if not any(v is c for c in cores)]
        assert bool(extra) is (not name.startswith("rigid"))  # the rigid kinds draw the bare cores only
        assert len(renderer.particle_bodies) == sum(len(v.radii) for v in extra if v.kind == "points")
        for hidden in (cores, extra):
            if not hidden:
                continue
            sc.visuals = lambda hidden=hidden: [v for v in visuals if not any(v is h for h in hidden)]
            renderer.invalidate()
            assert _changed_pixels(renderer.render(sc), full) > 20
    finally:
        renderer.close()
        sc.close()


@pytest.mark.parametrize("name", FINGERS)
def test_a_blown_up_state_ends_the_episode_with_a_finite_observation(name, make_env):
    env = make_env("SoftGraspEasy-v5", fingers=name)
    obs0, _ = env.reset(seed=0)
    obs1, *_ = env.step(np.zeros(4, dtype=np.float32))
    sc = env.unwrapped.scene
    sc.client.resetBaseVelocity(sc.cylinder, [math.nan, 0.0, 0.0], [0.0, 0.0, 0.0])
    obs, reward, term, trunc, info = env.step(np.zeros(4, dtype=np.float32))
    assert term and info["diverged"] and info["divergence"] and not info["is_success"] and reward == 0.0
    assert_same(obs, obs1)  # the last finite observation
    assert_same(env.reset(seed=0)[0], obs0)  # and reset builds a healthy world again
