"""softgrasp_env.policies: the scripted grasp and the shipped baselines, from the package itself (the
wheel test runs them from an install outside the checkout; here the loader's behaviour): names and
cards without stable-baselines3, loading with it, a clear error without it, the old
``agents.scripted`` spelling still the same class."""

from __future__ import annotations

import builtins

import gymnasium as gym
import numpy as np
import pytest

from softgrasp_env import policies
from softgrasp_env.policies import ScriptedGraspPolicy, baseline_card, baseline_path, list_baselines, load_baseline
from tests.helpers import run_episode


def test_the_baselines_are_package_data_with_cards():
    names = list_baselines()
    # the v1/v2 set (25) and issue 22's runs (the v3 ids, the goal id's v4) as they are shipped
    assert len([n for n in names if "-v1_" in n or "-v2_" in n]) == 25 and len(names) >= 28, names
    assert {"SoftGrasp-v3_sac_0", "SoftGraspRigid-v3_sac_0", "SoftGraspRigid-v3_ppo_0"} <= set(names)
    assert policies.TRAINED.parent.name == "policies" and policies.TRAINED.parent.parent.name == "softgrasp_env"
    v2 = list_baselines(env="SoftGrasp-v2")
    assert v2 == [f"SoftGrasp-v2_{a}_{s}" for a in ("ppo", "sac") for s in range(3)]
    assert list_baselines(env="SoftGrasp-v2", algo="sac") == [f"SoftGrasp-v2_sac_{s}" for s in range(3)]
    card = baseline_card("SoftGrasp-v2_sac_0")
    assert card["env"] == "SoftGrasp-v2" and card["algo"] == "sac" and card["evaluation"]["episodes"] == 100
    for name in names:
        folder = baseline_path(name)
        assert (folder / "model.zip").is_file() and (folder / "card.json").is_file()


def test_an_unknown_baseline_is_named_with_the_nearest_ones():
    with pytest.raises(ValueError, match=r"no shipped baseline 'SoftGrasp-v2_sac_7' \(did you mean 'SoftGrasp-v2_sac_"):
        baseline_card("SoftGrasp-v2_sac_7")
    with pytest.raises(ValueError, match="no shipped baseline '../trained'"):
        load_baseline("../trained")


def test_a_loaded_baseline_acts_on_raw_observations_as_agents_runs_does():
    from agents.runs import load_run

    b = load_baseline("SoftGraspRigid-v2_ppo_0")
    run = load_run(baseline_path("SoftGraspRigid-v2_ppo_0"))
    env = b.make_env()
    try:
        assert env.spec.id == "SoftGraspRigid-v2" and b.stats is not None and not b.stats.training
        seen = []

        def act(obs):
            action = b.policy(obs)
            assert np.array_equal(action, run.policy(obs))  # the repository's loader agrees
            seen.append(obs)
            return action

        ep = run_episode(env, act, seed=1000, max_steps=5)
        assert ep.steps == 5
        batch, _ = b.predict(np.stack(seen))
        assert batch.shape == (5, 4)
    finally:
        env.close()


def test_a_her_baseline_loads_onto_an_env_of_its_own():
    b = load_baseline("SoftGraspGoal-v1_her-sac_0")
    try:
        assert b.stats is None and b._env is not None
        env = b.make_env()
        obs, _ = env.reset(seed=1000)
        assert env.action_space.contains(np.asarray(b.policy(obs), dtype=np.float32))
        env.close()
    finally:
        b.close()


def test_loading_without_stable_baselines3_names_the_train_extra(monkeypatch):
    real_import = builtins.__import__

    def no_sb3(name, *args, **kwargs):
        if name == "stable_baselines3" or name.startswith("stable_baselines3."):
            raise ModuleNotFoundError("No module named 'stable_baselines3'", name="stable_baselines3")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_sb3)
    assert list_baselines() and baseline_card("SoftGrasp-v2_sac_0")  # cards need no SB3
    with pytest.raises(ImportError, match=r"softgrasp-env\[train\]") as exc:
        load_baseline("SoftGrasp-v2_sac_0")
    assert "SoftGrasp-v2_sac_0" in str(exc.value)


def test_a_missing_old_baseline_says_where_the_old_ones_are():
    """The wheel leaves issue 10's v1/v2 models in the repository: asking an install for one names
    where they are; a missing v3 name gets the plain list."""
    with pytest.raises(ValueError, match="not in the wheel.*source repository"):
        baseline_card("SoftGrasp-v2_sac_7")
    with pytest.raises(ValueError) as exc:
        baseline_card("SoftGrasp-v3_sac_7")
    assert "not in the wheel" not in str(exc.value) and "SoftGrasp-v3_sac_0" in str(exc.value)


def test_the_scripted_policy_is_one_class_under_both_names():
    import agents.scripted

    assert agents.scripted.ScriptedGraspPolicy is ScriptedGraspPolicy  # one implementation, in the package
    env = gym.make("SoftGraspRigid-v2")
    try:
        obs, _ = env.reset(seed=3)
        action = ScriptedGraspPolicy()(obs)
        assert action.shape == (4,) and env.action_space.contains(action)
    finally:
        env.close()
