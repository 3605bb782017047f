"""The files of a train.py run, and loading them back: the one place where a run's observation
statistics (VecNormalize) are applied for evaluation, by train.py and by ``agents.evaluate`` alike
(loading a model and its statistics is ``softgrasp_env.policies._sb3``'s, shared with the
package's ``load_baseline``).

A run directory holds ``run.json`` (env id, env kwargs, algo, seed, ...), ``model.zip``,
``vecnormalize.pkl`` (not for HER), ``replay_buffer.pkl`` (off-policy algos) and, with
``--checkpoint-every``, ``checkpoints/model_<N>_steps.zip`` with ``model_vecnormalize_<N>_steps.pkl``
beside it and ``model_replay_buffer_<N>_steps.pkl`` beside the newest (SB3's CheckpointCallback
names; ``--checkpoint-buffers`` says how many buffers stay: Checkpoints).
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.callbacks import CheckpointCallback
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv, VecNormalize

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.policies._sb3 import frozen, load_model, load_stats, saved_algo
from softgrasp_env.wrappers import PrivilegedObservation

CHECKPOINT_PREFIX = "model"
_CHECKPOINT = re.compile(rf"^{CHECKPOINT_PREFIX}_(\d+)_steps\.zip$")
_BUFFER = re.compile(rf"^{CHECKPOINT_PREFIX}_replay_buffer_(\d+)_steps\.pkl$")


class Checkpoints(CheckpointCallback):
    """SB3's CheckpointCallback (model, replay buffer and VecNormalize statistics every
    ``save_freq`` calls, under SB3's names) that keeps the replay buffers of only the ``buffers``
    most recently written checkpoints (None: all of them). A buffer is the whole replay memory,
    about 1.2 GB for a grip id's dict observations at the SAC preset's 300k transitions, so a run checkpointed
    every 25k steps would hold 12 of them by 300k; the models and statistics, small, all stay.
    "Most recently written" is by modification time, not by step count: a run resumed from an
    older checkpoint writes smaller step counts than the files of the branch it left, and it is the
    new branch's buffers that are kept."""

    def __init__(self, *args: Any, buffers: int | None = 1, **kwargs: Any) -> None:
        if buffers is not None and (isinstance(buffers, bool) or not isinstance(buffers, int) or buffers < 0):
            raise ValueError(f"buffers must be None (keep all) or an int >= 0, got {buffers!r}")
        super().__init__(*args, save_replay_buffer=buffers != 0, **kwargs)
        self.buffers = buffers

    def _on_step(self) -> bool:
        out = super()._on_step()
        if self.buffers is not None and self.n_calls % self.save_freq == 0:
            prune_buffers(Path(self.save_path), self.buffers)
        return out


def prune_buffers(checkpoints: Path, keep: int) -> list[Path]:
    """Delete every checkpoint replay buffer in ``checkpoints`` but the ``keep`` most recently
    written (modification time, then step count); returns the deleted paths."""
    found = [(f.stat().st_mtime, int(m.group(1)), f) for f in checkpoints.iterdir() if (m := _BUFFER.match(f.name))]
    found.sort(reverse=True)
    gone = [f for _, _, f in found[keep:]]
    for f in gone:
        f.unlink()
    return gone


@dataclass(frozen=True)
class RunFiles:
    """Where a run's pieces are, for a model saved at the end (``model.zip``) or at a checkpoint."""

    run_dir: Path
    model: Path
    vecnormalize: Path
    """May not exist (HER runs keep raw observations)."""
    replay_buffer: Path
    """May not exist (PPO; runs saved before buffers were kept)."""

    @property
    def meta(self) -> dict[str, Any]:
        """``run.json``, checked: a ValueError naming the file when it cannot be read or lacks what
        loading needs (env id and algo)."""
        return read_meta(self.run_dir / "run.json")


_META_KEYS = {"env": str, "algo": str, "env_kwargs": dict}


def read_meta(path: Path) -> dict[str, Any]:
    try:
        meta = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{str(path)!r} cannot be read: {type(exc).__name__}: {exc}") from None
    if not isinstance(meta, dict):
        raise ValueError(f"{str(path)!r} holds a {type(meta).__name__}, not the object train.py writes")
    for key, kind in _META_KEYS.items():
        if not isinstance(meta.get(key, {} if kind is dict else None), kind):
            raise ValueError(f"{str(path)!r}: {key!r} must be a {kind.__name__}, got {meta.get(key)!r}")
    return meta


def run_files(path: str | Path) -> RunFiles:
    """The files of the run at ``path``: a run directory, its ``model.zip`` or one of its
    checkpoints (``checkpoints/model_<N>_steps.zip``). Raises ``ValueError`` when there is no model
    or no ``run.json`` for it."""
    path = Path(path)
    if path.is_dir():
        path = path / "model.zip"
    if not path.exists():
        raise ValueError(f"no saved model at {str(path)!r}: give a run directory, its model.zip or a checkpoint zip")
    match = _CHECKPOINT.match(path.name)
    if match:
        steps = match.group(1)
        vecnormalize = path.with_name(f"{CHECKPOINT_PREFIX}_vecnormalize_{steps}_steps.pkl")
        replay_buffer = path.with_name(f"{CHECKPOINT_PREFIX}_replay_buffer_{steps}_steps.pkl")
    else:
        vecnormalize, replay_buffer = path.with_name("vecnormalize.pkl"), path.with_name("replay_buffer.pkl")
    for run_dir in (path.parent, path.parent.parent):  # a checkpoint sits one level down
        if (run_dir / "run.json").exists():
            return RunFiles(run_dir, path, vecnormalize, replay_buffer)
    raise ValueError(f"no run.json beside {str(path)!r} (or one level up); was it saved by train.py?")


