"""The task (``task="reach"``, the -v2 ids; -v1 is the same without the carry test): it needs a closed-loop policy. The gripper starts above
the cylinder's top, 4-14 cm from the origin in a random direction, the cylinder anywhere within
+-7 cm, the fingers misaligned (jaw wedge up to +-0.15 rad, yaw up to +-pi/4)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import softgrasp_env  # noqa: F401
from agents.scripted import ScriptedGraspPolicy


def _open_loop(move: tuple[float, float], steps: int) -> list[list[float]]:
    """A constant action sequence a policy without feedback might try (100 steps): move
    ``steps`` steps along ``move`` with the fingers open, down 14 steps (the start height), close
    for 10, then lift."""
    seq = [[move[0], move[1], 0, -1]] * steps + [[0, 0, -1, -1]] * 14 + [[0, 0, 0, 1]] * 10
    return seq + [[0, 0, 1, 1]] * (100 - len(seq))


def _success_rate(env, policy_or_actions, seeds) -> float:
    ok = 0
    for seed in seeds:
        obs, _ = env.reset(seed=seed)
        info = {}
        for t in range(100):
            a = policy_or_actions(obs) if callable(policy_or_actions) else np.asarray(policy_or_actions[t], np.float32)
            obs, _, term, trunc, info = env.step(a)
            if term or trunc:
                break
        ok += bool(info["is_success"])
    return ok / len(seeds)


ISSUE_SEQUENCE = [[0, 0, 0, 1]] * 15 + [[0, 0, 1, 1]] * 85
"""'Close the fingers for 15 steps, then move up': it solved every v0 episode (the fingers
started around the cylinder)."""


@pytest.mark.parametrize("name", ["close 15, then up", "down, close, up"])
def test_open_loop_actions_rarely_succeed(name):
    """The task needs feedback: measured over seeds 0-39 on the soft env, 'close 15, then up'
    succeeds in 0 of 40, 'down, close, up' in 1 of 40. Asserted on 20 other seeds: at most 10 %."""
    seq = ISSUE_SEQUENCE if name == "close 15, then up" else _open_loop((0.0, 0.0), 0)
    env = gym.make("SoftGrasp-v2")
    try:
        rate = _success_rate(env, seq, range(1000, 1020))
    finally:
        env.close()
    assert rate <= 0.10, f"open-loop {name!r} succeeded in {rate:.0%}"


@pytest.mark.slow
@pytest.mark.parametrize("move,steps", [((0.7, 0.7), 5), ((0.7, 0.7), 9), ((-0.7, -0.7), 9), ((1.0, 0.0), 9),
                                        ((0.0, 1.0), 9), ((0.7, -0.7), 9)])  # fmt: skip
def test_no_constant_move_finds_the_cylinder_often(move, steps):
    """Move a fixed way first, then down, close, lift. Measured over seeds 0-39 (soft), eighteen
    such sequences: 0-4 of 40 each; the best, along +x+y for 5 or 9 steps, 4 of 40 - at the
    bound (and 6 of 60 over seeds 0-59): the start and the cylinder are spread as widely as the
    workspace allows, and the soft fingers, wide open, still catch a cylinder that lies within
    about 2.5 cm of where they come down."""
    env = gym.make("SoftGrasp-v2")
    try:
        rate = _success_rate(env, _open_loop(move, steps), range(40))
    finally:
        env.close()
    assert rate <= 0.10, f"open-loop move {move} x{steps} succeeded in {rate:.0%}"


def test_scripted_policy_solves_the_soft_task():
    """The scripted policy (observation only) succeeds in >= 90 % of seeded episodes with soft
    fingers. Measured: 30 of 30 (seeds 0-29); the rigid twin 14 of 30 - its fingers lose the
    cylinder under the jaw wedge (docs/RESULTS.md), which is what the task is to show."""
    env = gym.make("SoftGrasp-v2")
    forces = []
    policy = ScriptedGraspPolicy()

    def watched(obs):
        forces.append(obs[19:21])
        return policy(obs)

    try:
        rate = _success_rate(env, watched, range(2000, 2020))
    finally:
        env.close()
    assert rate >= 0.9, f"scripted policy: {rate:.0%}"
    # The arm only moves and lifts: the fingers press with their motors' 3 N, no more (measured
    # 2.93 N at most over 10 episodes); random arm pushes reach 220 N (the env card).
    assert np.max(forces) <= 3.3


def test_rigid_fingers_press_no_harder_than_their_motors_in_the_scripted_grasp():
    """Measured 3.34 N at most over 10 episodes (the core's impact on first contact), 3.00 N while
    the cylinder is in the air."""
    env = gym.make("SoftGraspRigid-v2")
    forces = []
    policy = ScriptedGraspPolicy()

    def watched(obs):
        forces.append((obs[19], obs[20], obs[21]))
        return policy(obs)

    try:
        _success_rate(env, watched, range(100, 104))
    finally:
        env.close()
    forces = np.array(forces)
    assert forces[:, :2].max() <= 3.6
    lifted = forces[forces[:, 2] > 0.03]
    assert len(lifted) == 0 or lifted[:, :2].max() <= 3.1


def test_reach_start_is_above_and_away_and_options_fix_it():
    env = gym.make("SoftGrasp-v2")
    try:
        for seed in range(5):
            env.reset(seed=seed)
            sc = env.unwrapped.scene
            cfg = sc.config
            d = np.hypot(*np.subtract(cfg.gripper_xy, (0.0, 0.0)))
            assert 0.04 - 1e-12 <= d <= 0.14 + 1e-12
            assert abs(cfg.cylinder_xy[0]) <= 0.07 and abs(cfg.cylinder_xy[1]) <= 0.07
            assert abs(cfg.jaw_wedge) <= 0.15 and abs(cfg.yaw) <= np.pi / 4
            tips = sc.start_palm[2] - sc.palm_offset - cfg.finger_half_extents[2]
            assert tips == pytest.approx(cfg.cylinder_height + 0.02)  # 2 cm above its top
        env.reset(seed=0, options={"gripper_xy": (0.05, -0.02), "cylinder_xy": (0.0, 0.0), "jaw_wedge": 0.1})
        cfg = env.unwrapped.scene.config
        assert cfg.gripper_xy == (0.05, -0.02) and cfg.jaw_wedge == 0.1
    finally:
        env.close()


def test_task_is_validated():
    with pytest.raises(ValueError, match="task must be one of"):
        gym.make("SoftGrasp-v2", task="fly")
    with pytest.raises(ValueError, match="approach_range"):
        gym.make("SoftGrasp-v2", approach_range=(0.05, 0.2))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(cylinder_radius=0.2), r"does not fit between the open fingers.*at most 0\.0480 m"),
        (dict(cylinder_radius=0.08), r"does not fit between the open fingers"),
        (dict(cylinder_height=0.5), r"too tall for task='reach'.*at most 0\.140 m"),
        (dict(cylinder_height=0.5, task="easy"), r"too tall for task='easy'"),
        (dict(cylinder_radius=0.047), r"randomisation ranges reach a scene that cannot start.*jaw_wedge_range=0\.15"),
        (dict(task="easy", cylinder_position_range=0.05), r"cylinder_position_range=0\.05.*fingers start inside the cylinder"),
    ],
)
def test_geometry_that_cannot_start_is_refused_when_the_env_is_made(kwargs, match):
    """Issue 12's clashes: a cylinder wider than the open fingers (0.08 diverged at step 1, 0.12 and
    0.2 started inside the fingers), a cylinder taller than the start (the palm inside it), and
    range extremes that put a finger into the cylinder - each a ValueError naming the settings
    and the limit, at gym.make, not at some later reset."""
    with pytest.raises(ValueError, match=match):
        gym.make("SoftGrasp-v2", **kwargs)


def test_scene_geometry_check_names_the_palm_and_allows_an_offset_along_the_faces():
    from softgrasp_env.config import SceneConfig

    with pytest.raises(ValueError, match="palm starts inside the cylinder"):
        SceneConfig(cylinder_height=0.3)
    SceneConfig(lateral_offset=0.03)  # past the face's end along y: no overlap (the stability map's cells)
    with pytest.raises(ValueError, match="fingers start inside the cylinder"):
        SceneConfig(cylinder_xy=(0.03, 0.0))
    with pytest.raises(ValueError, match="reset option|does not fit"):
        env = gym.make("SoftGrasp-v2")
        try:
            env.reset(seed=0, options={"cylinder_radius": 0.06})
        finally:
            env.close()


@pytest.mark.parametrize(
    "options, error, match",
    [
        ("x", TypeError, "reset options must be a dict"),
        ({"cylinder_xy": 0.0}, TypeError, "'cylinder_xy' must be two numbers"),
        ({"gripper_xy": (0.0, "b")}, TypeError, "'gripper_xy' must be two numbers"),
        ({"yaw": "a"}, TypeError, "'yaw' must be a number, got str"),
        ({"yaw": True}, TypeError, "'yaw' must be a number, got bool"),
        ({"jaw_wedge": float("nan")}, ValueError, "'jaw_wedge' must be finite"),
    ],
)
def test_reset_options_of_the_wrong_type_name_the_option_and_leave_the_env_usable(options, error, match):
    """Issue 12 item 5: a wrong-typed option names itself and the type it wants (it used to be
    "TypeError: 'float' object is not iterable"); the env still resets and steps afterwards,
    under gym.make's default checker too."""
    env = gym.make("SoftGraspEasyRigid-v1")
    try:
        with pytest.raises(error, match=match):
            env.reset(seed=0, options=options)
        obs, _ = env.reset(seed=0, options={"cylinder_xy": np.array([0.005, 0.0]), "yaw": np.float32(0.05)})
        obs, *_ = env.step(env.action_space.sample())
        assert np.isfinite(obs).all()
    finally:
        env.close()


