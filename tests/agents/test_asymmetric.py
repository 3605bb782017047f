"""The asymmetric actor-critic: the privileged observation (what it holds, that it follows the
scene), the SB3 policies (the actor never reads a privileged entry, the critic does), and
train.py --asymmetric end to end (train, evaluate, resume, publish a card)."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest
import torch as th
from stable_baselines3 import PPO, SAC
from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

import softgrasp_env  # noqa: F401
from agents.baselines import make_model
from softgrasp_env.observation import PRIVILEGED_NAMES
from softgrasp_env.policies.asymmetric import AsymmetricActorCriticPolicy, AsymmetricSACPolicy, KeysExtractor
from softgrasp_env.wrappers import PRIVILEGED, SENSED, PrivilegedObservation

GRIP = "SoftGraspGripRigid-v5"  # a grip id (no object state observed), on the fast rigid fingers
P = {n: k for k, n in enumerate(PRIVILEGED_NAMES)}


def test_the_privileged_observation_is_the_objects_state_and_the_episodes_draws(make_env):
    plain = make_env(GRIP)
    env = PrivilegedObservation(make_env(GRIP))
    assert set(env.observation_space.spaces) == {SENSED, PRIVILEGED}
    assert env.observation_space[SENSED] == plain.observation_space
    assert env.observation_space[PRIVILEGED].shape == (len(PRIVILEGED_NAMES),)
    # the grip id observes no object state: the privileged part is what it lacks
    assert not set(PRIVILEGED_NAMES) & set(plain.unwrapped.obs_names)
    obs, _ = env.reset(seed=5)
    ref, _ = plain.reset(seed=5)
    rng = np.random.default_rng(0)
    moved = 0.0
    for _ in range(30):
        action = rng.uniform(-1.0, 1.0, plain.action_space.shape).astype(np.float32)
        ref, *_ = plain.step(action)
        obs, *_ = env.step(action)
        assert np.array_equal(obs[SENSED], ref)  # the sensed part is the env's observation, to the bit
        p = obs[PRIVILEGED].astype(np.float64)
        base = env.unwrapped
        cfg = base.scene.config
        x, q, v, w = base.scene.cylinder_state()
        assert np.allclose(p[[P["cyl_rel_x"], P["cyl_rel_y"], P["cyl_rel_z"]]], x - base.scene.grip_point(), atol=1e-6)
        assert np.allclose(p[[P["cyl_vx"], P["cyl_vy"], P["cyl_vz"]]], v, atol=1e-6)
        assert np.allclose(p[[P["object_qx"], P["object_qy"], P["object_qz"], P["object_qw"]]], q, atol=1e-6)
        assert p[P["object_mass"]] == np.float32(cfg.cylinder_mass)
        assert p[P["friction_static"]] == np.float32(cfg.tissue.friction_static)
        moved = max(moved, float(np.linalg.norm(v)))
    assert moved > 0.0  # the object moved in those steps, and the privileged state followed it
    # the episode's drawn mass: other seeds, other masses
    masses = {float(env.reset(seed=s)[0][PRIVILEGED][P["object_mass"]]) for s in range(5)}
    assert len(masses) == 5


def test_the_privileged_observation_refuses_what_it_cannot_wrap(make_env):
    with pytest.raises(ValueError, match="vector"):
        PrivilegedObservation(make_env("SoftGraspGoal-v5"))
    with pytest.raises(ValueError, match="SoftGrasp env"):
        PrivilegedObservation(gym.make("Pendulum-v1"))


@pytest.mark.parametrize("algo", ["sac", "ppo"])
def test_the_actor_reads_only_the_sensed_keys_and_the_critic_reads_both(algo, make_env, tmp_path):
    """Trained a few hundred steps on a grip id: the actor's action is the same with NaN in every
    privileged entry; the critic's value moves with the privileged state; saved and loaded, the
    policy is the same."""
    th.manual_seed(0)
    # as train.py trains: normalised observations (raw taxel pressures saturate a tanh layer)
    venv = VecNormalize(DummyVecEnv([lambda: PrivilegedObservation(gym.make(GRIP))]), norm_reward=False)
    env = PrivilegedObservation(make_env(GRIP))
    small = {"policy_kwargs": {"net_arch": [32, 32]}}
    model = make_model(algo, venv, seed=0, asymmetric=True,
                       **small, **({"learning_starts": 100} if algo == "sac" else {"n_steps": 128, "batch_size": 64}))  # fmt: skip
    assert isinstance(model.policy, AsymmetricSACPolicy if algo == "sac" else AsymmetricActorCriticPolicy)
    model.learn(300)
    venv.training = False
    raw, _ = env.reset(seed=3)
    for _ in range(10):
        raw, *_ = env.step(model.predict(venv.normalize_obs(raw), deterministic=True)[0])
    obs = venv.normalize_obs(raw)
    venv.close()
    action = model.predict(obs, deterministic=True)[0]
    blind = {SENSED: obs[SENSED], PRIVILEGED: np.full_like(obs[PRIVILEGED], np.nan)}
    assert np.all(np.isfinite(action)) and np.array_equal(model.predict(blind, deterministic=True)[0], action)

    def value(o):
        t, _ = model.policy.obs_to_tensor(o)
        with th.no_grad():
            if algo == "sac":
                return float(model.policy.critic(t, th.as_tensor(action[None], dtype=th.float32))[0])
            return float(model.policy.predict_values(t))

    heavier = {SENSED: obs[SENSED], PRIVILEGED: obs[PRIVILEGED].copy()}
    heavier[PRIVILEGED][P["object_mass"]] += 1.0  # one standard deviation of the drawn masses, or more
    assert value(heavier) != value(obs)
    assert not np.isfinite(value(blind))  # the critic does read them
    model.save(tmp_path / "model")
    loaded = (SAC if algo == "sac" else PPO).load(tmp_path / "model", device="cpu")
    assert loaded.policy.actor_keys == (SENSED,)
    assert np.array_equal(loaded.predict(obs, deterministic=True)[0], action)


def test_the_asymmetric_policies_refuse_what_would_leak_or_cannot_be_read(make_env):
    env = PrivilegedObservation(make_env(GRIP))
    with pytest.raises(ValueError, match="share_features_extractor"):
        SAC(AsymmetricSACPolicy, env, policy_kwargs={"share_features_extractor": True}, device="cpu")
    with pytest.raises(ValueError, match="actor_keys"):
        PPO(AsymmetricActorCriticPolicy, env, policy_kwargs={"actor_keys": ("taxels",)}, device="cpu")
    with pytest.raises(ValueError, match="Dict observation"):
        SAC(AsymmetricSACPolicy, make_env(GRIP), device="cpu")
    with pytest.raises(ValueError, match="keys"):
        KeysExtractor(env.observation_space, ("nope",))
    with pytest.raises(ValueError, match="asymmetric"):
        make_model("her-sac", env, asymmetric=True)


def test_train_asymmetric_trains_evaluates_resumes_and_publishes(tmp_path, capsys):
    import train
    from agents import cards
    from agents.evaluate import main as evaluate_main

    args = ["--env", GRIP, "--asymmetric", "--timesteps", "300", "--eval-every", "150", "--eval-episodes", "1",
            "--learning-starts", "110", "--out", str(tmp_path)]  # fmt: skip
    assert train.main(args) == 0
    run = tmp_path / f"{GRIP}_sac-asymmetric_0"
    meta = json.loads((run / "run.json").read_text())
    assert meta["asymmetric"] is True and meta["hyperparameters"]["policy"] == "AsymmetricSACPolicy"
    capsys.readouterr()
    assert evaluate_main(["--policy", str(run), "--episodes", "1"]) == 0  # wrapped as it trained
    assert "success" in capsys.readouterr().out
    assert train.main(["--resume", str(run), "--timesteps", "100", "--no-progress"]) == 0
    plain = tmp_path / "plain"
    assert train.main(["--env", GRIP, "--timesteps", "120", "--learning-starts", "110", "--eval-every", "120",
                       "--eval-episodes", "1", "--out", str(plain)]) == 0  # fmt: skip
    with pytest.raises(SystemExit):  # a plain run stays plain
        train.main(["--resume", str(plain / f"{GRIP}_sac_0"), "--asymmetric", "--timesteps", "10"])
    out = cards.publish(run, episodes=2, dest=tmp_path / "trained")
    card = cards.read_card(out)
    assert card["asymmetric"] is True and cards.policy_label(card) == "sac asymmetric"
    assert "| critic | asymmetric" in (out / "README.md").read_text()
