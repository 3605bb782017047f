"""Sharp edges a new user met, each held here: a time limit too short for the carry test
warns at gym.make, the observation Box has the bounds that hold (and every observation lies in
it), agents.evaluate names the env it ran."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest

from softgrasp_env.env import OBS_BOUNDS, observation_box
from softgrasp_env.observation import CARRY_OBS_NAMES, OBS_GROUPS, OBS_NAMES, SHAPE_OBS_NAMES
from softgrasp_env.registration import steps_to_succeed


def _make_warnings(env_id: str, **kwargs) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        env = gym.make(env_id, **kwargs)
    env.close()
    return [str(w.message) for w in caught if "max_episode_steps" in str(w.message)]


def test_a_time_limit_that_ends_before_the_carry_warns_at_make():
    (msg,) = _make_warnings("SoftGrasp-v5", max_episode_steps=60)
    assert "max_episode_steps=60" in msg and "5 s" in msg and ">= 100" in msg
    assert _make_warnings("SoftGrasp-v5") == []  # the registered 100 steps: the carry ends on the last
    assert _make_warnings("SoftGrasp-v5", max_episode_steps=100) == []
    assert _make_warnings("SoftGrasp-v5", max_episode_steps=-1) == []  # no time limit at all
    assert _make_warnings("SoftGraspEasy-v5", max_episode_steps=20) == []  # no carry: a lift may succeed any time
    # the rule follows the carry's settings and the control rate
    (msg,) = _make_warnings("SoftGraspRigid-v3", carry_start=5.0, control_frequency=40.0)
    assert ">= 260" in msg
    assert _make_warnings("SoftGraspRigid-v3", carry_start=2.0) == []


def test_steps_to_succeed_is_the_first_step_the_carry_is_over():
    env = gym.make("SoftGraspRigid-v3", carry_start=1.0, carry_duration=0.5)
    try:
        assert steps_to_succeed(env) == 30
        base = env.unwrapped
        assert base.task.over(30 * base.plan.substeps) and not base.task.over(29 * base.plan.substeps)
    finally:
        env.close()
    env = gym.make("SoftGraspGoal-v5")
    assert steps_to_succeed(env) is None
    env.close()


def test_the_observation_box_is_bounded_where_bounds_hold():
    names = CARRY_OBS_NAMES + SHAPE_OBS_NAMES
    box = observation_box(names)
    for group, (lo, hi) in OBS_BOUNDS.items():
        for name in OBS_GROUPS[group]:
            k = names.index(name)
            assert (box.low[k], box.high[k]) == (np.float32(lo), np.float32(hi)), name
    assert np.isinf(box.low[CARRY_OBS_NAMES.index("finger_gap")])  # soft joint limits: no bound
    box = observation_box(CARRY_OBS_NAMES)
    env = gym.make("SoftGrasp-v5")
    goal = gym.make("SoftGraspGoal-v5")
    try:
        assert env.observation_space == box
        assert goal.observation_space["observation"] == observation_box(OBS_NAMES)
        assert env.observation_space.low[CARRY_OBS_NAMES.index("cyl_axis_z")] == -1.0
    finally:
        env.close()
        goal.close()


@pytest.mark.parametrize("env_id", ["SoftGraspRigid-v3", "SoftGrasp-v4", "SoftGraspGoal-v6"])
def test_every_observation_lies_in_the_box(env_id, make_env, scripted):
    """Scripted grasps (the forces, the lift, the carry) and random flailing (tilts, fast spins)."""
    env = make_env(env_id)
    rng = np.random.default_rng(0)
    for ep in range(2):
        obs, _ = env.reset(seed=ep)
        assert env.observation_space.contains(obs)
        done = False
        while not done:
            action = scripted(obs) if ep == 0 else rng.uniform(-1.0, 1.0, 4).astype(np.float32)
            obs, _, terminated, truncated, _ = env.step(action)
            assert env.observation_space.contains(obs), obs
            done = terminated or truncated


def test_evaluate_names_the_env_it_ran(capsys):
    from agents.evaluate import DEFAULT_ENV, main
    from softgrasp_env import ENV_IDS

    assert DEFAULT_ENV in ENV_IDS  # a registered id, not a retired one
    assert main(["--policy", "scripted", "--episodes", "1"]) == 0
    assert capsys.readouterr().out.startswith(f"{DEFAULT_ENV} / scripted: success")
    assert main(["--policy", "random", "--env", "SoftGraspEasyRigid-v3", "--episodes", "1"]) == 0
    assert capsys.readouterr().out.startswith("SoftGraspEasyRigid-v3 / random: success")
