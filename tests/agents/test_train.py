"""train.py's run plumbing: --env-kwargs, the SB3 logger (success rate in csv and tensorboard),
checkpoints and --resume, and the one loader of observation statistics shared with agents.evaluate.
Tiny budgets (64-step PPO rollouts on the rigid fingers): they check the plumbing, not learning."""

from __future__ import annotations

import argparse
import contextlib
import csv
import functools
import json
import re
import shutil

import numpy as np
import pytest

import train
from agents import runs
from agents.evaluate import main as evaluate_main
from softgrasp_env.env import SoftGraspEnv

ENV = "SoftGraspEasyRigid-v3"  # fast, and random actions end episodes (tip the cylinder) within the tiny budgets
TINY_PPO = ["--env", ENV, "--algo", "ppo", "--algo-kwargs", "n_steps=64", "batch_size=64",
            "--timesteps", "64", "--eval-every", "64", "--eval-episodes", "1"]  # fmt: skip


@contextlib.contextmanager
def spy_envs_and_normalizer():
    """Record the kwargs of every SoftGraspEnv made, and every (raw, normalised) observation that
    goes through agents.runs.normalizer (train.py's evaluations and agents.evaluate both)."""
    made: list[dict] = []
    pairs: list[tuple[np.ndarray, np.ndarray]] = []
    init, normalizer = SoftGraspEnv.__init__, runs.normalizer

    @functools.wraps(init)
    def spy_init(self, *args, **kwargs):
        init(self, *args, **kwargs)
        made.append(dict(self._init_kwargs))

    def spy_normalizer(stats):
        norm = normalizer(stats)

        def apply(obs):
            out = norm(obs)
            pairs.append((np.array(obs, copy=True), np.array(out, copy=True)))
            return out

        return apply

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(SoftGraspEnv, "__init__", spy_init)
        mp.setattr(runs, "normalizer", spy_normalizer)
        yield made, pairs


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    """64 PPO steps with --env-kwargs cylinder_mass=0.2 and a checkpoint, progress bar on."""
    out = tmp_path_factory.mktemp("runs")
    with spy_envs_and_normalizer() as (made, pairs):
        assert train.main([*TINY_PPO, "--env-kwargs", "cylinder_mass=0.2", "--checkpoint-every", "64",
                           "--out", str(out)]) == 0  # fmt: skip
    return out / f"{ENV}_ppo_0", made, pairs


def test_parse_kwarg_reads_literals_and_falls_back_to_text():
    assert train.parse_kwarg("cylinder_mass=0.2") == ("cylinder_mass", 0.2)
    assert train.parse_kwarg("carry=False") == ("carry", False)
    assert train.parse_kwarg("goal_height_range=(0.05, 0.07)") == ("goal_height_range", (0.05, 0.07))
    assert train.parse_kwarg("fingers=segmented") == ("fingers", "segmented")
    assert train.parse_kwarg("fingers='segmented'") == ("fingers", "segmented")
    assert train.parse_kwarg("name=a=b") == ("name", "a=b")
    for bad in ("foo", "=1", "two words=1"):
        with pytest.raises(argparse.ArgumentTypeError, match="key=value"):
            train.parse_kwarg(bad)


def test_malformed_env_kwargs_are_argparse_errors_naming_the_item(tmp_path, capsys):
    for args, expect in ((["foo"], "'foo'"), (["cylinder_mass=0.2", "cylinder_mass=0.3"], "given twice"),
                         (["x={1, 2}"], "run.json")):  # fmt: skip
        with pytest.raises(SystemExit) as exc:
            train.main([*TINY_PPO, "--env-kwargs", *args, "--out", str(tmp_path)])
        assert exc.value.code == 2
        err = capsys.readouterr().err
        assert "--env-kwargs" in err and expect in err
    assert not any(tmp_path.iterdir())  # nothing written


