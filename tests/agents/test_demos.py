"""train.py --demos (agents/demos.py): scripted episodes in an off-policy learner's replay buffer,
stored as SB3 stores its own transitions (raw observations, scaled actions, time limits as
truncations), on their own seeds; HER's buffer keeps them as episodes it can relabel."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

import softgrasp_env  # noqa: F401  (registers the ids)
import train
from agents.baselines import make_model
from agents.demos import DEMO_SEED_BASE, add_demonstrations, demo_seeds
from softgrasp_env.tasks.goal import DISTANCE_THRESHOLD

GOAL = "SoftGraspGoal-v6"
RIGID = "SoftGraspRigidTorsion-v3"  # the scripted grasp holds there (100 % in the results table)


def test_her_buffer_holds_the_demonstrations_as_relabelable_successful_episodes():
    env = DummyVecEnv([lambda: gym.make(GOAL)])
    model = make_model("her-sac", env, seed=0, buffer_size=1000, learning_starts=10_000)
    stats = add_demonstrations(model, GOAL, {}, 2, seed=3)
    buf = model.replay_buffer
    assert stats["episodes"] == 2 and stats["successes"] == 2
    assert buf.pos == stats["transitions"] == 2 * gym.spec(GOAL).max_episode_steps
    # The first stored observation is the env's own reset observation on the first demo seed.
    first, _ = gym.make(GOAL).reset(seed=DEMO_SEED_BASE + 10_000 * 3)
    for key in first:
        np.testing.assert_array_equal(buf.observations[key][0, 0], first[key])
    # Two episodes of 100 steps each, the second starting where the first ended.
    assert buf.ep_start[0, 0] == 0 and buf.ep_start[100, 0] == 100
    assert buf.ep_length[0, 0] == buf.ep_length[199, 0] == 100
    # Each reached its goal (reward 0 at the end) after lifting the cylinder off the table: the
    # achieved goals HER relabels with are heights above the table, not only the resting spot.
    for ep in (slice(0, 100), slice(100, 200)):
        ach, des = buf.observations["achieved_goal"][ep, 0], buf.observations["desired_goal"][ep, 0]
        assert buf.rewards[ep, 0][-1] == 0.0
        assert np.linalg.norm(buf.next_observations["achieved_goal"][ep, 0][-1] - des[-1]) <= DISTANCE_THRESHOLD
        assert ach[:, 2].max() - ach[0, 2] > 0.04
    # Time limits are truncations (the critic bootstraps past them), stored as SB3 does.
    assert buf.dones[99, 0] == 1.0 and buf.timeouts[99, 0] == 1.0
    assert np.all(np.abs(buf.actions[:200]) <= 1.0)
    # Sampling (with relabelling) works on them.
    sample = buf.sample(64, env=None)
    assert sample.rewards.shape == (64, 1) and set(np.unique(sample.rewards.numpy())) <= {-1.0, 0.0}
    env.close()


def test_a_normalised_sac_run_stores_raw_observations_and_updates_its_statistics():
    venv = VecNormalize(make_vec_env(RIGID, n_envs=1, seed=0), norm_obs=True, norm_reward=False)
    model = make_model("sac", venv, seed=0, buffer_size=500, learning_starts=10_000)
    count = venv.obs_rms.count
    stats = add_demonstrations(model, RIGID, {}, 1, seed=0, norm=venv)
    n = stats["transitions"]
    first, _ = gym.make(RIGID).reset(seed=DEMO_SEED_BASE)
    np.testing.assert_array_equal(model.replay_buffer.observations[0, 0], first)  # raw, not normalised
    assert venv.obs_rms.count == pytest.approx(count + n + 1)  # the reset and every step's observation
    assert stats["successes"] == 1 and model.replay_buffer.pos == n
    venv.close()


def test_demo_seeds_are_per_run_and_bounded():
    assert demo_seeds(0, 2) == [DEMO_SEED_BASE, DEMO_SEED_BASE + 1]
    assert set(demo_seeds(1, 5)).isdisjoint(demo_seeds(0, 5)) and min(demo_seeds(0, 1)) > 1099
    with pytest.raises(ValueError, match="episodes"):
        demo_seeds(0, 10_001)


def test_train_records_the_demonstrations_and_refuses_them_where_they_cannot_go(tmp_path, capsys):
    common = ["--timesteps", "20", "--learning-starts", "1000", "--eval-every", "1000", "--eval-episodes", "1",
              "--no-progress", "--out", str(tmp_path)]  # fmt: skip
    assert train.main(["--env", GOAL, "--demos", "1", *common]) == 0
    meta = json.loads((tmp_path / f"{GOAL}_her-sac_0" / "run.json").read_text())
    assert meta["demos"] == 1 and meta["demonstrations"]["successes"] == 1
    assert meta["demonstrations"]["transitions"] == 100
    for bad, message in ((["--env", RIGID, "--algo", "ppo", "--demos", "2"], "ppo has none"),
                         (["--env", RIGID, "--demos", "0"], "--demos must be >= 1"),
                         (["--resume", str(tmp_path / f"{GOAL}_her-sac_0"), "--demos", "2"], "a resumed run keeps")):  # fmt: skip
        with pytest.raises(SystemExit):
            train.main([*bad, *common])
        assert message in capsys.readouterr().err


def test_her_exploration_counts_the_lifts_in_a_buffer(tmp_path, capsys):
    """benchmarks/her_exploration.py on a buffer of two demonstrations: both lift the cylinder
    past 3 cm and reach their goals."""
    from stable_baselines3.common.save_util import save_to_pkl

    from benchmarks import her_exploration

    env = DummyVecEnv([lambda: gym.make(GOAL)])
    model = make_model("her-sac", env, seed=0, buffer_size=1000, learning_starts=10_000)
    add_demonstrations(model, GOAL, {}, 2, seed=0)
    save_to_pkl(tmp_path / "buffer.pkl", model.replay_buffer)
    env.close()
    assert her_exploration.main([str(tmp_path / "buffer.pkl"), "--blocks", "1"]) == 0
    out = capsys.readouterr().out
    assert "2 complete episodes" in out
    # block, episodes, lift>=1cm, lift>=3cm, steps>=3cm, reached goal, top lift
    last = out.strip().splitlines()[-1].split()
    assert last[0] == "all" and last[1:4] == ["2", "2", "2"] and last[5] == "2" and float(last[4].rstrip("%")) > 20
    with pytest.raises(SystemExit):
        her_exploration.main([str(tmp_path / "nothing.pkl")])


GRIP = "SoftGraspGripRigid-v4"  # rigid: fast; its demonstrations are the slip script's
BLIND = {"tactile": None, "tactile_history": 1}  # the grip id without its taxels


def test_grip_demonstrations_come_from_the_grip_script_and_a_learner_without_taxels_gets_the_same_episodes():
    """On a rigid grip id the demonstrations are the slip script's; a run without the taxels
    stores the same episodes with the taxel entries left out (the taxels change no physics)."""
    stores = {}
    for kwargs in ({}, BLIND):
        venv = make_vec_env(GRIP, n_envs=1, seed=0, env_kwargs=kwargs)
        model = make_model("sac", venv, seed=0, buffer_size=400, learning_starts=10_000)
        stats = add_demonstrations(model, GRIP, kwargs, 1, seed=0)
        assert stats["policy"] == "TactileGripPolicy" and model.replay_buffer.pos == stats["transitions"] > 50
        stores[bool(kwargs)] = (stats, model.replay_buffer, gym.make(GRIP, **kwargs).unwrapped.obs_names)
        venv.close()
    (full, buf, names), (blind, blind_buf, blind_names) = stores[False], stores[True]
    assert full["successes"] == blind["successes"] and full["transitions"] == blind["transitions"]
    assert len(blind_names) < len(names) and not any(n.startswith("tactile") for n in blind_names)
    keep = [names.index(n) for n in blind_names]
    n = full["transitions"]
    np.testing.assert_array_equal(blind_buf.observations[:n, 0], buf.observations[:n, 0][:, keep])
    np.testing.assert_array_equal(blind_buf.actions[:n], buf.actions[:n])
    np.testing.assert_array_equal(blind_buf.rewards[:n], buf.rewards[:n])
    # The blind learner's first observation is its own env's reset observation on the demo seed.
    first, _ = gym.make(GRIP, **BLIND).reset(seed=DEMO_SEED_BASE)
    np.testing.assert_array_equal(blind_buf.observations[0, 0], first)


def test_an_asymmetric_run_stores_the_privileged_state_and_normalises_each_key():
    from softgrasp_env.wrappers import PRIVILEGED, SENSED, PrivilegedObservation

    venv = VecNormalize(make_vec_env(GRIP, n_envs=1, seed=0, env_kwargs=BLIND,
                                     wrapper_class=PrivilegedObservation), norm_obs=True, norm_reward=False)  # fmt: skip
    model = make_model("sac", venv, seed=0, asymmetric=True, buffer_size=400, learning_starts=10_000)
    before = {k: rms.count for k, rms in venv.obs_rms.items()}
    stats = add_demonstrations(model, GRIP, BLIND, 1, seed=0, norm=venv, privileged=True)
    n = stats["transitions"]
    env = PrivilegedObservation(gym.make(GRIP, **BLIND))
    first, _ = env.reset(seed=DEMO_SEED_BASE)
    for key in (SENSED, PRIVILEGED):
        np.testing.assert_array_equal(model.replay_buffer.observations[key][0, 0], first[key])
        assert venv.obs_rms[key].count == pytest.approx(before[key] + n + 1)
    # the privileged state is the episode's own: its mass and friction stay put, its pose moves
    priv = model.replay_buffer.observations[PRIVILEGED][:n, 0]
    assert np.ptp(priv, axis=0).max() > 0.01 and (np.ptp(priv, axis=0) == 0.0).any()
    venv.close()


def test_the_grip_script_is_the_shear_lag_one_on_the_tissue_and_the_slip_one_on_rigid_pads():
    from softgrasp_env.policies.grip import grip_script

    assert type(grip_script(gym.make("SoftGraspGrip-v7"))).__name__ == "ShearLagGripPolicy"
    for env_id in ("SoftGraspGripRigid-v4", "SoftGraspGripRigidTorsion-v4"):
        assert type(grip_script(gym.make(env_id))).__name__ == "TactileGripPolicy"


def _filled(buf, n, start=0):
    """Add n one-env transitions to ``buf`` whose reward is their running number from ``start``."""
    obs = np.zeros((1, *buf.obs_shape), dtype=np.float32)
    for k in range(n):
        buf.add(obs, obs, np.zeros((1, buf.action_dim), dtype=np.float32), np.array([start + k], dtype=np.float32),
                np.array([False]), [{}])  # fmt: skip


def test_a_keeping_buffer_never_overwrites_the_demonstrations_and_gives_them_their_share_of_every_batch():
    from gymnasium import spaces

    from softgrasp_env.policies.replay import DemoReplayBuffer

    box = spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
    buf = DemoReplayBuffer(50, box, box, device="cpu", demo_share=0.25)
    _filled(buf, 10)  # the demonstrations: rewards 0-9
    assert buf.keep_demonstrations() == 10
    _filled(buf, 100, start=100)  # the learner's own: 100-199, wrapping twice round the 40 free slots
    rewards = buf.rewards[:, 0]
    np.testing.assert_array_equal(rewards[:10], np.arange(10))  # kept
    assert rewards[10:].min() >= 100 + 100 - 40  # the newest 40 of the learner's, each once
    assert len(set(rewards[10:])) == 40 and buf.pos == 10 + 100 % 40
    np.random.seed(0)
    for batch in (4, 256):
        r = buf.sample(batch).rewards.numpy()[:, 0]
        assert (r < 10).sum() == round(0.25 * batch)  # a fixed count per batch
        assert set(r[r >= 10]) <= set(rewards[10:])
    # before the learner has a transition of its own the demonstrations are all there is
    fresh = DemoReplayBuffer(50, box, box, device="cpu", demo_share=0.5)
    _filled(fresh, 5)
    fresh.keep_demonstrations()
    assert (fresh.sample(32).rewards.numpy() < 5).all()
    with pytest.raises(RuntimeError, match="keeps 5"):
        fresh.keep_demonstrations()
    for share in (0.0, 1.0, 1.5):
        with pytest.raises(ValueError, match="demo_share"):
            DemoReplayBuffer(50, box, box, device="cpu", demo_share=share)
    with pytest.raises(ValueError, match="optimize_memory_usage"):
        DemoReplayBuffer(50, box, box, device="cpu", demo_share=0.5, optimize_memory_usage=True)
    full = DemoReplayBuffer(20, box, box, device="cpu", demo_share=0.5)
    _filled(full, 19)
    with pytest.raises(ValueError, match="room"):
        full.keep_demonstrations()


def test_train_keeps_the_demonstrations_in_every_batch_with_demo_share(tmp_path, capsys):
    """--demo-share on an asymmetric grip run: the dict buffer keeps the demonstrations through
    training and a resume, the card's hyperparameters name it; bad combinations are refused."""
    import pickle

    from agents.cards import hyperparameters, policy_label
    from softgrasp_env.policies.replay import DictDemoReplayBuffer

    common = ["--timesteps", "120", "--learning-starts", "60", "--eval-every", "1000", "--eval-episodes", "1",
              "--checkpoint-every", "120", "--no-progress", "--out", str(tmp_path)]  # fmt: skip
    assert train.main(["--env", GRIP, "--asymmetric", "--demos", "1", "--demo-share", "0.25",
                       "--algo-kwargs", "buffer_size=400", *common]) == 0  # fmt: skip
    run = tmp_path / f"{GRIP}_sac-asymmetric_0"
    meta = json.loads((run / "run.json").read_text())
    assert meta["demo_share"] == 0.25 and meta["demonstrations"]["share"] == 0.25
    assert hyperparameters(meta)["replay_buffer_class"] == "DictDemoReplayBuffer"
    assert policy_label({"algo": "sac", "asymmetric": True, "demonstrations": meta["demonstrations"]}) == (
        "sac asymmetric + 1 demos (25% of each batch)")
    with open(run / "replay_buffer.pkl", "rb") as f:
        buf = pickle.load(f)
    assert isinstance(buf, DictDemoReplayBuffer) and buf.kept == meta["demonstrations"]["transitions"] == 100
    assert buf.pos == 100 + 120
    assert train.main(["--resume", str(run), "--timesteps", "10", "--no-progress"]) == 0
    with open(run / "replay_buffer.pkl", "rb") as f:
        buf = pickle.load(f)
    assert isinstance(buf, DictDemoReplayBuffer) and buf.kept == 100 and buf.pos == 100 + 130
    # the model names its buffer class by the package's module, so an installed wheel (no agents/)
    # loads it
    import zipfile

    with zipfile.ZipFile(run / "model.zip") as archive:
        data = json.loads(archive.read("data").decode())
    assert data["replay_buffer_class"]["__module__"] == "softgrasp_env.policies.replay"
    for bad, message in ((["--env", GRIP, "--demo-share", "0.5"], "give --demos"),
                         (["--env", GRIP, "--demos", "1", "--demo-share", "1"], "in (0, 1)"),
                         (["--env", GOAL, "--demos", "1", "--demo-share", "0.5"], "not her-sac")):  # fmt: skip
        with pytest.raises(SystemExit):
            train.main([*bad, *common])
        assert message in capsys.readouterr().err


