"""Agents: the scripted policy through the evaluator, train.py end to end (tiny budgets: these
check the plumbing; learning itself is measured by running train.py, see README)."""

from __future__ import annotations

import csv
import json

import gymnasium as gym
import numpy as np
import pytest

import softgrasp_env  # noqa: F401
from agents.baselines import ALGOS, default_algo, make_model
from agents.evaluate import evaluate, load_policy
from agents.evaluate import main as evaluate_main
from agents.scripted import ScriptedGraspPolicy


def test_scripted_policy_succeeds_where_random_actions_do_not():
    env = gym.make("SoftGraspEasyRigid-v3")  # the evaluator, quickly: rigid twin, gentle start
    scripted = evaluate(env, ScriptedGraspPolicy(), episodes=3, seed=100)
    env.action_space.seed(0)
    random = evaluate(env, load_policy("random", env), episodes=3, seed=100)
    env.close()
    assert scripted.success_rate == 1.0 and scripted.mean_final_lift > 0.05 and scripted.diverged == 0
    assert random.success_rate == 0.0 and random.mean_return < scripted.mean_return


def test_evaluate_resets_a_stateful_policy_at_every_episode():
    """The grip task's scripted policies keep state within an episode: the evaluator
    resets them at each episode's start, so every episode meets the policy as it was made."""
    env = gym.make("SoftGraspEasyRigid-v3")

    class Counting:
        def __init__(self):
            self.resets, self.steps, self.longest = 0, 0, 0

        def reset(self):
            self.resets, self.steps = self.resets + 1, 0

        def __call__(self, obs):
            self.steps += 1
            self.longest = max(self.longest, self.steps)
            return np.zeros(env.action_space.shape, dtype=np.float32)

    policy = Counting()
    try:
        ev = evaluate(env, policy, episodes=2, seed=0)
    finally:
        env.close()
    assert policy.resets == 2 and policy.longest == env.spec.max_episode_steps and ev.episodes == 2


def test_evaluate_counts_success_per_object():
    """On an object-set id the evaluation splits its episodes by the object each drew (the card's
    per-object row); on a cylinder id it names none."""
    env = gym.make("SoftGraspObjectsRigidTorsion-v1")
    try:
        ev = evaluate(env, ScriptedGraspPolicy.for_env(env), episodes=3, seed=1000)
        drawn = [env.reset(seed=1000 + k)[1]["object"] for k in range(3)]
    finally:
        env.close()
    assert sum(met for _, met in ev.by_object.values()) == 3
    assert sum(won for won, _ in ev.by_object.values()) == round(ev.success_rate * 3)
    assert {name: drawn.count(name) for name in drawn} == {name: met for name, (_, met) in ev.by_object.items()}
    env = gym.make("SoftGraspEasyRigid-v3")
    try:
        assert evaluate(env, ScriptedGraspPolicy(), episodes=1, seed=0).by_object == {}
    finally:
        env.close()


def test_default_algos_and_presets():
    assert default_algo("SoftGraspGoal-v6") == "her-sac"
    assert default_algo("SoftGrasp-v5") == "sac"
    env = gym.make("SoftGraspRigid-v3")
    for algo in ("ppo", "sac"):
        model = make_model(algo, env, seed=0, **({"n_steps": 64, "batch_size": 64} if algo == "ppo" else {}))
        assert model.gamma == 0.98
    with pytest.raises(ValueError, match="algo"):
        make_model("dqn", env)
    env.close()
    assert set(ALGOS) == {"ppo", "sac", "her-sac"}


@pytest.mark.parametrize(("env_id", "algo", "steps"), [("SoftGraspRigid-v3", "sac", 300),
                                                       ("SoftGraspRigid-v3", "ppo", 1024),
                                                       ("SoftGraspGoal-v6", "her-sac", 230)])  # fmt: skip