def test_unknown_or_bad_env_kwargs_surface_the_envs_own_error(tmp_path, capsys):
    for item, expect in (("no_such_kwarg=1", "no_such_kwarg"), ("cylinder_mass=-1.0", "cylinder_mass")):
        with pytest.raises(SystemExit) as exc:
            train.main([*TINY_PPO, "--env-kwargs", item, "--out", str(tmp_path)])
        assert exc.value.code == 2
        assert expect in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_env_kwargs_reach_every_env_of_the_run_and_of_its_evaluation(tiny_run, capsys):
    run, made, _ = tiny_run
    meta = json.loads((run / "run.json").read_text())
    assert meta["env_kwargs"] == {"cylinder_mass": 0.2} and meta["algo_kwargs"] == {"n_steps": 64, "batch_size": 64}
    assert len(made) >= 2  # the training env and the evaluation env
    assert all(kw["cylinder_mass"] == 0.2 for kw in made)
    loaded = runs.load_run(run)
    env = loaded.make_env()
    assert env.unwrapped._init_kwargs["cylinder_mass"] == 0.2 and env.spec.id == ENV
    env.close()
    with spy_envs_and_normalizer() as (made_eval, _):
        assert evaluate_main(["--policy", str(run), "--episodes", "1"]) == 0
    assert made_eval and all(kw["cylinder_mass"] == 0.2 for kw in made_eval)
    assert capsys.readouterr().out.startswith(f"{ENV} / ")


def test_success_rate_is_logged_to_csv_and_tensorboard(tiny_run):
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    run, _, _ = tiny_run
    header = (run / "logs" / "progress.csv").read_text().splitlines()[0].split(",")
    assert {"eval/success_rate", "time/total_timesteps", "train/loss"} <= set(header)
    acc = EventAccumulator(str(run / "logs"))
    acc.Reload()
    tags = set(acc.Tags()["scalars"])
    assert "eval/success_rate" in tags and "train/loss" in tags
    # Training episodes' success rate (Monitor's is_success): SB3 records it once an episode has
    # ended; 64 steps of random-ish actions may not end one, so it is checked where one has (the
    # resume test below and test_agents' runs) -- here: present iff the monitor has an episode.
    episodes = (run / "0.monitor.csv").read_text().splitlines()[2:]
    assert ("rollout/success_rate" in header) == bool(episodes) == ("rollout/success_rate" in tags)