def test_behaviour_cloning_moves_the_actor_to_the_demonstrations_the_critic_rates_higher(monkeypatch):
    """DemoSAC's step: with the critic rating every demonstration above the actor's own action (a
    critic that is the negative distance to the demonstrations' action), the actor's deterministic
    action moves toward it; rated below, nothing is cloned and the actor is left as it was. SAC's
    own update is taken out, so what moves is the cloning alone."""
    import torch as th
    from gymnasium import spaces
    from stable_baselines3 import SAC
    from stable_baselines3.common.logger import configure

    from agents.demos import DemoSAC
    from softgrasp_env.policies.replay import DemoReplayBuffer

    class Still(gym.Env):
        observation_space = spaces.Box(-1.0, 1.0, (3,), dtype=np.float32)
        action_space = spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)

        def reset(self, *, seed=None, options=None):
            return np.zeros(3, dtype=np.float32), {}

        def step(self, action):
            return np.zeros(3, dtype=np.float32), 0.0, False, False, {}

    monkeypatch.setattr(SAC, "train", lambda self, gradient_steps, batch_size=64: None)
    target = np.array([0.6, -0.4], dtype=np.float32)
    for sign, moves in ((1.0, True), (-1.0, False)):
        model = DemoSAC("MlpPolicy", DummyVecEnv([Still]), demo_bc=1.0, learning_starts=10_000, seed=0,
                        replay_buffer_class=DemoReplayBuffer, replay_buffer_kwargs={"demo_share": 0.5},
                        learning_rate=3e-3, device="cpu")  # fmt: skip
        model.set_logger(configure(None, [""]))
        rng = np.random.default_rng(0)
        for k in range(72):  # 64 demonstrations of ``target``, then 8 of the learner's own
            o = rng.uniform(-1, 1, (1, 3)).astype(np.float32)
            act = target[None] if k < 64 else np.zeros((1, 2), np.float32)
            model.replay_buffer.add(o, o, act, np.zeros(1, np.float32), np.array([False]), [{}])
            if k == 63:
                model.replay_buffer.keep_demonstrations()

        def critic(obs, act, sign=sign):  # the demonstrations' action best (sign 1) or worst (-1)
            q = -sign * ((act - th.as_tensor(target)) ** 2).sum(1, keepdim=True)
            return q, q

        model.critic.forward = critic
        obs = th.as_tensor(rng.uniform(-1, 1, (32, 3)).astype(np.float32))
        before = model.actor(obs, deterministic=True).detach().numpy()
        for _ in range(30):
            model.train(gradient_steps=1, batch_size=32)
        after = model.actor(obs, deterministic=True).detach().numpy()
        d0, d1 = np.abs(before - target).mean(), np.abs(after - target).mean()
        if moves:
            assert d1 < 0.5 * d0, (d0, d1)
        else:
            np.testing.assert_array_equal(after, before)
    with pytest.raises(ValueError, match="demo_bc"):
        DemoSAC("MlpPolicy", DummyVecEnv([Still]), demo_bc=-1.0, device="cpu")