def make_env(meta: dict[str, Any], *, env_id: str | None = None, **extra: Any) -> gym.Env:
    """The env a run trained on: ``gym.make(meta["env"], **meta["env_kwargs"])`` (``env_id``
    replaces the id, e.g. to try a soft-trained policy on the rigid fingers; ``extra`` adds kwargs
    such as ``render_mode``); a run with an asymmetric actor-critic (``train.py --asymmetric``) gets
    its env in ``PrivilegedObservation``, as it trained."""
    env = gym.make(env_id or meta["env"], **{**meta.get("env_kwargs", {}), **extra})
    return PrivilegedObservation(env) if meta.get("asymmetric") else env


def check_env_matches(meta: dict[str, Any], env: gym.Env | VecEnv, run_json: Path | str, *,
                      other_id: bool = False) -> None:
    """A ValueError naming ``run_json`` and the mismatch when ``env`` is not the env the run
    trained on: another id (unless ``other_id``, e.g. a soft-trained policy tried on the rigid twin
    on purpose), or, always, other observation or action spaces (a SoftGrasp model on the goal
    env's dict observations)."""
    spec = getattr(env, "spec", None)
    env_id = spec.id if spec is not None else None
    if env_id is not None and env_id != meta["env"] and not other_id:
        raise ValueError(f"the env is {env_id!r} but {str(run_json)!r} trained on {meta['env']!r} "
                         "(evaluate.py: add --other-env to run it there on purpose)")  # fmt: skip
    reference = make_env(meta)
    try:
        for name in ("observation_space", "action_space"):
            if getattr(env, name) != getattr(reference, name):
                raise ValueError(f"the env's {name} {getattr(env, name)} is not the {getattr(reference, name)} "
                                 f"that {str(run_json)!r} ({meta['env']!r}) trained on")  # fmt: skip
    finally:
        reference.close()


def normalizer(stats: VecNormalize | None) -> Callable[[Any], Any]:
    """``obs -> the obs the policy saw in training``: the only function evaluation uses to apply
    observation statistics (identity without them). Reads ``stats`` live, so train.py's periodic
    evaluation follows the statistics as they are updated."""
    if stats is None:
        return lambda obs: obs
    return stats.normalize_obs


def deterministic_policy(model: BaseAlgorithm, stats: VecNormalize | None) -> Callable[[Any], np.ndarray]:
    """``obs -> action`` of ``model``'s deterministic policy, observations normalised by ``stats``."""
    norm = normalizer(stats)

    def act(obs):
        return model.predict(norm(obs), deterministic=True)[0]

    return act


@dataclass
class LoadedRun:
    files: RunFiles
    meta: dict[str, Any]
    model: BaseAlgorithm
    stats: VecNormalize | None
    """Frozen observation statistics (``None`` for HER runs)."""

    @property
    def policy(self) -> Callable[[Any], np.ndarray]:
        """The deterministic policy on raw env observations (normalised inside)."""
        return deterministic_policy(self.model, self.stats)

    def make_env(self, **extra: Any) -> gym.Env:
        """A fresh env as the run made it (same id and kwargs); raw observations."""
        return make_env(self.meta, **extra)

    def make_vec_env(self, *, n_envs: int = 1) -> VecEnv:
        """A ``DummyVecEnv`` of the run's env with the frozen statistics applied (for SB3's own
        ``evaluate_policy``): observations come out normalised, rewards do not."""
        venv: VecEnv = DummyVecEnv([self.make_env] * n_envs)
        if self.stats is None:
            return venv
        wrapped = frozen(self.stats)
        wrapped.set_venv(venv)
        return wrapped


def load_run(path: str | Path, *, env: gym.Env | VecEnv | None = None, other_env: bool = False) -> LoadedRun:
    """Model, metadata and frozen observation statistics of the run at ``path`` (see
    :func:`run_files`). HER needs an env to load its buffer; one is made from ``run.json`` unless
    ``env`` is given. A given ``env`` must be the run's (:func:`check_env_matches`; another id
    with the same spaces only with ``other_env``). ValueErrors name the file and what is wrong: a
    damaged ``run.json``, a model saved by another algo than it says, missing statistics."""
    files = run_files(path)
    meta = files.meta
    from agents.baselines import ALGOS

    if meta["algo"] not in ALGOS:
        raise ValueError(f"{str(files.run_dir / 'run.json')!r} names algo {meta['algo']!r}, not one of {ALGOS}")
    found = saved_algo(files.model)
    expected = "sac" if meta["algo"] == "her-sac" else meta["algo"]
    if found is not None and found != expected:
        raise ValueError(f"{str(files.model)!r} holds a {found.upper()} model but "
                         f"{str(files.run_dir / 'run.json')!r} says algo {meta['algo']!r}")  # fmt: skip
    if env is not None:
        check_env_matches(meta, env, files.run_dir / "run.json", other_id=other_env)
    kwargs: dict[str, Any] = {}
    if meta["algo"] == "her-sac":
        kwargs["env"] = env if env is not None else DummyVecEnv([lambda: make_env(meta)])
    model = load_model(meta["algo"], files.model, env=kwargs.get("env"))
    # runs from before run.json said so: every algo but HER trained on normalised observations
    required = bool(meta.get("normalized_observations", meta["algo"] != "her-sac"))
    return LoadedRun(files, meta, model, load_stats(files.vecnormalize, required=required))
