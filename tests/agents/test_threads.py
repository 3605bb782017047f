"""One torch thread per process unless asked, one thread in every env process: the count is
checked, applied to this process and handed to the env processes it starts, and recorded with
the run."""

from __future__ import annotations

import json
import os

import pytest

import train
from agents.evaluate import main as evaluate_main
from agents.threads import CHILD_THREAD_VARIABLES, child_environment, set_threads, threads_error

torch = pytest.importorskip("torch")


@pytest.fixture
def restore_threads():
    """The test process keeps its own thread settings whatever a test sets."""
    before = torch.get_num_threads(), {k: os.environ.get(k) for k in CHILD_THREAD_VARIABLES}
    yield
    torch.set_num_threads(before[0])
    for k, v in before[1].items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


@pytest.mark.parametrize("bad", [0, -1, 1.5, "2", True, None, 10_000])
def test_a_bad_thread_count_is_named(bad):
    problem = threads_error(bad)
    assert problem is not None and "torch threads" in problem
    with pytest.raises(ValueError, match="torch threads"):
        set_threads(bad)


def test_set_threads_applies_here_and_to_the_env_processes_started_later(restore_threads):
    assert threads_error(1) is None and threads_error(2) is None
    got = set_threads(2)
    assert got == {"torch": 2} and torch.get_num_threads() == 2
    # env processes (SubprocVecEnv, Ray workers) start with one thread whatever the learner has
    assert all(os.environ[k] == "1" for k in CHILD_THREAD_VARIABLES)
    assert set_threads(1) == {"torch": 1}
    assert child_environment(3) == {"OMP_NUM_THREADS": "3", "MKL_NUM_THREADS": "3", "OPENBLAS_NUM_THREADS": "3",
                                     "NUMBA_NUM_THREADS": "1"}  # fmt: skip


@pytest.mark.parametrize("main", [train.main, evaluate_main], ids=["train", "evaluate"])
def test_the_command_lines_refuse_a_bad_thread_count_before_anything_runs(main, tmp_path, capsys):
    with pytest.raises(SystemExit):
        main(["--torch-threads", "0", *(["--out", str(tmp_path)] if main is train.main else [])])
    assert "--torch-threads: torch threads must be a whole number >= 1, got 0" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_a_run_records_the_threads_it_trained_on(tmp_path, restore_threads):
    args = ["--env", "SoftGraspEasyRigid-v3", "--algo", "ppo", "--algo-kwargs", "n_steps=64", "batch_size=64",
            "--timesteps", "64", "--eval-every", "64", "--eval-episodes", "1", "--no-progress",
            "--out", str(tmp_path), "--torch-threads", "2"]  # fmt: skip
    assert train.main(args) == 0
    meta = json.loads((tmp_path / "SoftGraspEasyRigid-v3_ppo_0" / "run.json").read_text())
    assert meta["torch_threads"] == 2 and torch.get_num_threads() == 2