def test_train_runs_behaviour_cloning_through_a_resume(tmp_path, capsys):
    from agents.cards import hyperparameters, policy_label
    from agents.demos import DemoSAC
    from softgrasp_env.policies._sb3 import load_model

    common = ["--timesteps", "120", "--learning-starts", "60", "--eval-every", "1000", "--eval-episodes", "1",
              "--no-progress", "--out", str(tmp_path)]  # fmt: skip
    assert train.main(["--env", GRIP, "--demos", "1", "--demo-share", "0.5", "--demo-bc", "2",
                       "--algo-kwargs", "buffer_size=400", *common]) == 0  # fmt: skip
    run = tmp_path / f"{GRIP}_sac_0"
    meta = json.loads((run / "run.json").read_text())
    assert meta["demo_bc"] == 2.0 and meta["demonstrations"]["bc"] == 2.0
    assert hyperparameters(meta)["demo_bc"] == 2.0
    assert policy_label({"algo": "sac", "demonstrations": meta["demonstrations"]}) == (
        "sac + 1 demos (50% of each batch, BC 2)")
    progress = (run / "logs" / "progress.csv").read_text()
    assert "train/bc_loss" in progress and "train/bc_filter" in progress
    assert train.main(["--resume", str(run), "--timesteps", "70", "--no-progress"]) == 0
    assert isinstance(load_model("sac", run / "model.zip", cls=DemoSAC), DemoSAC)
    assert "train/bc_loss" in (run / "logs" / "progress_from_120.csv").read_text()
    with pytest.raises(SystemExit):
        train.main(["--env", GRIP, "--demos", "1", "--demo-bc", "1", *common])
    assert "give --demos N and --demo-share F too" in capsys.readouterr().err
