"""The carry test (the -v2 ids, softgrasp_env/tasks/carry.py): for the episode's last 1.5 s the
arm, not the policy, sways the palm 1 cm at 2 Hz across the jaw, and success needs the cylinder
still held once it is over. A rigid two-point grasp swings out under it, the tissue holds."""

from __future__ import annotations

from dataclasses import replace

import gymnasium as gym
import numpy as np
import pytest

from softgrasp_env import presets
from softgrasp_env.observation import CARRY_OBS_NAMES
from tests.helpers import obs_vector, run_episode

AXIS_Z = CARRY_OBS_NAMES.index("cyl_axis_z")
LIFT = CARRY_OBS_NAMES.index("lift")
TIME = CARRY_OBS_NAMES.index("time")


def _run(env, policy, *, seed=0, options=None, arm_during_carry=None):
    """One episode (to its time limit or its end); returns (per-step infos, observations with the
    reset's first, max tilt during the carry and at the step after it [deg]). ``arm_during_carry``:
    the action while the last step was carrying, instead of the policy's."""
    infos, observations = [], []

    def act(obs):
        if not observations:
            observations.append(obs)  # the reset's
        if arm_during_carry is not None and infos and infos[-1]["carrying"]:
            return np.asarray(arm_during_carry, np.float32)
        return policy(obs)

    def seen(obs, reward, term, trunc, info):
        infos.append(info)
        observations.append(obs)

    run_episode(env, act, seed=seed, options=options, on_step=seen)
    tilt = max((float(np.degrees(np.arccos(min(1.0, observations[k + 1][AXIS_Z]))))
                for k, info in enumerate(infos) if info["carrying"] or (k > 0 and infos[k - 1]["carrying"])),
               default=0.0)  # fmt: skip
    return infos, np.array(observations), tilt


def test_the_carry_sways_the_palm_across_the_jaw_and_ignores_the_arm_action(make_env, scripted):
    """From 3.5 s the arm moves the grip A sin(2 pi f t) across the jaw (1 cm, 2 Hz), whatever
    the policy commands (here: full speed along every axis); the fingers keep obeying. Measured
    tracking error across the jaw 2.5 mm (the force-limited arm lags its target), nothing along
    the jaw or up. Success only once the carry is over: step 100; the clock is the last entry."""
    env = make_env("SoftGrasp-v2")
    infos, obs, _ = _run(env, scripted, seed=1001, arm_during_carry=[1, -1, 1, 1])
    yaw = env.unwrapped.scene.config.yaw
    assert len(infos) == 100 and obs.shape[1] == 24
    np.testing.assert_allclose(obs[:, TIME], 0.05 * np.arange(101), atol=1e-9)
    carrying = [i["carrying"] for i in infos]
    assert carrying == [False] * 69 + [True] * 30 + [False]  # from the 3.5 s observation on
    assert all(i["held"] for i in infos[60:]) and [i["is_success"] for i in infos[60:]] == [False] * 39 + [True]
    across = np.array([-np.sin(yaw), np.cos(yaw), 0.0])
    along = np.array([np.cos(yaw), np.sin(yaw), 0.0])
    d = obs[71:] - obs[70]
    t = 0.05 * np.arange(1, 31)
    assert np.abs(d[:, :3] @ across - 0.01 * np.sin(2 * np.pi * 2.0 * t)).max() < 0.005
    assert np.abs(d[:, :3] @ along).max() < 1e-3 and np.abs(d[:, 2]).max() < 1e-3


def test_before_the_carry_v2_is_v1_bit_for_bit(make_env, scripted):
    """The carry changes nothing before it starts: the same seed and actions give bit-identical
    observations on SoftGrasp-v1 and the first 23 entries of SoftGrasp-v2 for 70 steps."""
    e1, e2 = make_env("SoftGrasp-v1"), make_env("SoftGrasp-v2")
    o1, _ = e1.reset(seed=5)
    o2, _ = e2.reset(seed=5)
    assert o1.shape == (23,) and o2.shape == (24,)
    for _ in range(70):
        a = scripted(o1)  # v1's action drives both
        o1, *_ = e1.step(a)
        o2, *_ = e2.step(a)
        assert np.array_equal(o1, o2[:23])