# --- the carry test (v2) ---------------------------------------------------------------------------


def _run(env, policy, *, seed=0, options=None, arm_during_carry=None):
    """One episode; returns (per-step infos, observations, max tilt during the carry [deg])."""
    obs, _ = env.reset(seed=seed, options=options)
    infos, observations, tilt = [], [obs], 0.0
    for _ in range(env.spec.max_episode_steps if env.spec and env.spec.max_episode_steps else 100):
        a = policy(obs)
        if arm_during_carry is not None and infos and infos[-1]["carrying"]:
            a = np.asarray(arm_during_carry, np.float32)
        obs, _, term, trunc, info = env.step(a)
        infos.append(info)
        observations.append(obs)
        if info["carrying"] or (len(infos) > 1 and infos[-2]["carrying"]):
            tilt = max(tilt, float(np.degrees(np.arccos(min(1.0, obs[12])))))
        if term or trunc:
            break
    return infos, np.array(observations), tilt


def test_the_carry_sways_the_palm_across_the_jaw_and_ignores_the_arm_action():
    """From 3.5 s the arm moves the grip A sin(2 pi f t) across the jaw (1 cm, 2 Hz), whatever
    the policy commands (here: full speed along every axis); the fingers keep obeying. Measured
    tracking error across the jaw 2.5 mm (the force-limited arm lags its target), nothing along
    the jaw or up. Success only once the carry is over: step 100; the clock is the last entry."""
    env = gym.make("SoftGrasp-v2")
    try:
        infos, obs, _ = _run(env, ScriptedGraspPolicy(), seed=1001, arm_during_carry=[1, -1, 1, 1])
        yaw = env.unwrapped.scene.config.yaw
    finally:
        env.close()
    assert len(infos) == 100 and obs.shape[1] == 24
    np.testing.assert_allclose(obs[:, 23], 0.05 * np.arange(101), atol=1e-9)
    carrying = [i["carrying"] for i in infos]
    assert carrying == [False] * 69 + [True] * 30 + [False]  # from the 3.5 s observation on
    assert all(i["held"] for i in infos[60:]) and [i["is_success"] for i in infos[60:]] == [False] * 39 + [True]
    across = np.array([-np.sin(yaw), np.cos(yaw), 0.0])
    along = np.array([np.cos(yaw), np.sin(yaw), 0.0])
    d = obs[71:] - obs[70]
    t = 0.05 * np.arange(1, 31)
    assert np.abs(d[:, :3] @ across - 0.01 * np.sin(2 * np.pi * 2.0 * t)).max() < 0.005
    assert np.abs(d[:, :3] @ along).max() < 1e-3 and np.abs(d[:, 2]).max() < 1e-3


