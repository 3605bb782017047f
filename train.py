"""Train a stable-baselines3 agent on a SoftGrasp environment.

    python train.py --env SoftGrasp-v5 --algo sac --timesteps 100000
    python train.py --env SoftGraspGoal-v6 --demos 100   # HER + SAC by default for the goal env
    python train.py --env SoftGraspRigid-v3 --algo ppo --n-envs 2
    python train.py --env SoftGrasp-v5 --env-kwargs cylinder_mass=0.2 fingers="'segmented'"
    python train.py --resume runs/SoftGrasp-v5_sac_0 --timesteps 50000   # 50k more steps
    python train.py --env SoftGrasp-v5 --force       # start runs/SoftGrasp-v5_sac_0 anew (deletes the old run)
    python train.py --env SoftGrasp-v5 --torch-threads 2   # the learner on 2 torch threads (default 1)
    python train.py --env SoftGraspGrip-v7 --asymmetric     # the critic also reads the object's mass, friction, pose

Writes ``<out>/<env>_<algo>_<seed>/``: ``model.zip``, ``vecnormalize.pkl`` (observation statistics,
except for HER), ``replay_buffer.pkl`` (off-policy algos, for --resume), ``run.json`` (the
arguments, env kwargs included, and the sessions), ``*.monitor.csv`` (per episode: return, length,
is_success; a resumed part's in ``monitor_from_<N>/``), ``progress.csv`` (per evaluation: timesteps, success rate, mean return, mean final lift,
wall time), ``logs/`` (SB3's logger: ``progress.csv`` and tensorboard events with
``rollout/success_rate`` of the training episodes and ``eval/*``; a resumed session writes
``progress_from_<N>.csv`` and adds events) and, with ``--checkpoint-every``, ``checkpoints/``.
Evaluate a saved model with ``python -m agents.evaluate --policy <dir>`` (same env, same kwargs).
An existing run directory is never overwritten: ``--resume`` continues it, ``--force`` deletes it
and starts again. ``--algo-kwargs`` are checked against the algorithm's keywords before anything is
written. The learner runs on one torch thread and every env process on one thread
(``--torch-threads N`` for more: agents/threads.py says why, with the figures).
"""

from __future__ import annotations

import argparse
import csv
import difflib
import inspect
import json
import math
import os
import shutil
import sys
import time
from pathlib import Path

import gymnasium as gym
from stable_baselines3.common import logger as sb3_logger
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.off_policy_algorithm import OffPolicyAlgorithm
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecNormalize
from tqdm import tqdm

import softgrasp_env
from agents.baselines import ALGOS, ASYMMETRIC_ALGOS, default_algo, make_model, model_class
from agents.cards import hyperparameters, quote_arg
from agents.cli import kwargs_dict as _kwargs_dict
from agents.cli import parse_kwarg
from agents.demos import MAX_DEMOS, DemoSAC, add_demonstrations, demo_buffer
from agents.evaluate import evaluate
from agents.runs import CHECKPOINT_PREFIX, Checkpoints, deterministic_policy, load_model, make_env, run_files
from agents.threads import DEFAULT_TORCH_THREADS, set_threads, threads_error
from softgrasp_env.policies._sb3 import saved_timesteps
from softgrasp_env.wrappers import PrivilegedObservation

EVAL_EVERY = 10_000  # timesteps between a fresh run's evaluations
EVAL_EPISODES = 10


def _buffers_kept(text: str) -> int | None:
    """--checkpoint-buffers: 'all' (None) or a count >= 0."""
    if text.strip().lower() == "all":
        return None
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is neither a count of buffers (0, 1, 2, ...) nor 'all'") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"{value} buffers: give a count >= 0 or 'all'")
    return value


def _log(message: str) -> None:
    tqdm.write(message)  # prints above a running progress bar instead of through it
    sys.stdout.flush()


