"""The goal task (SoftGraspGoal-v6, -v5, softgrasp_env/tasks/goal.py): its reward is compute_reward on
(achieved, desired) goals, vectorised over batches, the same online and for HER's relabelled
samples."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from agents.scripted import ScriptedGraspPolicy
from tests.helpers import run_episode


def test_goal_env_compute_reward_is_vectorised_and_matches_step(make_env):
    env = make_env("SoftGraspGoal-v6")
    u = env.unwrapped
    obs, _ = env.reset(seed=0)
    policy = ScriptedGraspPolicy(lift_to=obs["desired_goal"][2] - 0.05)
    rewards = []

    def check(obs, r, term, trunc, info):
        assert r == u.compute_reward(obs["achieved_goal"], obs["desired_goal"], info)
        assert info["is_success"] == (r == 0.0)
        rewards.append(r)

    run_episode(env, policy, seed=0, max_steps=60, on_step=check)  # the same reset: the goal read above
    assert len(rewards) == 60 and rewards[0] == -1.0 and rewards[-1] == 0.0
    ag = np.zeros((5, 3), dtype=np.float32)
    dg = np.zeros((5, 3), dtype=np.float32)
    dg[:, 2] = [0.0, 0.01, 0.019, 0.021, 0.5]
    np.testing.assert_array_equal(u.compute_reward(ag, dg, [{}] * 5), [0, 0, 0, -1, -1])


def test_her_trains_on_the_goal_env():
    from stable_baselines3 import SAC, HerReplayBuffer

    env = gym.make("SoftGraspGoal-v6", max_episode_steps=20)
    try:
        model = SAC("MultiInputPolicy", env, replay_buffer_class=HerReplayBuffer,
                    replay_buffer_kwargs={"n_sampled_goal": 2, "goal_selection_strategy": "future"},
                    learning_starts=40, batch_size=32, seed=0, device="cpu")  # fmt: skip
        model.learn(total_timesteps=80)
        assert model.replay_buffer.size() == 80
        # relabelled samples carry the env's own reward for their (achieved, desired) pair
        batch = model.replay_buffer.sample(64)
        want = env.unwrapped.compute_reward(batch.next_observations["achieved_goal"].numpy(),
                                            batch.next_observations["desired_goal"].numpy(), [{}] * 64)  # fmt: skip
        np.testing.assert_array_equal(batch.rewards.numpy().ravel(), want)
    finally:
        env.close()


def _knock_over(env, seed: int = 0) -> list[tuple[float, bool, bool]]:
    """(reward, terminated, truncated) per step of an episode that drives the open fingers through
    the cylinder 3.5 cm above its centre (it topples by step 15 on seed 0), then sweeps on."""
    obs, _ = env.reset(seed=seed)
    names = env.unwrapped.obs_names
    out = []
    for t in range(200):
        o = obs["observation"] if isinstance(obs, dict) else obs
        rel = o[names.index("cyl_rel_x") : names.index("cyl_rel_z") + 1]
        action = np.array([1.0, 0.0, 0.0, -1.0], dtype=np.float32)
        if t < 30:
            action[:3] = np.clip(20 * (rel + [0.05, 0.0, 0.035]), -1.0, 1.0)
        obs, r, term, trunc, _ = env.step(action)
        out.append((r, term, trunc))
        if term or trunc:
            return out
    raise AssertionError("the episode did not end within 200 steps")


def test_knocking_the_cylinder_over_ends_the_lift_task_but_not_the_goal_episode(make_env):
    # The lift task ends the episode when the cylinder topples ...
    env = make_env("SoftGrasp-v5")
    lift = _knock_over(env)
    assert lift[-1][1] and len(lift) < 30 and env.unwrapped._last.tilt > env.unwrapped.args.lift.max_tilt
    # ... SoftGraspGoal-v6 runs on to its time limit at -1 a step: ending early would pay less (with -1
    # per step HER + SAC learned to topple the cylinder for it), so it is not on offer.
    goal = _knock_over(make_env("SoftGraspGoal-v6"))
    assert len(goal) == gym.spec("SoftGraspGoal-v6").max_episode_steps
    assert goal[-1][2] and not any(term for _, term, _ in goal)
    assert all(r == -1.0 for r, _, _ in goal[len(lift) :])
    # end_when_knocked_over=True keeps the lift task's ends (SoftGraspGoal-v3, retired, had them).
    assert _knock_over(make_env("SoftGraspGoal-v6", end_when_knocked_over=True))[-1][1]
    # a flag, not a truthy value
    with pytest.raises(TypeError, match="end_when_knocked_over must be True or False"):
        gym.make("SoftGraspGoal-v6", end_when_knocked_over="yes")