def test_before_the_carry_v2_is_v1_bit_for_bit():
    """The carry changes nothing before it starts: the same seed and actions give bit-identical
    observations on SoftGrasp-v1 and the first 23 entries of SoftGrasp-v2 for 70 steps."""
    e1, e2 = gym.make("SoftGrasp-v1"), gym.make("SoftGrasp-v2")
    policy = ScriptedGraspPolicy()
    try:
        o1, _ = e1.reset(seed=5)
        o2, _ = e2.reset(seed=5)
        assert o1.shape == (23,) and o2.shape == (24,)
        for _ in range(70):
            a = policy(o1)
            o1, *_ = e1.step(a)
            o2, *_ = e2.step(a)
            assert np.array_equal(o1, o2[:23])
    finally:
        e1.close()
        e2.close()


@pytest.mark.parametrize("wedge", [-0.1, 0.0])
def test_a_rigid_two_point_grasp_swings_out_under_the_carry_the_tissue_holds(wedge):
    """The physics the carry is there for. The scripted grasp at a -0.1 rad wedge (the gap open
    at the bottom: the rigid faces touch the cylinder at their upper edges, two points) holds
    statically on v1 (tilt 0.02 deg), but the cylinder swings about the line through the two
    contacts under the 2 Hz sway: measured 52 deg, knocked over at step 91. The soft fingers
    hold it (0.32 deg). Aligned rigid fingers (no wedge) touch along a line and hold too
    (2.6 deg): it is the misalignment the tissue makes up for."""
    opts = dict(cylinder_xy=(0.0, 0.0), gripper_xy=(0.06, 0.0), yaw=0.0, jaw_wedge=wedge, lateral_offset=0.0)
    tilts, ends = {}, {}
    for env_id in ("SoftGraspRigid-v1", "SoftGraspRigid-v2", "SoftGrasp-v2"):
        env = gym.make(env_id)
        try:
            infos, _, tilts[env_id] = _run(env, ScriptedGraspPolicy(), options=opts)
        finally:
            env.close()
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
def test_a_soft_grasp_holds_through_a_30_s_carry(coupling):
    """Long runs count: the carry test lasts 1.5 s; here 30 s (60 periods) on two seeds, with
    both couplings at the default preset. Measured over seeds 1000-1005 (thesis): every one held,
    tilt at most 0.36 deg, the lift unchanged to 0.1 mm; consistent, seeds 1000-1002: tilt at most
    0.15 deg, lift unchanged to 0.01 mm."""
    from dataclasses import replace

    from softgrasp_env import presets

    sim = replace(presets.scene_config("default").sim, coupling=coupling)
    env = gym.make("SoftGrasp-v2", sim=sim, carry_duration=30.0, max_episode_steps=670)
    try:
        for seed in (1000, 1001):
            infos, obs, tilt = _run(env, ScriptedGraspPolicy(), seed=seed)
            assert len(infos) == 670 and infos[-1]["is_success"], seed
            assert tilt < 1.0
            lift = obs[70:, 21]
            assert lift.max() - lift.min() < 5e-4  # no slip in the hand
    finally:
        env.close()


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


def test_the_easy_task_and_v1_have_no_carry_and_no_clock():
    for env_id in ("SoftGraspEasy-v1", "SoftGraspRigid-v1", "SoftGraspSparse-v1", "SoftGraspGoal-v1"):
        env = gym.make(env_id)
        try:
            assert not env.unwrapped.carry
            obs, info = env.reset(seed=0)
            assert (obs["observation"] if isinstance(obs, dict) else obs).shape == (23,) and not info["carrying"]
        finally:
            env.close()
    env = gym.make("SoftGraspEasy-v1", carry=True)  # asked for: the easy start with the carry
    try:
        assert env.observation_space.shape == (24,)
    finally:
        env.close()
