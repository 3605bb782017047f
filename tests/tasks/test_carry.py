"""The carry test (softgrasp_env/tasks/carry.py): for the episode's last 1.5 s the arm, not the
policy, sways the palm: a sway drawn per episode (1.2-3 Hz, 0.5-1 m/s^2 peak, any horizontal
direction), ramped in, and success needs the cylinder held at every step of it with little
in-hand slide. A rigid two-point grasp swings out near its pendulum frequency, the tissue holds."""

from __future__ import annotations

import math
from dataclasses import replace
from types import SimpleNamespace

import gymnasium as gym
import numpy as np
import pytest

from softgrasp_env import presets
from softgrasp_env.observation import CARRY_OBS_NAMES
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.registration import TISSUE_V3
from softgrasp_env.scene import SceneConfig, Workspace
from softgrasp_env.tasks import CarryTest, Outcome, Task
from softgrasp_env.tasks.carry import CARRY_ACCELERATION_RANGE, CARRY_FREQUENCY_BAND, CARRY_SLIDE_LIMIT
from tests.helpers import obs_vector, run_episode

AXIS_Z = CARRY_OBS_NAMES.index("cyl_axis_z")
LIFT = CARRY_OBS_NAMES.index("lift")
TIME = CARRY_OBS_NAMES.index("time")
TWO_POINT = dict(cylinder_xy=(0.0, 0.0), gripper_xy=(0.06, 0.0), yaw=0.0, lateral_offset=0.0)
"""An aligned start; with jaw_wedge -0.1 the rigid faces touch the cylinder at two points."""


def _run(env, policy=None, *, seed=0, options=None, arm_during_carry=None):
    """One episode (to its time limit or its end); returns (per-step infos, observations with the
    reset's first, max tilt during the carry and at the step after it [deg]). ``arm_during_carry``:
    the action while the last step was carrying, instead of the policy's."""
    policy = policy or ScriptedGraspPolicy.for_env(env)
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


# --- v3 --------------------------------------------------------------------------------------------


def test_the_v3_sway_is_drawn_per_episode_in_its_bands_and_reproduces(make_env):
    env = make_env("SoftGraspRigid-v3")
    task = env.unwrapped.task
    draws = []
    for seed in range(40):
        env.reset(seed=seed)
        draws.append((task.frequency, task.amplitude, task.angle))
    f, amp, angle = np.array(draws).T
    accel = amp * (2 * np.pi * f) ** 2
    assert CARRY_FREQUENCY_BAND[0] <= f.min() and f.max() <= CARRY_FREQUENCY_BAND[1]
    assert CARRY_ACCELERATION_RANGE[0] - 1e-12 <= accel.min() and accel.max() <= CARRY_ACCELERATION_RANGE[1] + 1e-12
    assert 0.0 <= angle.min() and angle.max() < np.pi
    assert np.ptp(f) > 1.2 and np.ptp(accel) > 0.3 and np.ptp(angle) > 2.0  # the bands are covered, not one value
    assert (amp * 2 * np.pi * f).max() <= 0.15  # within the arm's speed
    env.reset(seed=7)
    again = (task.frequency, task.amplitude, task.angle)
    assert again == draws[7]
    env.reset(seed=7, options=dict(carry_frequency=1.9, carry_acceleration=0.8, carry_direction=0.3))
    assert (task.frequency, task.angle) == (1.9, 0.3) and task.amplitude == pytest.approx(0.8 / (2 * np.pi * 1.9) ** 2)


def test_a_sway_the_arm_cannot_follow_is_refused_at_reset_and_at_make(make_env):
    """Peak acceleration and speed with the ramp over the first period included (4.9 % and 1.3 %
    above the steady sway's): 1.45 m/s^2 steady is 1.52 while it ramps in, past the arm's 1.5."""
    env = make_env("SoftGraspRigid-v3")
    with pytest.raises(ValueError, match=r"peaks at 2.1 m/s\^2 \(2 steady, more while it ramps in\), above the arm's "
                                         r"arm_acceleration=1.5"):  # fmt: skip
        env.reset(seed=0, options=dict(carry_acceleration=2.0))
    with pytest.raises(ValueError, match=r"peaks at 1.52 m/s\^2 \(1.45 steady"):
        env.reset(seed=0, options=dict(carry_frequency=2.0, carry_acceleration=1.45))
    env.reset(seed=0, options=dict(carry_frequency=2.0, carry_acceleration=1.4))  # 1.47 while ramping: followed
    with pytest.raises(ValueError, match=r"peaks at 0.161 m/s \(0.159 steady.*arm_speed=0.15"):
        env.reset(seed=0, options=dict(carry_frequency=1.0, carry_acceleration=1.0))
    with pytest.raises(ValueError, match="reset option 'carry_frequency' must be in"):
        env.reset(seed=0, options=dict(carry_frequency=0.0))
    with pytest.raises(ValueError, match=r"sway at 2 Hz \(1 cm\) peaks at 1.66 m/s\^2 \(1.58 steady"):
        gym.make("SoftGrasp-v5", carry_acceleration=0.01 * (4.0 * math.pi) ** 2, carry_frequency=2.0)


