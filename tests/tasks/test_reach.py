"""The reach task (``start="reach"``, softgrasp_env/tasks/reach.py; every id but the Easy and grip ones, the
carry test on top: tests/tasks/test_carry.py): it needs a closed-loop policy. The gripper
starts above the cylinder's top, 4-14 cm from the origin in a random direction, the cylinder
anywhere within +-7 cm, the fingers misaligned (jaw wedge up to +-0.15 rad, yaw up to +-pi/4)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from softgrasp_env.observation import OBS_NAMES, obs_slice
from softgrasp_env.scene import SceneConfig
from tests.helpers import SOFT_PHYSICS, run_episode, soft_physics

FORCE = obs_slice(OBS_NAMES, "force")
LIFT = OBS_NAMES.index("lift")


def _open_loop(move: tuple[float, float], steps: int) -> list[list[float]]:
    """A constant action sequence a policy without feedback might try (100 steps): move
    ``steps`` steps along ``move`` with the fingers open, down 14 steps (the start height), close
    for 10, then lift."""
    seq = [[move[0], move[1], 0, -1]] * steps + [[0, 0, -1, -1]] * 14 + [[0, 0, 0, 1]] * 10
    return seq + [[0, 0, 1, 1]] * (100 - len(seq))


def _replay(actions: list[list[float]]):
    """An open-loop policy: the next of ``actions`` whatever it observes."""
    it = iter(actions)
    return lambda obs: np.asarray(next(it), np.float32)


def _success_rate(env, policy_or_actions, seeds) -> float:
    """Share of the seeded episodes that end in success; a list of actions is replayed open loop."""
    ok = 0
    for seed in seeds:
        policy = policy_or_actions if callable(policy_or_actions) else _replay(policy_or_actions)
        ok += run_episode(env, policy, seed=seed, max_steps=100).success
    return ok / len(seeds)


ISSUE_SEQUENCE = [[0, 0, 0, 1]] * 15 + [[0, 0, 1, 1]] * 85
"""'Close the fingers for 15 steps, then move up': it solved every v0 episode (the fingers
started around the cylinder)."""


@pytest.mark.parametrize("soft", SOFT_PHYSICS)
@pytest.mark.parametrize("name", ["close 15, then up", "down, close, up"])
def test_open_loop_actions_rarely_succeed(name, soft, make_env):
    """The task needs feedback: measured over seeds 0-39, 'close 15, then up' succeeds in 0 of 40
    on both soft envs, 'down, close, up' in 1 of 40 on both. Asserted on 20 other seeds (measured
    0 of 20 each): at most 10 %."""
    seq = ISSUE_SEQUENCE if name == "close 15, then up" else _open_loop((0.0, 0.0), 0)
    env_id, keywords = soft_physics("SoftGrasp", soft)
    rate = _success_rate(make_env(env_id, **keywords), seq, range(1000, 1020))
    assert rate <= 0.10, f"open-loop {name!r} succeeded in {rate:.0%}"


@pytest.mark.slow
@pytest.mark.parametrize("move,steps", [((0.7, 0.7), 5), ((0.7, 0.7), 9), ((-0.7, -0.7), 9), ((1.0, 0.0), 9),
                                        ((0.0, 1.0), 9), ((0.7, -0.7), 9)])  # fmt: skip
@pytest.mark.parametrize("soft", SOFT_PHYSICS)
def test_no_constant_move_finds_the_cylinder_often(move, steps, soft, make_env):
    """Move a fixed way first, then down, close, lift. Measured over seeds 0-39 on the thesis
    tissue, eighteen such sequences: 0-4 of 40 each; the best, along +x+y for 5 or 9 steps, 4 of 40
    - at the bound (and 6 of 60 over seeds 0-59): the start and the cylinder are spread as widely
    as the workspace allows, and the soft fingers, wide open, still catch a cylinder that lies
    within about 2.5 cm of where they come down. On SoftGrasp-v5 the six here: 4, 4, 3, 1, 1, 3 of
    40."""
    env_id, keywords = soft_physics("SoftGrasp", soft)
    rate = _success_rate(make_env(env_id, **keywords), _open_loop(move, steps), range(40))
    assert rate <= 0.10, f"open-loop move {move} x{steps} succeeded in {rate:.0%}"


@pytest.mark.parametrize("soft", SOFT_PHYSICS)
def test_scripted_policy_solves_the_soft_task(soft, make_env, scripted):
    """The scripted policy (observation only) succeeds in >= 90 % of seeded episodes with soft
    fingers. Measured: 30 of 30 (seeds 0-29) on both soft envs, and 20 of 20 here on SoftGrasp-v5;
    the rigid twin 14 of 30 - its fingers lose the cylinder under the jaw wedge (docs/RESULTS.md),
    which is what the task is to show."""
    forces = []

    def watched(obs):
        forces.append(obs[FORCE])
        return scripted(obs)

    env_id, keywords = soft_physics("SoftGrasp", soft)
    rate = _success_rate(make_env(env_id, **keywords), watched, range(2000, 2020))
    assert rate >= 0.9, f"scripted policy: {rate:.0%}"
    # The arm only moves and lifts: the fingers press with their motors' 3 N, no more (measured
    # 2.93 N at most over 10 episodes on the thesis tissue, 2.99 N over 50 on SoftGrasp-v5); random
    # arm pushes reach 220 N (the env card).
    assert np.max(forces) <= 3.3


def test_rigid_fingers_press_no_harder_than_their_motors_in_the_scripted_grasp(make_env, scripted):
    """Measured 3.34 N at most over 10 episodes (the core's impact on first contact), 3.00 N while
    the cylinder is in the air."""
    forces = []

    def watched(obs):
        forces.append((*obs[FORCE], obs[LIFT]))
        return scripted(obs)

    _success_rate(make_env("SoftGraspRigid-v3"), watched, range(100, 104))
    forces = np.array(forces)
    assert forces[:, :2].max() <= 3.6
    lifted = forces[forces[:, 2] > 0.03]
    assert len(lifted) == 0 or lifted[:, :2].max() <= 3.1


def test_reach_start_is_above_and_away_and_options_fix_it(make_env):
    env = make_env("SoftGrasp-v5")
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


def test_start_is_validated():
    with pytest.raises(ValueError, match="start must be one of"):
        gym.make("SoftGrasp-v5", start="fly")
    with pytest.raises(ValueError, match="approach_range"):
        gym.make("SoftGrasp-v5", approach_range=(0.05, 0.2))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(cylinder_radius=0.2), r"does not fit between the open fingers.*at most 0\.0480 m"),
        (dict(cylinder_radius=0.08), r"does not fit between the open fingers"),
        (dict(cylinder_height=0.5), r"too tall for start='reach'.*at most 0\.140 m"),
        (dict(cylinder_height=0.5, start="easy"), r"too tall for start='easy'"),
        (dict(cylinder_radius=0.047), r"randomisation ranges reach a scene that cannot start.*jaw_wedge_range=0\.15"),
        (dict(start="easy", cylinder_position_range=0.05), r"cylinder_position_range=0\.05.*fingers start inside the cylinder"),
    ],
)
def test_geometry_that_cannot_start_is_refused_when_the_env_is_made(kwargs, match):
    """Clashes of geometry: a cylinder wider than the open fingers (0.08 diverged at step 1, 0.12 and
    0.2 started inside the fingers), a cylinder taller than the start (the palm inside it), and
    range extremes that put a finger into the cylinder - each a ValueError naming the settings
    and the limit, at gym.make, not at some later reset."""
    with pytest.raises(ValueError, match=match):
        gym.make("SoftGrasp-v5", **kwargs)


def test_scene_geometry_check_names_the_palm_and_allows_an_offset_along_the_faces():
    with pytest.raises(ValueError, match="palm starts inside the cylinder"):
        SceneConfig(cylinder_height=0.3)
    SceneConfig(lateral_offset=0.03)  # past the face's end along y: no overlap (the stability map's cells)
    with pytest.raises(ValueError, match="fingers start inside the cylinder"):
        SceneConfig(cylinder_xy=(0.03, 0.0))
    with pytest.raises(ValueError, match="reset option|does not fit"):
        env = gym.make("SoftGrasp-v5")
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
    """A wrong-typed option names itself and the type it wants (it used to be
    "TypeError: 'float' object is not iterable"); the env still resets and steps afterwards,
    under gym.make's default checker too."""
    env = gym.make("SoftGraspEasyRigid-v3")
    try:
        with pytest.raises(error, match=match):
            env.reset(seed=0, options=options)
        obs, _ = env.reset(seed=0, options={"cylinder_xy": np.array([0.005, 0.0]), "yaw": np.float32(0.05)})
        obs, *_ = env.step(env.action_space.sample())
        assert np.isfinite(obs).all()
    finally:
        env.close()