class ProgressBar(BaseCallback):
    """A tqdm bar over the session's timesteps, counting from the model's total (so a resumed run
    shows ``60000/110000``). SB3's own ``progress_bar=True`` needs rich (``tqdm.rich``, experimental)
    on top of tqdm; this needs only tqdm."""

    def __init__(self) -> None:
        super().__init__()
        self.bar: tqdm | None = None

    def _on_training_start(self) -> None:
        self.bar = tqdm(total=self.locals["total_timesteps"], initial=self.model.num_timesteps, unit="step",
                        mininterval=1.0, dynamic_ncols=True)  # fmt: skip

    def _on_step(self) -> bool:
        assert self.bar is not None
        self.bar.update(self.model.num_timesteps - self.bar.n)
        return True

    def _on_training_end(self) -> None:
        if self.bar is not None:
            self.bar.update(self.model.num_timesteps - self.bar.n)
            self.bar.close()


class EvalProgress(BaseCallback):
    """At every multiple of ``every`` timesteps: success rate of the deterministic policy on
    ``episodes`` fixed seeds of a separate env (made like the training envs), appended to
    progress.csv and recorded as ``eval/*`` in SB3's logger (csv, tensorboard)."""

    def __init__(self, env: gym.Env, every: int, episodes: int, path: Path, norm: VecNormalize | None, *,
                 rows: list[dict] | None = None) -> None:  # fmt: skip
        super().__init__()
        self.env, self.every, self.episodes, self.path, self.norm = env, every, episodes, path, norm
        self.rows: list[dict] = list(rows or [])
        self.wall_offset = float(self.rows[-1]["wall_seconds"]) if self.rows else 0.0
        self.next_at = every
        self.start = time.perf_counter()

    def _on_training_start(self) -> None:
        self.next_at = (self.model.num_timesteps // self.every + 1) * self.every
        self.start = time.perf_counter()

    def evaluate_now(self) -> dict:
        steps = self.model.num_timesteps
        ev = evaluate(self.env, deterministic_policy(self.model, self.norm), episodes=self.episodes, seed=10_000)
        if self.rows and self.rows[-1]["timesteps"] == steps:
            self.rows.pop()  # the final evaluation supersedes one taken at the same step count
        row = {"timesteps": steps, "success_rate": ev.success_rate, "mean_return": ev.mean_return,
               "mean_final_lift": ev.mean_final_lift, "diverged": ev.diverged,
               "wall_seconds": self.wall_offset + time.perf_counter() - self.start}  # fmt: skip
        self.rows.append(row)
        with open(self.path, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(row))
            w.writeheader()
            w.writerows(self.rows)
        for key in ("success_rate", "mean_return", "mean_final_lift", "diverged"):
            self.logger.record(f"eval/{key}", row[key])
        self.logger.dump(steps)
        _log(f"[{steps:>8d} steps, {row['wall_seconds']:7.0f} s] success {ev.success_rate:.0%}, "
             f"return {ev.mean_return:.2f}, final lift {ev.mean_final_lift * 100:.2f} cm")  # fmt: skip
        return row

    def _on_step(self) -> bool:
        if self.num_timesteps >= self.next_at:
            self.next_at = (self.num_timesteps // self.every + 1) * self.every
            self.evaluate_now()
        return True


def read_progress(path: Path, *, up_to: int) -> list[dict]:
    """The rows of an earlier session's progress.csv taken at most ``up_to`` timesteps (a resume
    from an earlier checkpoint drops the evaluations after it)."""
    if not path.exists():
        return []
    rows = []
    with open(path, newline="") as f:
        table = list(csv.DictReader(f))
    for r in table:
        row = {k: float(v) for k, v in r.items()}
        row["timesteps"], row["diverged"] = int(row["timesteps"]), int(row["diverged"])
        if row["timesteps"] <= up_to:
            rows.append(row)
    return rows


def make_logger(folder: Path, csv_name: str) -> sb3_logger.Logger:
    """SB3's logger writing ``folder/csv_name`` and tensorboard events into ``folder``. Tensorboard
    is a dependency; an install without it still logs the csv (and says so)."""
    folder.mkdir(parents=True, exist_ok=True)
    formats: list[sb3_logger.KVWriter] = [sb3_logger.CSVOutputFormat(str(folder / csv_name))]
    if sb3_logger.SummaryWriter is not None:
        formats.append(sb3_logger.TensorBoardOutputFormat(str(folder)))
    else:
        _log("note: tensorboard is not installed; logging to csv only (pip install tensorboard)")
    return sb3_logger.Logger(folder=str(folder), output_formats=formats)


def _unwritable(run: Path, *, replacing: bool = False) -> str | None:
    """Why the run directory ``run`` cannot be made and written to, or ``None``: checked before
    anything is built, so a bad ``--out`` costs no training. ``replacing``: ``run`` is deleted
    first (``--force``), so only its parent must be writable."""
    if replacing:
        run = run.parent / (run.name + ".replaced")  # what matters is the folder it is made in
    for name in ("model.zip", "vecnormalize.pkl", "run.json"):
        if (run / name).is_dir():
            return f"{str(run / name)!r} is a directory: the run's {name} cannot be saved there"
    parent = run
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        return f"--out: {str(parent)!r} is a file, so {str(run)!r} cannot be made"
    if not os.access(parent, os.W_OK | os.X_OK):
        return f"--out: {str(parent)!r} is not writable, so {str(run)!r} cannot be made"
    return None


SET_BY_TRAIN = {"env": "the env is --env's", "seed": "use --seed", "device": "train.py trains on the CPU",
                "verbose": "train.py logs through SB3's logger"}  # fmt: skip
"""Keywords of the SB3 classes that train.py sets itself, and what to use instead."""


def algo_kwargs_error(algo: str, algo_kwargs: dict) -> str | None:
    """Why ``--algo-kwargs`` cannot build a model of ``algo``, or None: every key must be a keyword
    of the SB3 class (PPO for ppo, SAC for sac and her-sac) that train.py does not set itself.
    Checked before anything is built or written, so a typo costs nothing (it used to surface as
    SB3's traceback after run.json and the monitor files were written)."""
    cls = model_class(algo)
    params = [n for n, prm in inspect.signature(cls.__init__).parameters.items()
              if n != "self" and prm.kind in (prm.POSITIONAL_OR_KEYWORD, prm.KEYWORD_ONLY)]  # fmt: skip
    valid = sorted(n for n in params if n not in SET_BY_TRAIN)
    for key in algo_kwargs:
        if key in SET_BY_TRAIN:
            return f"--algo-kwargs: {key!r} is set by train.py ({SET_BY_TRAIN[key]})"
        if key not in params:
            near = difflib.get_close_matches(key, valid, n=1)
            hint = f" (did you mean {near[0]!r}?)" if near else ""
            return (f"--algo-kwargs: {key!r} is not a keyword of {cls.__name__} ({algo}){hint}; "
                    f"valid: {', '.join(valid)}")  # fmt: skip
    return None


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python train.py", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    parser.add_argument("--env", default=None, choices=softgrasp_env.ENV_IDS, help="default: SoftGrasp-v5")
    parser.add_argument("--env-kwargs", nargs="+", type=parse_kwarg, default=None, metavar="KEY=VALUE",
                        help="keyword arguments of gym.make (values as Python literals, else strings), "
                             "recorded in run.json; e.g. cylinder_mass=0.2 fingers=rigid")  # fmt: skip
    parser.add_argument("--algo", choices=ALGOS, default=None, help="default: her-sac for the goal env, else sac")
    parser.add_argument("--algo-kwargs", nargs="+", type=parse_kwarg, default=None, metavar="KEY=VALUE",
                        help="override the algo preset (any keyword of the SB3 class), e.g. n_steps=256")  # fmt: skip
    parser.add_argument("--timesteps", type=int, default=100_000, help="steps to train (more steps with --resume)")
    parser.add_argument("--seed", type=int, default=None, help="default 0 (with --resume: the run's seed + its steps)")
    parser.add_argument("--n-envs", type=int, default=None, help="parallel envs (subprocesses when > 1); default 1")
    parser.add_argument("--vec", choices=("subproc", "dummy"), default=None,
                        help="how --n-envs > 1 run: 'subproc' (default; one process each, SB3's SubprocVecEnv) or "
                             "'dummy' (in this process, one after the other)")  # fmt: skip
    parser.add_argument("--eval-every", type=int, default=None,
                        help=f"timesteps between evaluations (default {EVAL_EVERY}; with --resume: the run's)")
    parser.add_argument("--eval-episodes", type=int, default=None,
                        help=f"episodes per evaluation (default {EVAL_EPISODES}; with --resume: the run's)")
    parser.add_argument("--learning-starts", type=int, default=None, help="override the preset (off-policy algos)")
    parser.add_argument("--asymmetric", action="store_true",
                        help="an asymmetric actor-critic (sac, ppo): the critic also reads what the simulator "
                             "knows (the object's pose, mass, friction: softgrasp_env.wrappers.PrivilegedObservation), "
                             "the actor only the env's observation (softgrasp_env.policies.asymmetric); the run is "
                             "named <env>_<algo>-asymmetric_<seed>")  # fmt: skip
    parser.add_argument("--demos", type=int, default=None, metavar="N",
                        help="start an off-policy learner's replay buffer with N episodes of the scripted grasp, on the "
                             "grip ids a tactile grip script (agents/demos.py: HER on the goal id never "
                             "lifts the cylinder by itself)")
    parser.add_argument("--demo-share", type=float, default=None, metavar="F",
                        help="with --demos (sac): keep the demonstrations for the whole run and draw the fraction F "
                             "of every batch from them (agents/demos.py DemoReplayBuffer; 0.5 is RLPD's symmetric "
                             "sampling); default: they are ordinary transitions")  # fmt: skip
    parser.add_argument("--demo-bc", type=float, default=None, metavar="LAMBDA",
                        help="with --demo-share: after each round of SAC's updates, a behaviour-cloning step on the "
                             "kept demonstrations with Nair et al.'s Q-filter, weight LAMBDA (agents/demos.py "
                             "DemoSAC); default none")  # fmt: skip
    parser.add_argument(
        "--checkpoint-every",
        type=int,
        default=None,
        metavar="N",
        help="save model, replay buffer and VecNormalize stats every N timesteps to checkpoints/ "
        "(default none; with --resume: the run's)",
    )
    parser.add_argument("--checkpoint-buffers", type=_buffers_kept, default=1, metavar="K",
                        help="keep the replay buffers of the K checkpoints written last and delete older ones (a "
                             "buffer is the whole replay memory: about 1.2 GB on a grip id); 0 saves none, 'all' "
                             "keeps every one (default 1; the models and statistics all stay)")  # fmt: skip
    parser.add_argument("--empty-buffer", action="store_true",
                        help="with --resume (sac, her-sac): go on with an empty replay buffer where the run's is "
                             "missing; without it such a resume is refused")  # fmt: skip
    parser.add_argument("--resume", type=Path, default=None, metavar="PATH",
                        help="continue the run at PATH (its directory, model.zip or a checkpoint zip): model, "
                             "replay buffer and observation statistics, with its settings, writing back into that run "
                             "directory (--out is not used); the timestep count goes on")  # fmt: skip
    parser.add_argument("--force", action="store_true",
                        help="start a new run even if its directory exists: the old run there is deleted first "
                             "(without --force an existing run directory is an error)")  # fmt: skip
    parser.add_argument("--no-progress", action="store_true", help="no progress bar (CI, log files)")
    parser.add_argument("--torch-threads", type=int, default=DEFAULT_TORCH_THREADS, metavar="N",
                        help="torch threads of the learner (default 1: measured fastest on a 2-core machine with "
                             "another run beside it; env processes always take one)")  # fmt: skip
    parser.add_argument("--out", type=Path, default=Path("runs"))
    parser.add_argument("--name", default=None, metavar="NAME",
                        help="the run directory's name under --out (default <env>_<algo>_<seed>); e.g. for a "
                             "variant by --env-kwargs, which the default name does not tell apart")  # fmt: skip
    ns = parser.parse_args(argv)
    if ns.name is not None and (not ns.name.strip() or ns.name in (".", "..") or any(c in ns.name for c in "/\\")):
        parser.error(f"--name {ns.name!r}: a run's name is one directory name (no path separators)")
    problem = threads_error(ns.torch_threads)
    if problem:
        parser.error(f"--torch-threads: {problem}")
    env_kwargs = _kwargs_dict(parser, "--env-kwargs", ns.env_kwargs)
    algo_kwargs = _kwargs_dict(parser, "--algo-kwargs", ns.algo_kwargs)
    for name in ("timesteps", "n_envs", "eval_every", "eval_episodes", "checkpoint_every", "demos"):
        if getattr(ns, name) is not None and getattr(ns, name) < 1:
            parser.error(f"--{name.replace('_', '-')} must be >= 1, got {getattr(ns, name)}")
    if ns.demos is not None and ns.demos > MAX_DEMOS:
        parser.error(f"--demos must be <= {MAX_DEMOS}, got {ns.demos}")
    if ns.demo_share is not None:
        if ns.demos is None:
            parser.error("--demo-share keeps the demonstrations in every batch: give --demos N too")
        if not 0.0 < ns.demo_share < 1.0:
            parser.error(f"--demo-share is a fraction of each batch, in (0, 1); got {ns.demo_share}")
    if ns.demo_bc is not None:
        if ns.demo_share is None:
            parser.error("--demo-bc clones the kept demonstrations: give --demos N and --demo-share F too")
        if not (math.isfinite(ns.demo_bc) and ns.demo_bc > 0.0):
            parser.error(f"--demo-bc is a weight > 0; got {ns.demo_bc}")

    files = None
    if ns.resume is not None:
        try:
            files = run_files(ns.resume)
        except ValueError as exc:
            parser.error(f"--resume: {exc}")
        meta = files.meta
        if ns.name is not None:
            parser.error(f"--name {ns.name!r}: a resumed run keeps its directory ({str(files.run_dir)!r})")
        if ns.demos is not None:
            parser.error("--demos fills a new run's replay buffer before it trains; a resumed run keeps its buffer")
        given = {"env": ns.env, "algo": ns.algo, "env_kwargs": ns.env_kwargs and env_kwargs,
                 "algo_kwargs": ns.algo_kwargs and algo_kwargs, "n_envs": ns.n_envs,
                 "learning_starts": ns.learning_starts, "asymmetric": ns.asymmetric or None}  # fmt: skip
        for name, value in given.items():
            if value is not None and value != meta.get(name, False if name == "asymmetric" else None):
                parser.error(f"--{name.replace('_', '-')} {value!r} differs from the resumed run's "
                             f"{meta.get(name)!r}: a resumed run keeps its settings")  # fmt: skip
        env_id, algo, n_envs = meta["env"], meta["algo"], meta["n_envs"]
        if algo != "ppo" and not files.replay_buffer.exists() and not ns.empty_buffer:
            # SAC resumed on an empty buffer relearns from its own first new steps and forgets: a
            # refusal, not a note in the log (the training page has the measurement)
            why = (" (a checkpoint keeps its buffer only while it is among the last --checkpoint-buffers written)"
                   if files.model.parent.name == "checkpoints" else "")  # fmt: skip
            parser.error(f"--resume: no replay buffer {str(files.replay_buffer)!r} beside {str(files.model)!r}{why}; "
                         "add --empty-buffer to go on with an empty one (an off-policy learner restarted that way "
                         "loses much of what it had learned)")  # fmt: skip
        # How often it evaluates and saves goes on as the run was started unless asked otherwise:
        # a resumed part that fell back to the fresh defaults would save no checkpoint (a cut part
        # is then lost whole) and evaluate on 10 episodes where the run's curve has 50.
        fallback = {"eval_every": EVAL_EVERY, "eval_episodes": EVAL_EPISODES, "checkpoint_every": None}
        for name, default in fallback.items():
            if getattr(ns, name) is None:
                setattr(ns, name, meta.get(name, default))
        env_kwargs, algo_kwargs = meta.get("env_kwargs", {}), meta.get("algo_kwargs", {})
        run = files.run_dir
    else:
        if ns.empty_buffer:
            parser.error("--empty-buffer is for --resume: a new run starts with an empty replay buffer anyway")
        ns.eval_every = EVAL_EVERY if ns.eval_every is None else ns.eval_every
        ns.eval_episodes = EVAL_EPISODES if ns.eval_episodes is None else ns.eval_episodes
        env_id = ns.env or "SoftGrasp-v5"
        algo = ns.algo or default_algo(env_id)
        n_envs = ns.n_envs or 1
        seed = 0 if ns.seed is None else ns.seed
        meta = {"env": env_id, "env_kwargs": env_kwargs, "algo": algo, "algo_kwargs": algo_kwargs, "seed": seed,
                "n_envs": n_envs, "timesteps": ns.timesteps, "eval_every": ns.eval_every,
                "eval_episodes": ns.eval_episodes, "learning_starts": ns.learning_starts,
                "checkpoint_every": ns.checkpoint_every, "checkpoint_buffers": ns.checkpoint_buffers, "demos": ns.demos,
                "demo_share": ns.demo_share, "demo_bc": ns.demo_bc,
                "asymmetric": ns.asymmetric,
                "out": str(ns.out),
                "normalized_observations": default_algo(env_id) != "her-sac",  # the goal env runs raw (HER)
                "softgrasp_env": softgrasp_env.__version__}  # fmt: skip
        run = ns.out / (ns.name or f"{env_id}_{algo}{'-asymmetric' if ns.asymmetric else ''}_{seed}")
    goal = default_algo(env_id) == "her-sac"  # the goal-conditioned ids
    if algo == "her-sac" and not goal:
        parser.error("--algo her-sac needs a goal-conditioned env (SoftGraspGoal-v5 or -v4)")
    if algo == "her-sac" and n_envs != 1:
        parser.error("--algo her-sac runs with --n-envs 1")
    asymmetric = bool(meta.get("asymmetric"))
    if asymmetric and algo not in ASYMMETRIC_ALGOS:
        parser.error(f"--asymmetric is built for {', '.join(ASYMMETRIC_ALGOS)}, not {algo} (the goal env's dict "
                     "observations are HER's)")  # fmt: skip
    if ns.demos is not None and algo == "ppo":
        parser.error("--demos fills a replay buffer; ppo has none (an off-policy algo: sac, her-sac)")
    if ns.demo_share is not None and algo != "sac":
        parser.error(f"--demo-share is built for sac's buffer, not {algo}'s (HER relabels in a buffer of its own)")
    if ns.demo_share is not None and "replay_buffer_class" in algo_kwargs:
        parser.error("--demo-share sets the replay buffer; --algo-kwargs gives replay_buffer_class too")
    if ns.demos is not None and n_envs != 1:
        parser.error("--demos runs with --n-envs 1 (the demonstrations fill a single-env buffer)")
    if files is None:
        problem = algo_kwargs_error(algo, algo_kwargs)
        if problem:
            parser.error(problem)
        if ns.force and ns.resume is not None:
            parser.error("--force starts a run anew; --resume continues one: give one of them")
        if run.exists() and not run.is_dir():
            parser.error(f"{str(run)!r} is a file, not a run directory")
        if run.exists() and any(run.iterdir()) and not ns.force:
            parser.error(f"{str(run)!r} exists already: continue it with --resume {run}, start it anew with --force "
                         "(deletes it), or give another --seed or --out")  # fmt: skip
    elif ns.force:
        parser.error("--force starts a run anew; --resume continues one: give one of them")

    # The evaluation env is made first, in this process: a bad --env-kwargs fails here with the
    # env's own message (naming the key) rather than inside a subprocess, and before any file is written.
    try:
        eval_env = make_env(meta)
    except (TypeError, ValueError) as exc:
        if not env_kwargs:
            raise
        parser.error(f"--env-kwargs {env_kwargs}: {exc}")
    replacing = files is None and ns.force and run.is_dir()
    problem = _unwritable(run, replacing=replacing)
    if problem:
        eval_env.close()
        parser.error(problem)
    if replacing:
        shutil.rmtree(run)  # the old run, replaced as --force asked
    fresh = not run.exists()  # made by this call: removed again if the model cannot be built
    run.mkdir(parents=True, exist_ok=True)
    if files is None:
        (run / "run.json").write_text(json.dumps(meta, indent=2))

    vec = ns.vec or ("subproc" if n_envs > 1 else "dummy")
    vec_cls = SubprocVecEnv if vec == "subproc" else DummyVecEnv
    # The learner's torch threads as asked; one thread per env process (they inherit the
    # environment variables set here; the kernels are serial, more would only compete).
    threads = set_threads(ns.torch_threads)
    # "module:id": a worker process imports softgrasp_env (and with it the ids) before gym.make,
    # whatever the main module is (train.main called from a script or a test, not only train.py).
    # SB3's Monitor opens its file anew: a resumed part writes its episodes to a folder of its own
    # (monitor_from_<steps>/), or it would wipe the earlier parts' record.
    try:
        monitor_dir = run if files is None else run / f"monitor_from_{saved_timesteps(files.model)}"
    except ValueError as exc:
        eval_env.close()
        parser.error(f"--resume: {exc}")
    venv = make_vec_env(f"softgrasp_env:{env_id}", n_envs=n_envs, seed=meta["seed"], vec_env_cls=vec_cls, env_kwargs=env_kwargs,
                        monitor_dir=str(monitor_dir), monitor_kwargs={"info_keywords": ("is_success",)},
                        wrapper_class=PrivilegedObservation if asymmetric else None)  # fmt: skip
    # Positions (cm), velocities and forces (N) differ by orders of magnitude: normalise the
    # observations. HER relabels goals inside its buffer, so the goal env runs unnormalised.
    norm: VecNormalize | None = None
    model: BaseAlgorithm
    if files is None:
        if not goal:
            venv = norm = VecNormalize(venv, norm_obs=True, norm_reward=False)
        overrides = dict(algo_kwargs)
        if ns.learning_starts is not None and algo != "ppo":
            overrides["learning_starts"] = ns.learning_starts
        if ns.demo_share is not None:
            overrides.update(demo_buffer(asymmetric, ns.demo_share))
        if ns.demo_bc is not None:
            overrides["demo_bc"] = ns.demo_bc
        try:
            model = make_model(algo, venv, seed=seed, asymmetric=asymmetric, **overrides)
        except (TypeError, ValueError, AssertionError) as exc:  # a value SB3 refuses (the keys are checked)
            venv.close()
            eval_env.close()
            if fresh:
                shutil.rmtree(run, ignore_errors=True)
            parser.error(f"--algo-kwargs {algo_kwargs}: {algo} cannot be built with them: {type(exc).__name__}: {exc}")
        meta["hyperparameters"] = hyperparameters(meta)  # the preset as it stands, with the overrides
        start = 0
        if ns.demos is not None:
            assert isinstance(model, OffPolicyAlgorithm)  # ppo refused above
            tic = time.perf_counter()
            meta["demonstrations"] = add_demonstrations(model, env_id, env_kwargs, ns.demos, seed=seed, norm=norm,
                                                          privileged=asymmetric)
            meta["demonstrations"]["seconds"] = round(time.perf_counter() - tic, 1)
            if ns.demo_bc is not None:
                meta["demonstrations"]["bc"] = ns.demo_bc
            _log(f"{ns.demos} scripted demonstrations in the replay buffer: {meta['demonstrations']['transitions']} "
                 f"transitions, {meta['demonstrations']['successes']} successes")  # fmt: skip
            (run / "run.json").write_text(json.dumps(meta, indent=2))
    else:
        if not goal:
            if not files.vecnormalize.exists():
                parser.error(
                    f"--resume: no observation statistics {str(files.vecnormalize)!r} for {str(files.model)!r}"
                )
            venv = norm = VecNormalize.load(str(files.vecnormalize), venv)
            norm.training, norm.norm_reward = True, False
        model = load_model(algo, files.model, env=venv, cls=DemoSAC if meta.get("demo_bc") else None)
        start = model.num_timesteps
        if isinstance(model, OffPolicyAlgorithm):
            if files.replay_buffer.exists():
                model.load_replay_buffer(str(files.replay_buffer))
            else:  # refused above unless --empty-buffer
                _log(f"note: no replay buffer {files.replay_buffer.name} beside {files.model.name}; continuing "
                     "with an empty one (--empty-buffer)")  # fmt: skip
        # Fresh episode starts: re-using the run's seed would replay its first episodes.
        seed = meta["seed"] + start if ns.seed is None else ns.seed
        venv.seed(seed)
        model.set_random_seed(seed)
        meta.setdefault("sessions", []).append({"resumed_from": str(files.model), "at_timesteps": start,
                                                "timesteps": ns.timesteps, "seed": seed, "eval_every": ns.eval_every,
                                                "eval_episodes": ns.eval_episodes,
                                                "checkpoint_every": ns.checkpoint_every,
                                                "checkpoint_buffers": ns.checkpoint_buffers,
                                                # whether it went on with its buffer (None: PPO keeps none)
                                                "replay_buffer": None if algo == "ppo" else files.replay_buffer.exists()})  # fmt: skip
    model.set_logger(make_logger(run / "logs", "progress.csv" if start == 0 else f"progress_from_{start}.csv"))

    progress = EvalProgress(eval_env, ns.eval_every, ns.eval_episodes, run / "progress.csv", norm,
                            rows=read_progress(run / "progress.csv", up_to=start) if start else None)  # fmt: skip
    callbacks: list[BaseCallback] = [progress]
    if ns.checkpoint_every is not None:
        callbacks.append(Checkpoints(save_freq=max(ns.checkpoint_every // n_envs, 1), save_path=str(run / "checkpoints"),
                                     name_prefix=CHECKPOINT_PREFIX, save_vecnormalize=True,
                                     buffers=ns.checkpoint_buffers))  # fmt: skip
    if not ns.no_progress:
        callbacks.append(ProgressBar())
    tic = time.perf_counter()
    # log_interval=1: SB3 records rollout/success_rate (from Monitor's is_success) at every dump:
    # every rollout for PPO, every episode for SAC (its default, 4 episodes, skips short runs).
    model.learn(total_timesteps=ns.timesteps, callback=callbacks, log_interval=1, reset_num_timesteps=files is None)
    seconds = time.perf_counter() - tic
    saved_at = time.time()
    model.save(run / "model.zip")
    if norm is not None:
        norm.save(str(run / "vecnormalize.pkl"))
    if isinstance(model, OffPolicyAlgorithm):
        model.save_replay_buffer(str(run / "replay_buffer.pkl"))
    # SB3 saves elsewhere without a word when the name is taken by a folder (model.zip_2): check.
    for name in ("model.zip",) + (("vecnormalize.pkl",) if norm is not None else ()):
        written = run / name
        if not written.is_file() or written.stat().st_mtime < saved_at - 1.0:
            raise SystemExit(f"train.py: error: {str(written)!r} was not written; the trained model is not saved")
    final = progress.evaluate_now()
    model.logger.close()
    eval_env.close()
    venv.close()
    meta["num_timesteps"] = model.num_timesteps
    session = {"command": " ".join(["python", "train.py", *map(quote_arg, sys.argv[1:] if argv is None else argv)]),
               "timesteps_trained": model.num_timesteps - start, "train_seconds": round(seconds, 1),
               "torch_threads": threads["torch"]}  # fmt: skip
    if files is None:
        meta.update(session)
    else:
        meta["sessions"][-1].update(session)
    (run / "run.json").write_text(json.dumps(meta, indent=2))
    _log(f"trained {model.num_timesteps - start} steps in {seconds:.0f} s ({(model.num_timesteps - start) / seconds:.0f} "
         f"steps/s, {threads['torch']} torch thread{'s' if threads['torch'] > 1 else ''}, {model.num_timesteps} in all); final success {final['success_rate']:.0%}; saved to {run}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
