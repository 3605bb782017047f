"""Loading stable-baselines3 models and their observation statistics: the one implementation that
``softgrasp_env.policies.load_baseline`` and the repository's training and evaluation scripts
share. stable-baselines3 and torch come with the ``[train]`` extra; nothing here
imports them before it is called, so ``import softgrasp_env.policies`` works without them.
"""

from __future__ import annotations

import copy
import json
import pickle
import zipfile
from pathlib import Path
from typing import Any

TRAIN_EXTRA = ("needs stable-baselines3 and torch, the [train] extra: pip install 'softgrasp-env[train]' "
               "(install torch's CPU build first if you have no GPU: pip install torch --index-url "
               "https://download.pytorch.org/whl/cpu)")  # fmt: skip


def require_sb3(what: str):
    """The ``stable_baselines3`` module, or an ImportError naming ``what`` needs it and the extra."""
    try:
        import stable_baselines3
    except ImportError as exc:
        raise ImportError(f"{what} {TRAIN_EXTRA}; importing it failed: {exc}", name=exc.name) from exc
    return stable_baselines3


ALGOS = ("ppo", "sac", "her-sac")


def model_class(algo: str):
    """The SB3 class that loads a model of ``algo`` (HER + SAC is a SAC with a HER buffer)."""
    if algo not in ALGOS:
        raise ValueError(f"algo must be one of {ALGOS}, got {algo!r}")
    sb3 = require_sb3(f"a {algo} model")
    return sb3.PPO if algo == "ppo" else sb3.SAC


def _saved_data(model: Path) -> dict:
    """The ``data`` entry of an SB3 model zip (JSON: the algorithm's saved attributes)."""
    try:
        with zipfile.ZipFile(model) as archive:
            data = json.loads(archive.read("data"))
    except (OSError, KeyError, zipfile.BadZipFile, json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{str(model)!r} is not a model saved by stable-baselines3: {type(exc).__name__}: {exc}") from None
    if not isinstance(data, dict):
        raise ValueError(f"{str(model)!r} is not a model saved by stable-baselines3: its data entry is not a mapping")  # noqa: TRY004 (a bad file, as above)
    return data


def saved_timesteps(model: Path) -> int:
    """The env steps a model zip was trained for (SB3's ``num_timesteps``). Reads the zip only."""
    steps = _saved_data(model).get("num_timesteps")
    if not isinstance(steps, int) or steps < 0:
        raise ValueError(f"{str(model)!r} does not say how many steps it was trained for (num_timesteps: {steps!r})")
    return steps


def saved_algo(model: Path) -> str | None:
    """The SB3 algorithm a model zip was saved by ("ppo" or "sac"), told by the attributes each
    saves in the zip's ``data`` entry (PPO's clip range, SAC's entropy target); ``None`` when the
    zip says neither. Reads the zip only: no SB3 needed."""
    data = _saved_data(model)
    if "clip_range" in data and "n_epochs" in data:
        return "ppo"
    if "target_entropy" in data:
        return "sac"
    return None


def load_model(algo: str, path: str | Path, *, env: Any = None, cls: Any = None):
    """``model_class(algo).load(path)`` on the CPU, onto ``env`` if given (HER's buffer needs one;
    a resumed training run continues on its envs).

    A model saved before the observation Box got its finite bounds (the unit axis, the forces, the
    yaw, the clock) recorded ``Box(-inf, inf)``; SB3 refuses an env whose space differs in anything,
    bounds included. The bounds do not enter an MLP policy (SB3 rescales only image spaces), so
    when only they differ the env's space replaces the saved one. ``cls``: a subclass of the algo's
    SB3 class to load as (a resumed run that trained with one)."""
    cls = model_class(algo) if cls is None else cls
    custom: dict[str, Any] = {}
    if env is not None:
        from stable_baselines3.common.save_util import json_to_data

        with zipfile.ZipFile(path) as archive:  # the saved spaces only, not the weights
            saved = json_to_data(archive.read("data").decode()).get("observation_space")
        if saved is not None and saved != env.observation_space and _same_layout(saved, env.observation_space):
            custom["observation_space"] = env.observation_space
    return cls.load(str(path), env=env, device="cpu", custom_objects=custom or None)


def _same_layout(a: Any, b: Any) -> bool:
    """Two gymnasium spaces alike but for a Box's bounds: same type, shape, dtype and keys."""
    from gymnasium import spaces

    if isinstance(a, spaces.Dict) and isinstance(b, spaces.Dict):
        return a.spaces.keys() == b.spaces.keys() and all(_same_layout(a[k], b[k]) for k in a.spaces)
    if isinstance(a, spaces.Box) and isinstance(b, spaces.Box):
        return a.shape == b.shape and a.dtype == b.dtype
    return a == b


def frozen(stats):
    """A copy of ``stats`` (a VecNormalize) that normalises observations and never updates:
    ``training=False``, ``norm_reward=False`` (evaluation reports the env's own reward)."""
    from stable_baselines3.common.vec_env import VecNormalize

    # Only the statistics are copied: not the envs under them, nor what depends on them (what
    # VecNormalize.__getstate__ leaves out; an unpickled one lacks them, so deepcopy would recurse).
    state = {k: copy.deepcopy(v) for k, v in vars(stats).items() if k not in ("venv", "class_attributes", "returns")}
    out = VecNormalize.__new__(VecNormalize)
    out.__setstate__(state)
    out.training, out.norm_reward = False, False
    return out


def load_stats(path: str | Path, *, required: bool = False):
    """The observation statistics saved by ``VecNormalize.save`` (frozen), or ``None`` when the file
    does not exist and is not ``required``. A missing required file, or one that does not unpickle
    to a VecNormalize, is a ValueError naming it: a policy fed raw observations it was trained on
    normalised ones for fails silently (one baseline: 100 % success with its statistics, 0 % without)."""
    path = Path(path)
    if not path.exists():
        if required:
            raise ValueError(f"observation statistics {str(path)!r} are missing: the run was trained on normalised "
                             "observations and cannot be evaluated without them")  # fmt: skip
        return None
    require_sb3("observation statistics (a pickled VecNormalize)")
    from stable_baselines3.common.vec_env import VecNormalize

    try:
        with open(path, "rb") as f:
            stats = pickle.load(f)
    except Exception as exc:  # pickle raises many kinds on a damaged file
        raise ValueError(f"observation statistics {str(path)!r} cannot be read: {type(exc).__name__}: {exc}") from None
    if not isinstance(stats, VecNormalize):
        raise ValueError(f"observation statistics {str(path)!r} hold a {type(stats).__name__}, not a VecNormalize")
    return frozen(stats)


__all__ = ["ALGOS", "TRAIN_EXTRA", "frozen", "load_model", "load_stats", "model_class", "require_sb3", "saved_algo"]