@pytest.mark.parametrize("angle", [0.0, 1.2])
def test_the_v3_carry_moves_the_palm_along_the_drawn_sway_and_ignores_the_arm_action(angle, make_env):
    """From 3.5 s the grip follows A r(t) sin(2 pi f t) along the drawn direction (r ramps from 0
    to 1 over the first period), whatever the policy commands (here: full speed along every
    axis); the fingers keep obeying. Measured deviation from the sway 0.7 mm (across) and 0.5 mm
    (1.2 rad), nothing up (SoftGrasp-v4 with the thesis tissue, TISSUE_V3); success only once the
    carry is over, at step 100."""
    env = make_env("SoftGrasp-v4", **TISSUE_V3)
    opts = dict(carry_frequency=2.0, carry_acceleration=1.0, carry_direction=angle)
    infos, obs, _ = _run(env, seed=1001, options=opts, arm_during_carry=[1, -1, 1, 1])
    yaw = env.unwrapped.scene.config.yaw
    assert len(infos) == 100 and obs.shape[1] == 24
    np.testing.assert_allclose(obs[:, TIME], 0.05 * np.arange(101), atol=1e-9)
    carrying = [i["carrying"] for i in infos]
    assert carrying == [False] * 69 + [True] * 30 + [False]  # from the 3.5 s observation on
    assert all(i["held"] for i in infos[60:]) and [i["is_success"] for i in infos[60:]] == [False] * 39 + [True]
    across = np.array([-np.sin(yaw), np.cos(yaw), 0.0])
    along = np.array([np.cos(yaw), np.sin(yaw), 0.0])
    direction = across * np.cos(angle) + along * np.sin(angle)
    normal = np.cross(direction, [0.0, 0.0, 1.0])
    d = obs[71:, :3] - obs[70, :3]
    t = 0.05 * np.arange(1, 31)
    amplitude = 1.0 / (2 * np.pi * 2.0) ** 2
    sway = amplitude * np.minimum(1.0, 2.0 * t) * np.sin(2 * np.pi * 2.0 * t)
    assert np.abs(d @ direction - sway).max() < 2e-3
    assert np.abs(d @ normal).max() < 1e-3 and np.abs(d[:, 2]).max() < 1e-3


def test_before_the_carry_v3_is_v3_without_it_bit_for_bit(make_env):
    """The carry changes nothing before it starts: the same seed and actions give bit-identical
    observations with and without it (the first 23 entries) for 69 steps (the 70th ends with the
    carry's first physics step, at 3.5 s: the arm's path starts to hold the palm there)."""
    e1, e2 = make_env("SoftGrasp-v5", carry=False), make_env("SoftGrasp-v5")
    policy = ScriptedGraspPolicy.for_env(e1)
    o1, _ = e1.reset(seed=5)
    o2, _ = e2.reset(seed=5)
    assert o1.shape == (23,) and o2.shape == (24,)
    for _ in range(69):
        a = policy(o1)
        o1, *_ = e1.step(a)
        o2, *_ = e2.step(a)
        assert np.array_equal(o1, o2[:23])


class _Script(Task):
    """A task whose verdicts are given: held or not, step by step."""

    observation_extras = ()

    def __init__(self, held):
        self.held = list(held)

    def draw(self, rng, options, base):
        return base

    def evaluate(self, reading, scene):
        return Outcome(held=self.held[scene.steps - 1], success=False, terminated=False, reward=0.0)


def _verdicts(held, slides, slide_limit=CARRY_SLIDE_LIMIT):
    """CarryTest's success at each of 10 steps (dt 1 s, carry from 3 s for 5 s) for the given
    held flags and in-hand positions."""
    cfg = SceneConfig(fingers="rigid")
    carry = CarryTest(_Script(held), dt=1.0, workspace=Workspace.of(cfg), start_time=3.0, duration=5.0,
                      acceleration=1.0, frequency=0.1, slide_limit=slide_limit)  # fmt: skip
    carry.draw(np.random.default_rng(0), {}, cfg)
    carry.begin(None, np.random.default_rng(0))
    out = []
    for k, slide in enumerate(slides, start=1):
        reading = SimpleNamespace(cyl_rel=np.array([0.0, slide, 0.0]))
        out.append(carry.evaluate(reading, SimpleNamespace(steps=k)).success)
    return out