@pytest.mark.parametrize("wedge", [-0.1, 0.0])
def test_a_rigid_two_point_grasp_swings_out_under_the_carry_the_tissue_holds(wedge, make_env, scripted):
    """The physics the carry is there for. The scripted grasp at a -0.1 rad wedge (the gap open
    at the bottom: the rigid faces touch the cylinder at their upper edges, two points) holds
    statically on v1 (tilt 0.02 deg), but the cylinder swings about the line through the two
    contacts under the 2 Hz sway: measured 52 deg, knocked over at step 91. The soft fingers
    hold it (0.32 deg). Aligned rigid fingers (no wedge) touch along a line and hold too
    (2.6 deg): it is the misalignment the tissue makes up for."""
    opts = dict(cylinder_xy=(0.0, 0.0), gripper_xy=(0.06, 0.0), yaw=0.0, jaw_wedge=wedge, lateral_offset=0.0)
    tilts, ends = {}, {}
    for env_id in ("SoftGraspRigid-v1", "SoftGraspRigid-v2", "SoftGrasp-v2"):
        infos, _, tilts[env_id] = _run(make_env(env_id), scripted, options=opts)
        ends[env_id] = infos[-1]
        assert infos[68]["held"], env_id  # lifted and held before the carry
        if env_id == "SoftGraspRigid-v1" or env_id == "SoftGrasp-v2" or wedge == 0.0:
            assert infos[-1]["is_success"] and len(infos) == 100, env_id
    assert tilts["SoftGrasp-v2"] < 1.0
    if wedge == 0.0:
        assert tilts["SoftGraspRigid-v2"] < 8.0
    else:
        assert tilts["SoftGraspRigid-v2"] > 45.0 and not ends["SoftGraspRigid-v2"]["is_success"]


@pytest.mark.parametrize("coupling", ["thesis", "consistent"])
def test_a_soft_grasp_holds_through_a_30_s_carry(coupling, make_env, scripted):
    """Long runs count: the carry test lasts 1.5 s; here 30 s (60 periods) on two seeds, with
    both couplings at the default preset. Measured over seeds 1000-1005 (thesis): every one held,
    tilt at most 0.36 deg, the lift unchanged to 0.1 mm; consistent, seeds 1000-1002: tilt at most
    0.15 deg, lift unchanged to 0.01 mm."""
    sim = replace(presets.scene_config("default").sim, coupling=coupling)
    env = make_env("SoftGrasp-v2", sim=sim, carry_duration=30.0, max_episode_steps=670)
    for seed in (1000, 1001):
        infos, obs, tilt = _run(env, scripted, seed=seed)
        assert len(infos) == 670 and infos[-1]["is_success"], seed
        assert tilt < 1.0
        lift = obs[70:, LIFT]
        assert lift.max() - lift.min() < 5e-4  # no slip in the hand


@pytest.mark.parametrize(
    "env_id, kwargs, match",
    [
        ("SoftGrasp-v2", dict(carry="yes"), "carry must be a bool"),
        ("SoftGrasp-v2", dict(carry_frequency=0.0), "carry_frequency"),
        ("SoftGrasp-v2", dict(carry_amplitude=0.1), "carry_amplitude"),
        ("SoftGrasp-v2", dict(carry_duration=-1.0), "carry_duration"),
        ("SoftGrasp-v2", dict(carry_amplitude=0.05, carry_frequency=10.0), r"moves the arm up to 1\.31 cm per physics step"),
        ("SoftGraspGoal-v1", dict(carry=True), "no carry test"),
    ],
)
def test_carry_settings_are_checked(env_id, kwargs, match):
    with pytest.raises(ValueError, match=match):
        gym.make(env_id, **kwargs)


def test_the_easy_task_and_v1_have_no_carry_and_no_clock(make_env):
    for env_id in ("SoftGraspEasy-v1", "SoftGraspRigid-v1", "SoftGraspSparse-v1", "SoftGraspGoal-v1"):
        env = make_env(env_id)
        assert not env.unwrapped.carry
        obs, info = env.reset(seed=0)
        assert obs_vector(obs).shape == (23,) and not info["carrying"]
    env = make_env("SoftGraspEasy-v1", carry=True)  # asked for: the easy start with the carry
    assert env.observation_space.shape == (24,)