def test_train_writes_a_run_that_evaluate_can_load(tmp_path, env_id, algo, steps, capsys):
    import train

    rc = train.main(["--env", env_id, "--algo", algo, "--timesteps", str(steps), "--eval-every", "150",
                     "--eval-episodes", "1", "--learning-starts", "110", "--out", str(tmp_path)])  # fmt: skip
    assert rc == 0
    run = tmp_path / f"{env_id}_{algo}_0"
    meta = json.loads((run / "run.json").read_text())
    assert meta["algo"] == algo and meta["env"] == env_id
    assert (run / "model.zip").exists()
    assert (run / "vecnormalize.pkl").exists() == (algo != "her-sac")
    rows = list(csv.DictReader(open(run / "progress.csv")))
    assert int(rows[-1]["timesteps"]) >= steps
    assert all(np.isfinite(float(r["mean_return"])) for r in rows)
    monitor = list(run.glob("*.monitor.csv"))
    assert monitor and "is_success" in monitor[0].read_text().splitlines()[1]
    assert (run / "replay_buffer.pkl").exists() == (algo != "ppo")  # for --resume
    # The training episodes' success rate (Monitor's is_success), on the on- and off-policy paths.
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    header = (run / "logs" / "progress.csv").read_text().splitlines()[0].split(",")
    acc = EventAccumulator(str(run / "logs"))
    acc.Reload()
    for key in ("rollout/success_rate", "eval/success_rate"):
        assert key in header and key in acc.Tags()["scalars"]
    capsys.readouterr()
    assert evaluate_main(["--env", env_id, "--policy", str(run / "model.zip"), "--episodes", "1"]) == 0
    assert "success" in capsys.readouterr().out
    assert evaluate_main(["--policy", str(run), "--episodes", "1"]) == 0  # the run's env from run.json
    assert "success" in capsys.readouterr().out


def test_train_rejects_bad_arguments(tmp_path):
    import train

    with pytest.raises(SystemExit):
        train.main(["--env", "SoftGrasp-v5", "--algo", "her-sac", "--out", str(tmp_path)])
    with pytest.raises(SystemExit):
        train.main(["--env", "SoftGrasp-v5", "--timesteps", "0", "--out", str(tmp_path)])
    with pytest.raises(SystemExit):
        evaluate_main(["--policy", str(tmp_path / "missing.zip")])


def test_making_a_model_leaves_the_presets_as_they_are():
    """SB3 writes into the policy_kwargs it is given; make_model hands it a copy, so the presets
    (and the hyperparameters train.py records from them) stay what agents/baselines.py says."""
    import copy

    from agents.baselines import PRESETS, make_model

    before = copy.deepcopy(PRESETS)
    env = gym.make("SoftGraspRigid-v3")
    for algo in ("ppo", "sac"):
        make_model(algo, env, seed=0)
    env.close()
    assert PRESETS == before


def test_the_zoo_hyperparameter_files_say_what_the_presets_say():
    """agents/hyperparams/*.yml repeat the presets for rl-baselines3-zoo: their network sizes,
    train_freq, gamma and learning rate must be the presets' (the HER preset once drifted). Each
    preset is the section its YAML anchor is defined on (the other ids' sections merge it), whatever
    id that section is."""
    import re
    from pathlib import Path

    from agents.baselines import PRESETS

    root = Path(__file__).resolve().parents[2] / "agents" / "hyperparams"
    for name, anchors in (("ppo.yml", {"ppo-defaults": "ppo"}),
                          ("sac.yml", {"sac-defaults": "sac", "her-defaults": "her-sac"})):  # fmt: skip
        text = (root / name).read_text()
        for anchor, algo in anchors.items():
            block = re.search(rf"^\S+: &{re.escape(anchor)}\n.*?(?=^\S|\Z)", text, re.S | re.M).group(0)
            preset = PRESETS[algo]
            arch = [int(x) for x in re.search(r"net_arch=\[([\d, ]+)\]", block).group(1).split(",")]
            assert arch == preset["policy_kwargs"]["net_arch"], (name, anchor)
            assert float(re.search(r"gamma: ([\d.]+)", block).group(1)) == preset["gamma"]
            assert float(re.search(r"learning_rate: !!float ([\de.-]+)", block).group(1)) == preset["learning_rate"]
            freq = re.search(r"train_freq: (\d+)", block)
            assert (int(freq.group(1)) if freq else None) == preset.get("train_freq"), (name, anchor)