def test_the_carry_test_defaults_to_the_envs_sway():
    """CarryTest on its own draws the sway gym.make's defaults give: the same band, range, window
    and slide limit."""
    from softgrasp_env.arguments import KEYWORDS

    defaults = {k.name: k.default for k in KEYWORDS}
    cfg = SceneConfig(fingers="rigid")
    carry = CarryTest(_Script([True] * 10), dt=1 / 240, workspace=Workspace.of(cfg))
    assert carry.frequency_band == defaults["carry_frequency"] == (1.2, 3.0)
    assert carry.acceleration_band == defaults["carry_acceleration"] == (0.5, 1.0)
    assert carry.slide_limit == defaults["carry_slide_limit"] == CARRY_SLIDE_LIMIT
    assert (carry.start_time, carry.duration) == (defaults["carry_start"], defaults["carry_duration"])


def test_v3_success_needs_the_cylinder_held_through_the_whole_carry_without_sliding():
    ok = [True] * 10
    assert _verdicts(ok, [0.0] * 10) == [False] * 7 + [True] * 3  # from the carry's end on
    dropped_and_back = ok[:5] + [False] + ok[6:]  # a swing past the tilt limit that comes back
    assert _verdicts(dropped_and_back, [0.0] * 10) == [False] * 10
    not_yet_held = [False] * 3 + ok[3:]  # lifted only as the carry began: its first step counts
    assert _verdicts(not_yet_held, [0.0] * 10) == [False] * 10
    creeping = [0.0] * 4 + [0.002, 0.004, 0.006] + [0.006] * 3  # 6 mm of slide within the carry (steps 3-8)
    assert _verdicts(ok, creeping) == [False] * 10
    assert _verdicts(ok, creeping, slide_limit=0.01) == [False] * 7 + [True] * 3
    assert _verdicts(ok[:7] + [False] + ok[8:], [0.0] * 10) == [False] * 10  # dropped at the carry's last step
    assert _verdicts(ok[:9] + [False], [0.0] * 10) == [False] * 7 + [True, True, False]  # dropped after it


@pytest.mark.parametrize("wedge", [-0.1, 0.0])
def test_a_rigid_two_point_grasp_swings_out_near_its_pendulum_frequency_the_tissue_holds(wedge, make_env):
    """The physics the carry is there for. The scripted grasp at a -0.1 rad wedge (the gap open at
    the bottom: the rigid faces touch the cylinder at their upper edges, two points) lifts and
    holds, but under a 1 m/s^2 sway across the jaw at 1.9 Hz, near the pendulum frequency, the
    cylinder swings about the line through the two contacts: measured 37 deg and 18 mm of slide
    (at 1.2 Hz 18 deg, 9 mm; at 3 Hz 5.5 deg, 2.8 mm). The soft fingers (SoftGrasp-v4 with the
    thesis tissue, TISSUE_V3) hold it (0.1 deg, 0.14 mm), and so do the soft ids' latest
    (SoftGrasp-v5: 0.03 deg, 0.06 mm). Aligned rigid fingers (no wedge) touch along a line and hold
    too (0.0 deg, 0.3 mm): it is the misalignment the tissue makes up for."""
    opts = dict(TWO_POINT, jaw_wedge=wedge, carry_frequency=1.9, carry_acceleration=1.0, carry_direction=0.0)
    tilts, ends, slides = {}, {}, {}
    for env_id, keywords in (("SoftGraspRigid-v3", {}), ("SoftGrasp-v4", TISSUE_V3), ("SoftGrasp-v5", {})):
        env = make_env(env_id, **keywords)
        infos, _, tilts[env_id] = _run(env, options=opts)
        ends[env_id], slides[env_id] = infos[-1], env.unwrapped.task.slide
        assert infos[68]["held"], env_id  # lifted and held before the carry
    assert ends["SoftGrasp-v4"]["is_success"] and tilts["SoftGrasp-v4"] < 0.5 and slides["SoftGrasp-v4"] < 5e-4
    assert ends["SoftGrasp-v5"]["is_success"] and tilts["SoftGrasp-v5"] < 0.1 and slides["SoftGrasp-v5"] < 2e-4
    if wedge == 0.0:
        assert ends["SoftGraspRigid-v3"]["is_success"]
        assert tilts["SoftGraspRigid-v3"] < 0.5 and slides["SoftGraspRigid-v3"] < 1e-3
    else:
        assert tilts["SoftGraspRigid-v3"] > 25.0 and slides["SoftGraspRigid-v3"] > 0.01
        assert not ends["SoftGraspRigid-v3"]["is_success"]


