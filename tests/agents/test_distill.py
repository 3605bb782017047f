"""agents/distill.py: the grip script distilled into a SAC actor, saved as a train.py run.

Tiny runs (a few episodes, a few epochs): the contract, not the learned grip, whose figures are
measured in the documentation (Training)."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

import softgrasp_env  # noqa: F401  (registers the ids)
from agents.baselines import make_model
from agents.demos import demonstrator
from agents.distill import DISTILL_SEED_BASE, collect, distill, fit, main
from agents.runs import load_run

GRIP = "SoftGraspGrip-v7"
NO_TAXELS = {"tactile": None, "tactile_history": 1}


def _tiny(tmp_path, **kwargs):
    return distill(GRIP, episodes=2, rounds=1, round_episodes=1, epochs=2, eval_episodes=1, out=tmp_path,
                   log=lambda _: None, **kwargs)  # fmt: skip


def test_a_distilled_run_is_a_train_py_run_that_loads_and_acts(tmp_path):
    run = _tiny(tmp_path)
    meta = json.loads((run / "run.json").read_text())
    assert meta["algo"] == "sac" and meta["env"] == GRIP and meta["timesteps"] == 300
    assert meta["algo_kwargs"] == {"policy_kwargs": {"net_arch": {"pi": [256, 256], "qf": [64, 64]}}}
    assert (run / "model.zip").stat().st_size < 1.5e6  # the actor, small critics, no optimiser moments
    d = meta["distilled"]
    assert d["expert"] == "ShearLagGripPolicy" and d["episodes"] == 2 and d["rounds"] == 1 and d["noise"] == 0.05
    assert d["seeds"] == f"{DISTILL_SEED_BASE}-{DISTILL_SEED_BASE + 2}" and meta["train_seconds"] > 0
    log = (run / "logs" / "progress.csv").read_text().splitlines()  # the expert's rollouts, as SB3 logs its own
    assert log[0].startswith("time/total_timesteps,time/time_elapsed,rollout/success_rate") and len(log) == 3
    rows = (run / "progress.csv").read_text().splitlines()
    assert rows[0].startswith("timesteps,success_rate") and [r.split(",")[0] for r in rows[1:]] == ["200", "300"]
    loaded = load_run(run)
    assert loaded.stats is not None and not loaded.stats.training
    env = loaded.make_env()
    try:
        obs, _ = env.reset(seed=5)
        action = loaded.policy(obs)
        assert action.shape == (4,) and env.action_space.contains(action.astype(np.float32))
    finally:
        env.close()


def test_without_the_taxels_the_student_reads_the_same_episodes_without_them(tmp_path):
    """The expert grips on the id's own taxels; the learner's observation leaves them out: the
    first observation the student is fitted on is the taxel-free env's own, entry for entry."""
    run = _tiny(tmp_path, env_kwargs=NO_TAXELS)
    loaded = load_run(run)
    blind = gym.make(GRIP, **NO_TAXELS)
    try:
        assert loaded.model.observation_space.shape == blind.observation_space.shape
        assert not any(n.startswith("tactile") for n in blind.unwrapped.obs_names)
        env, expert, project = demonstrator(GRIP, NO_TAXELS)
        try:
            obs, _, _, _ = collect(env, expert, project, [DISTILL_SEED_BASE], noise=0.0, rng=np.random.default_rng(0))
        finally:
            env.close()
        first, _ = blind.reset(seed=DISTILL_SEED_BASE)
        np.testing.assert_array_equal(obs[0], first)
    finally:
        blind.close()


def test_noise_perturbs_what_is_done_not_the_labels():
    """With noise the episode goes elsewhere, but every label is the expert's own action for the
    state it saw (the script run again on the recorded observations gives the same actions)."""
    env, expert, project = demonstrator(GRIP, {})
    try:
        clean_obs, clean_act, _, _ = collect(env, expert, project, [11], noise=0.0, rng=np.random.default_rng(0))
        obs, act, _, _ = collect(env, expert, project, [11], noise=0.3, rng=np.random.default_rng(0))
    finally:
        env.close()
    assert obs.shape[0] == act.shape[0] == 100 and not np.array_equal(obs, clean_obs)
    expert.reset()
    replayed = np.array([expert(o.astype(np.float64)) for o in obs])
    np.testing.assert_allclose(replayed, act, atol=1e-6)
    assert np.all(np.abs(act) <= 1.0)


def test_fitting_moves_the_actor_onto_the_labels():
    venv = VecNormalize(DummyVecEnv([lambda: gym.make(GRIP)]), norm_obs=True, norm_reward=False, training=False)
    model = make_model("sac", venv, seed=0)
    rng = np.random.default_rng(0)
    obs = rng.normal(size=(512, venv.observation_space.shape[0])).astype(np.float32)
    labels = np.tanh(obs[:, :4] @ rng.normal(size=(4, 4))).astype(np.float32) * 0.8
    first = fit(model, venv, obs, labels, epochs=1, batch_size=64, seed=0)
    last = fit(model, venv, obs, labels, epochs=20, batch_size=64, seed=0)
    assert last < 0.3 * first, (first, last)
    np.testing.assert_allclose(venv.obs_rms.mean, obs.mean(axis=0), rtol=1e-6, atol=1e-6)
    venv.close()


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"episodes": 0}, "episodes"), ({"rounds": -1}, "rounds"), ({"noise": 2.0}, "noise"),
    ({"noise": float("nan")}, "noise"), ({"eval_episodes": 0}, "eval_episodes"), ({"net_arch": ()}, "net_arch"),
    ({"net_arch": (64, 0)}, "net_arch"),
])  # fmt: skip
def test_bad_settings_are_refused_by_name(tmp_path, kwargs, match):
    with pytest.raises(ValueError, match=match):
        distill(GRIP, out=tmp_path, **kwargs)


def test_a_lift_id_and_an_existing_run_are_refused(tmp_path):
    with pytest.raises(ValueError, match="grip-force ids"):
        distill("SoftGrasp-v5", out=tmp_path)
    (tmp_path / f"{GRIP}_sac-distilled_0").mkdir()
    (tmp_path / f"{GRIP}_sac-distilled_0" / "model.zip").write_text("x")
    with pytest.raises(SystemExit):
        main(["--env", GRIP, "--out", str(tmp_path)])