def test_resume_continues_model_stats_and_timestep_count(tiny_run, tmp_path):
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    src, _, _ = tiny_run
    run = tmp_path / src.name
    shutil.copytree(src, run)
    first = runs.load_run(run)
    assert first.model.num_timesteps == 64
    count = first.stats.obs_rms.count
    first_episodes = (run / "0.monitor.csv").read_text()
    assert train.main(["--resume", str(run), "--timesteps", "128", "--eval-every", "64", "--eval-episodes", "1",
                       "--no-progress"]) == 0  # fmt: skip
    resumed = runs.load_run(run)
    assert resumed.model.num_timesteps == 192
    # The first part's episodes stay; the resumed part's go to a folder of their own.
    assert (run / "0.monitor.csv").read_text() == first_episodes
    assert len((run / "monitor_from_64" / "0.monitor.csv").read_text().splitlines()) > 2
    # The statistics went on from the saved ones: the resumed session's first reset, then 128 steps.
    assert resumed.stats.obs_rms.count == pytest.approx(count + 1 + 128)
    meta = json.loads((run / "run.json").read_text())
    assert meta["num_timesteps"] == 192 and meta["env_kwargs"] == {"cylinder_mass": 0.2}
    assert meta["sessions"][0]["at_timesteps"] == 64
    assert meta["sessions"][0]["replay_buffer"] is None  # PPO keeps no replay buffer to go on with
    with open(run / "progress.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [int(r["timesteps"]) for r in rows] == [64, 128, 192]
    # 128 steps of fresh 100-step episodes: one has ended, so the training success rate is logged.
    header = (run / "logs" / "progress_from_64.csv").read_text().splitlines()[0].split(",")
    assert "rollout/success_rate" in header and "eval/success_rate" in header
    acc = EventAccumulator(str(run / "logs"))
    acc.Reload()
    steps = [e.step for e in acc.Scalars("eval/success_rate")]
    assert steps[0] == 64 and steps[-1] == 192
    assert "rollout/success_rate" in acc.Tags()["scalars"]
    # A resumed run keeps its settings.
    with pytest.raises(SystemExit):
        train.main(["--resume", str(run), "--env-kwargs", "cylinder_mass=0.3", "--timesteps", "64"])
    with pytest.raises(SystemExit):
        train.main(["--resume", str(tmp_path / "nothing_here"), "--timesteps", "64"])


def test_resume_sac_from_a_checkpoint_keeps_its_replay_buffer(tmp_path):
    # learning_starts past the run: the buffer's plumbing is under test, not SAC's (slow) updates.
    sac = ["--env", ENV, "--algo", "sac", "--algo-kwargs", "buffer_size=500", "batch_size=32",
           "--learning-starts", "1000", "--eval-every", "1000", "--eval-episodes", "1", "--no-progress"]  # fmt: skip
    assert train.main([*sac, "--timesteps", "50", "--checkpoint-every", "25", "--checkpoint-buffers", "all",
                       "--out", str(tmp_path)]) == 0  # fmt: skip
    run = tmp_path / f"{ENV}_sac_0"
    checkpoint = run / "checkpoints" / "model_25_steps.zip"
    files = runs.run_files(checkpoint)
    assert files.run_dir == run and files.replay_buffer.exists() and files.vecnormalize.exists()
    assert (run / "replay_buffer.pkl").exists()
    # No evaluation or checkpoint options: the resumed part goes on with the run's (every 25 steps).
    assert train.main(["--resume", str(checkpoint), "--timesteps", "30", "--no-progress"]) == 0
    model = runs.load_run(run).model
    assert model.num_timesteps == 55
    assert (run / "checkpoints" / "model_50_steps.zip").exists()
    session = json.loads((run / "run.json").read_text())["sessions"][-1]
    assert (session["eval_every"], session["eval_episodes"], session["checkpoint_every"]) == (1000, 1, 25)
    assert session["replay_buffer"] is True
    model.load_replay_buffer(str(run / "replay_buffer.pkl"))
    # 24 from the checkpoint's buffer (SB3's CheckpointCallback runs after the 25th env step, before
    # that transition is stored) + 30 new; an empty buffer would give 30.
    assert model.replay_buffer.size() == 24 + 30


def test_checkpoints_keep_only_the_buffers_written_last(tmp_path, capsys):
    sac = ["--env", ENV, "--algo", "sac", "--algo-kwargs", "buffer_size=500", "batch_size=32",
           "--learning-starts", "1000", "--eval-every", "1000", "--eval-episodes", "1", "--no-progress"]  # fmt: skip
    assert train.main([*sac, "--timesteps", "75", "--checkpoint-every", "25", "--out", str(tmp_path)]) == 0
    run = tmp_path / f"{ENV}_sac_0"
    folder = run / "checkpoints"

    def names(kind: str) -> list[str]:
        return sorted(f.name for f in folder.glob(f"model_{kind}*_steps.*"))

    # by default the newest buffer only; every model and its statistics stay
    assert names("replay_buffer_") == ["model_replay_buffer_75_steps.pkl"]
    assert names("vecnormalize_") == [f"model_vecnormalize_{n}_steps.pkl" for n in (25, 50, 75)]
    assert sorted(f.name for f in folder.glob("model_[0-9]*_steps.zip")) == [f"model_{n}_steps.zip" for n in (25, 50, 75)]
    assert json.loads((run / "run.json").read_text())["checkpoint_buffers"] == 1
    # A resume from an older checkpoint whose buffer is gone is refused, naming the file and the way
    # on; with --empty-buffer it goes on with an empty buffer and says so, in the log and in run.json.
    capsys.readouterr()
    with pytest.raises(SystemExit):
        train.main(["--resume", str(folder / "model_25_steps.zip"), "--timesteps", "30", "--no-progress"])
    err = capsys.readouterr().err
    assert "model_replay_buffer_25_steps.pkl" in err and "--empty-buffer" in err and "--checkpoint-buffers" in err
    assert train.main(["--resume", str(folder / "model_25_steps.zip"), "--timesteps", "30", "--no-progress",
                       "--empty-buffer"]) == 0  # fmt: skip
    assert "no replay buffer model_replay_buffer_25_steps.pkl" in capsys.readouterr().out
    assert json.loads((run / "run.json").read_text())["sessions"][-1]["replay_buffer"] is False
    # Its branch wrote step 50 again, after 75: the buffer written last is kept, not the largest step.
    assert names("replay_buffer_") == ["model_replay_buffer_50_steps.pkl"]
    # 0 keeps none
    assert train.main([*sac, "--timesteps", "50", "--checkpoint-every", "25", "--checkpoint-buffers", "0", "--seed", "1",
                       "--out", str(tmp_path)]) == 0  # fmt: skip
    assert not list((tmp_path / f"{ENV}_sac_1" / "checkpoints").glob("model_replay_buffer_*"))
    assert len(list((tmp_path / f"{ENV}_sac_1" / "checkpoints").glob("model_[0-9]*_steps.zip"))) == 2


def test_empty_buffer_is_for_a_resume_only(tmp_path, capsys):
    with pytest.raises(SystemExit):
        train.main(["--env", ENV, "--algo", "sac", "--timesteps", "10", "--empty-buffer", "--out", str(tmp_path)])
    assert "--empty-buffer is for --resume" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("bad", ["-1", "two", "1.5"])
def test_bad_checkpoint_buffer_counts_are_argparse_errors(tmp_path, capsys, bad):
    with pytest.raises(SystemExit):
        train.main(["--env", ENV, "--timesteps", "10", "--checkpoint-buffers", bad, "--out", str(tmp_path)])
    assert "--checkpoint-buffers" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_evaluate_and_train_apply_the_same_observation_statistics(tiny_run):
    run, _, train_pairs = tiny_run
    with spy_envs_and_normalizer() as (_, eval_pairs):
        # train.py evaluates on seed 10_000; the same seed here meets the same episode.
        assert evaluate_main(["--policy", str(run), "--episodes", "1", "--seed", "10000"]) == 0
    assert eval_pairs and len(train_pairs) >= len(eval_pairs)
    last = train_pairs[-len(eval_pairs) :]  # train.py's final evaluation, with the saved statistics
    for (raw_t, norm_t), (raw_e, norm_e) in zip(last, eval_pairs, strict=True):
        np.testing.assert_array_equal(raw_t, raw_e)
        np.testing.assert_array_equal(norm_t, norm_e)
    raw, norm = eval_pairs[0]
    assert not np.allclose(raw, norm)  # the statistics are applied, not skipped
    loaded = runs.load_run(run)
    assert loaded.stats is not None and not loaded.stats.training and not loaded.stats.norm_reward
    venv = loaded.make_vec_env()
    venv.seed(10_000)
    np.testing.assert_allclose(venv.reset()[0], norm, rtol=1e-6)  # SB3's view: the same numbers
    venv.close()


def test_evaluation_refuses_missing_or_damaged_observation_statistics(tiny_run, tmp_path):
    """A run trained on normalised observations cannot be evaluated without its statistics (it used
    to run on raw observations without a word: 100 % vs 0 % success), nor with a damaged file."""
    import shutil

    run = tmp_path / "run"
    shutil.copytree(tiny_run[0], run)
    assert runs.load_run(run).stats is not None
    (run / "vecnormalize.pkl").unlink()
    with pytest.raises(ValueError, match=r"vecnormalize\.pkl' are missing"):
        runs.load_run(run)
    (run / "vecnormalize.pkl").write_bytes(b"not a pickle")
    with pytest.raises(ValueError, match=r"vecnormalize\.pkl' cannot be read"):
        runs.load_run(run)


def test_run_json_records_the_command_steps_time_and_hyperparameters(tiny_run):
    meta = json.loads((tiny_run[0] / "run.json").read_text())
    assert meta["command"].startswith("python train.py --env SoftGraspEasyRigid-v3 --algo ppo")
    assert "cylinder_mass=0.2" in meta["command"]
    # PPO collects whole rollouts: the steps really trained are reported, not the ones asked for
    assert meta["timesteps_trained"] == meta["num_timesteps"] >= 64
    assert meta["train_seconds"] > 0
    assert meta["torch_threads"] == 1  # the default (agents/threads.py)
    hp = meta["hyperparameters"]
    assert hp["n_steps"] == 64 and hp["batch_size"] == 64 and hp["policy_kwargs"] == {"net_arch": [64, 64]}


def test_evaluation_refuses_a_damaged_run_json_or_a_model_of_another_algo(tiny_run, tmp_path):
    run = tmp_path / "run"
    shutil.copytree(tiny_run[0], run)
    meta = json.loads((run / "run.json").read_text())
    (run / "run.json").write_text(json.dumps({**meta, "algo": "sac"}))
    with pytest.raises(ValueError, match=r"model\.zip' holds a PPO model but .*run\.json' says algo 'sac'"):
        runs.load_run(run)
    (run / "run.json").write_text(json.dumps({**meta, "algo": "dqn"}))
    with pytest.raises(ValueError, match=r"run\.json' names algo 'dqn'"):
        runs.load_run(run)
    (run / "run.json").write_text(json.dumps({**meta, "env": 3}))
    with pytest.raises(ValueError, match=r"run\.json': 'env' must be a str"):
        runs.load_run(run)
    (run / "run.json").write_text('{"env": "SoftGrasp-v5",')
    with pytest.raises(ValueError, match=r"run\.json' cannot be read: JSONDecodeError"):
        runs.load_run(run)
    (run / "run.json").write_text(json.dumps(meta))
    (run / "model.zip").write_bytes(b"not a zip")
    with pytest.raises(ValueError, match=r"model\.zip' is not a model saved by stable-baselines3"):
        runs.load_run(run)


def test_evaluation_refuses_another_env_unless_asked_and_never_other_spaces(tiny_run, capsys):
    run = str(tiny_run[0])
    with pytest.raises(SystemExit):
        evaluate_main(["--policy", run, "--env", "SoftGraspRigid-v3", "--episodes", "1"])
    assert "trained on 'SoftGraspEasyRigid-v3'" in capsys.readouterr().err
    # on purpose: the same spaces, another id
    assert evaluate_main(["--policy", run, "--env", "SoftGraspEasy-v5", "--other-env", "--episodes", "1"]) == 0
    assert "SoftGraspEasy-v5" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        evaluate_main(["--policy", run, "--env", "SoftGraspGoal-v6", "--other-env", "--episodes", "1"])
    assert "observation_space Dict(" in capsys.readouterr().err
    with pytest.raises(SystemExit):  # the carry test adds the clock: a policy without it cannot read it
        evaluate_main(["--policy", run, "--env", "SoftGraspRigid-v3", "--other-env", "--episodes", "1"])
    assert "(24,)" in capsys.readouterr().err


def test_train_checks_its_output_before_training(tmp_path, capsys):
    (tmp_path / "file").write_text("")
    with pytest.raises(SystemExit):
        train.main([*TINY_PPO, "--out", str(tmp_path / "file" / "runs")])
    assert "is a file" in capsys.readouterr().err
    (tmp_path / "runs" / f"{ENV}_ppo_0" / "model.zip").mkdir(parents=True)
    with pytest.raises(SystemExit):
        train.main([*TINY_PPO, "--out", str(tmp_path / "runs")])
    assert "exists already" in capsys.readouterr().err  # a run directory with anything in it is kept
    assert not (tmp_path / "runs" / f"{ENV}_ppo_0" / "run.json").exists()  # nothing written


def test_two_subprocess_envs_train_and_report_the_steps_really_taken(tmp_path, capsys):
    """--n-envs 2 (SubprocVecEnv) from train.main, not train.py's own __main__: the workers find
    the ids. PPO collects n_steps per env per rollout: 64 asked, 2 x 64 = 128 taken and reported."""
    assert train.main([*TINY_PPO, "--n-envs", "2", "--no-progress", "--out", str(tmp_path)]) == 0
    meta = json.loads((tmp_path / f"{ENV}_ppo_0" / "run.json").read_text())
    assert meta["n_envs"] == 2 and meta["num_timesteps"] == meta["timesteps_trained"] == 128
    assert "trained 128 steps" in capsys.readouterr().out


def test_train_refuses_to_overwrite_a_run_unless_forced(tmp_path, capsys):
    """The same arguments twice used to overwrite runs/<env>_<algo>_<seed> without a word."""
    args = [*TINY_PPO, "--no-progress", "--out", str(tmp_path)]
    assert train.main(args) == 0
    run = tmp_path / f"{ENV}_ppo_0"
    first = (run / "model.zip").read_bytes()
    (run / "notes.txt").write_text("mine")
    capsys.readouterr()
    with pytest.raises(SystemExit) as exc:
        train.main(args)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "exists already" in err and "--resume" in err and "--force" in err
    assert (run / "model.zip").read_bytes() == first and (run / "notes.txt").exists()  # untouched
    with pytest.raises(SystemExit):
        train.main(["--resume", str(run), "--force", "--timesteps", "64"])
    assert "give one of them" in capsys.readouterr().err
    assert train.main([*args, "--force"]) == 0  # anew: the old run's files are gone
    assert not (run / "notes.txt").exists() and json.loads((run / "run.json").read_text())["num_timesteps"] == 64
    # A variant by --env-kwargs beside it, under a name of its own; it resumes by its path only.
    assert train.main([*args, "--env-kwargs", "cylinder_mass=0.2", "--name", "heavy"]) == 0
    assert json.loads((tmp_path / "heavy" / "run.json").read_text())["env_kwargs"] == {"cylinder_mass": 0.2}
    assert json.loads((run / "run.json").read_text())["env_kwargs"] == {}  # the default-named run untouched
    with pytest.raises(SystemExit):
        train.main(["--resume", str(tmp_path / "heavy"), "--name", "other", "--timesteps", "64"])
    assert "keeps its directory" in capsys.readouterr().err
    for bad in ("", "a/b", ".."):
        with pytest.raises(SystemExit):
            train.main([*args, "--name", bad])
        assert "one directory name" in capsys.readouterr().err


def test_bad_algo_kwargs_are_named_before_anything_is_written(tmp_path, capsys):
    """``learning_rat=1e-3`` used to end in SB3's traceback, with run.json and the monitor files
    already written."""
    base = ["--env", ENV, "--timesteps", "64", "--eval-every", "64", "--eval-episodes", "1", "--no-progress",
            "--out", str(tmp_path)]  # fmt: skip
    for extra, expect in ((["--algo", "sac", "--algo-kwargs", "learning_rat=1e-3"],
                           r"'learning_rat' is not a keyword of SAC \(sac\) \(did you mean 'learning_rate'\?\); valid: "),
                          (["--algo", "ppo", "--algo-kwargs", "learning_starts=10"], "not a keyword of PPO"),
                          (["--algo", "ppo", "--algo-kwargs", "seed=3"], r"'seed' is set by train.py \(use --seed\)"),
                          (["--algo", "ppo", "--algo-kwargs", "n_steps=64", "batch_size=-5"], "ppo cannot be built"),
                          ):  # fmt: skip
        with pytest.raises(SystemExit) as exc:
            train.main([*base, *extra])
        assert exc.value.code == 2
        err = capsys.readouterr().err
        assert re.search(expect, err), err
        if "valid: " in expect:
            assert "batch_size" in err and "learning_rate" in err  # the valid keys are listed
        assert not any(tmp_path.iterdir()), list(tmp_path.iterdir())  # nothing written