@pytest.mark.parametrize("env_id, coupling, preset", [
    ("SoftGrasp-v4", "thesis", None), ("SoftGrasp-v4", "consistent", None), ("SoftGraspRigidTorsion-v3", None, None),
    ("SoftGrasp-v5", None, None), pytest.param("SoftGrasp-v5", None, "fine", marks=pytest.mark.slow)])  # fmt: skip
def test_the_grasp_holds_through_a_30_s_carry(env_id, coupling, preset, make_env):
    """Long runs count: the carry test lasts 1.5 s; here 30 s (57 periods at 1.9 Hz, 1 m/s^2, the
    hardest of the band for a two-point grasp) on two seeds: the soft fingers (SoftGrasp-v4 with the
    thesis tissue, TISSUE_V3) with both couplings at the default preset, and the torsional peer the
    v3 maps find as good as the tissue (it must hold as long; measured tilt 0.20 / 0.11 deg, slide
    0.37 / 0.35 mm, the lift steady within 0.10 / 0.06 mm), and the soft ids' latest physics
    (SoftGrasp-v5, the v4 tissue solved globally: tilt 0.00 / 0.06 deg, slide 0.06 / 0.08 mm, the
    lift steady within 0.003 mm; at ``preset="fine"``, 4 x the particles per m^2, slow: tilt 0.06 / 0.05
    deg, slide 0.07 / 0.08 mm, steady within 0.002 mm). Held at every step, little tilt, no creep in
    the hand."""
    kwargs = {} if coupling is None else {"sim": replace(presets.scene_config("default").sim, coupling=coupling),
                                          **TISSUE_V3}  # fmt: skip
    if preset is not None:
        kwargs["preset"] = preset
    env = make_env(env_id, carry_duration=30.0, max_episode_steps=670, **kwargs)
    for seed in (1000, 1001):
        opts = dict(carry_frequency=1.9, carry_acceleration=1.0, carry_direction=0.0)
        infos, obs, tilt = _run(env, seed=seed, options=opts)
        assert len(infos) == 670 and infos[-1]["is_success"], seed
        assert tilt < 1.0 and env.unwrapped.task.slide < 1e-3
        lift = obs[70:, LIFT]
        assert lift.max() - lift.min() < 5e-4  # no slip in the hand


# --- settings ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "env_id, kwargs, match",
    [
        ("SoftGrasp-v5", dict(carry="yes"), "carry must be a bool"),
        ("SoftGrasp-v5", dict(carry_frequency=0.0), "carry_frequency"),
        ("SoftGrasp-v5", dict(carry_frequency=(3.0, 1.0)), r"low <= high"),
        ("SoftGrasp-v5", dict(carry_frequency=(1.0, 2.0, 3.0)), r"a number or \(low, high\)"),
        ("SoftGrasp-v5", dict(carry_acceleration=(0.5, 2.0)), "above the arm's arm_acceleration"),
        ("SoftGrasp-v5", dict(carry_acceleration=None), "carry_acceleration must be a finite number"),
        ("SoftGrasp-v5", dict(carry_slide_limit=0.0), "carry_slide_limit"),
        ("SoftGrasp-v5", dict(carry_duration=-1.0), "carry_duration"),
        # the v1/v2 sway's settings, retired: each names the release that has them
        ("SoftGrasp-v5", dict(carry_amplitude=0.01), r"carry_amplitude=0\.01 was retired.*softgrasp-env==0\.6\.0.*"
                                                     r"carry_acceleration = amplitude \* \(2 pi carry_frequency\)\^2"),
        ("SoftGrasp-v5", dict(carry_direction="across"), r"carry_direction='across' was retired.*==0\.6\.0"),
        ("SoftGrasp-v5", dict(carry_direction="up"), "carry_direction is no longer an argument"),
        ("SoftGrasp-v5", dict(carry_slide_limit=None), r"carry_slide_limit=None .* was retired.*==0\.6\.0"),
        ("SoftGraspGoal-v5", dict(carry=True), "no carry test"),
    ],
)
def test_carry_settings_are_checked(env_id, kwargs, match):
    with pytest.raises(ValueError, match=match):
        gym.make(env_id, **kwargs)


def test_the_easy_task_has_no_carry_and_no_clock(make_env):
    for env_id in ("SoftGraspEasy-v5", "SoftGraspEasyRigid-v3", "SoftGraspGoal-v6"):
        env = make_env(env_id)
        assert not env.unwrapped.carry
        obs, info = env.reset(seed=0)
        assert obs_vector(obs).shape == (23,) and not info["carrying"]
    env = make_env("SoftGraspEasy-v5", carry=True)  # asked for: the easy start with the carry
    assert env.observation_space.shape == (24,)
    assert math.isclose(env.unwrapped.task.slide_limit, CARRY_SLIDE_LIMIT)
