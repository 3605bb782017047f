"""The scripted policy's SB3 interface: ``predict`` agrees with the callable, on single and on
vectorised observations, and SB3's own evaluator runs it."""

from __future__ import annotations

import numpy as np
import pytest
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy

from agents.scripted import ScriptedGraspPolicy
from tests.helpers import run_episode


def _observations(env, steps: int = 40) -> list:
    """The reset's observation and those of ``steps`` scripted steps (seed 3)."""
    seen = []
    policy = ScriptedGraspPolicy()

    def act(obs):
        seen.append(obs)
        return policy(obs)

    ep = run_episode(env, act, seed=3, max_steps=steps)
    return seen + [ep.observation]


@pytest.mark.parametrize("env_id", ["SoftGraspRigid-v3", "SoftGraspEasyRigid-v3", "SoftGraspGoal-v6"])
def test_predict_matches_the_callable_single_and_batched(env_id, make_env):
    policy = ScriptedGraspPolicy()
    seen = _observations(make_env(env_id))
    assert len(seen) == 41
    for obs in seen:
        action, state = policy.predict(obs, state="s", episode_start=np.array([False]), deterministic=False)
        assert state == "s" and np.array_equal(action, policy(obs))
    if isinstance(seen[0], dict):
        batch = {k: np.stack([o[k] for o in seen]) for k in seen[0]}
    else:
        batch = np.stack(seen)
    actions, _ = policy.predict(batch)
    assert actions.shape == (len(seen), 4)
    assert np.array_equal(actions, np.stack([policy(o) for o in seen]))


def test_predict_rejects_a_wrong_shape():
    policy = ScriptedGraspPolicy()
    with pytest.raises(ValueError, match="shape"):
        policy.predict(np.zeros((2, 5)))
    with pytest.raises(ValueError, match="shape"):
        policy(np.zeros((3, 23)))


def test_sb3_evaluate_policy_runs_the_scripted_policy_on_a_vec_env():
    """SB3's evaluator, two envs side by side: the scripted grasp holds the cylinder, so every
    episode returns about 82 (the dense reward: lift 1 per step once at 5 cm, from step ~18 on);
    zero actions return about -5."""
    venv = make_vec_env("SoftGraspEasyRigid-v3", n_envs=2, seed=0)  # rigid and gentle: quick, and it holds
    try:
        returns, lengths = evaluate_policy(ScriptedGraspPolicy(), venv, n_eval_episodes=2, return_episode_rewards=True)
    finally:
        venv.close()
    assert len(returns) == 2 and all(n == 100 for n in lengths)
    assert min(returns) > 70.0, returns
