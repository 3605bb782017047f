"""The trained baselines: SAC and PPO on the v3 soft fingers, rigid twin and torsional peer
(several seeds each), SAC on the grip-force ids (with and without the taxels) and HER + SAC with
demonstrations on the goal env. Each is a folder of ``trained/`` beside
this file: ``model.zip`` (stable-baselines3), ``vecnormalize.pkl`` (the observation statistics it
was trained with; HER runs have none), ``card.json`` and ``README.md`` (the model card: env, algo,
hyperparameters, steps, seed, success over 100 seeded episodes, the command that made it),
``run.json`` (the training run's record) and the training logs.

    from softgrasp_env.policies import list_baselines, baseline_card, load_baseline

    list_baselines(env="SoftGrasp-v4")          # names; no stable-baselines3 needed
    baseline_card("SoftGrasp-v4_sac_0")         # the card as a dict; no stable-baselines3 needed
    b = load_baseline("SoftGrasp-v4_sac_0")     # needs the [train] extra
    env = b.make_env()                          # the env it trained on, with its kwargs
    obs, _ = env.reset(seed=1000)
    action = b.policy(obs)                      # deterministic; the statistics applied inside

They are package data, not downloads (a download would need a server and a network at run
time): the SAC models are 0.95 MB each, their critics and optimiser state included, so that
training can go on from them. The wheel carries the best baseline of each id (:func:`best_per_env`:
the highest success on its card); the others are in the source repository's folder only, where
these functions find them from a checkout. The repository's ``agents.cards`` publishes new ones
here.
"""

from __future__ import annotations

import difflib
import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ._sb3 import load_model, load_stats, require_sb3, saved_algo

TRAINED = Path(__file__).resolve().parent / "trained"
"""Where the shipped baselines are (one folder each, named ``<env>_<algo>_<seed>``)."""


def _dirs() -> list[Path]:
    return sorted(p.parent for p in TRAINED.glob("*/card.json"))


def list_baselines(*, env: str | None = None, algo: str | None = None) -> list[str]:
    """The names of the shipped baselines, sorted; only those trained on ``env`` and/or by ``algo``
    ("ppo", "sac", "her-sac") if given."""
    out = []
    for d in _dirs():
        card = _read_card(d)
        if (env is None or card["env"] == env) and (algo is None or card["algo"] == algo):
            out.append(d.name)
    return out


def baseline_path(name: str) -> Path:
    """The folder of the shipped baseline ``name``; a ValueError listing the names (and the nearest
    ones) if there is none."""
    if not isinstance(name, str) or "/" in name or "\\" in name or not (TRAINED / name / "card.json").is_file():
        names = [d.name for d in _dirs()]
        near = difflib.get_close_matches(str(name), names, n=3)
        hint = f" (did you mean {', '.join(map(repr, near))}?)" if near else ""
        if re.fullmatch(r"SoftGrasp\w*-v\d+_[\w-]+", str(name)):
            hint += (" (the wheel carries the best baseline of each id only: the others are in the source "
                     "repository's softgrasp_env/policies/trained/, found from a checkout or loaded by path with "
                     "agents.evaluate; the baselines of a retired id ship with the release that last registers it, "
                     "which gym.make of the id names)")  # fmt: skip
        raise ValueError(f"no shipped baseline {name!r}{hint}; the baselines are: {', '.join(names)}")
    return TRAINED / name


def _read_card(model_dir: Path) -> dict[str, Any]:
    return json.loads((model_dir / "card.json").read_text())


def best_per_env(cards: list[dict[str, Any]]) -> dict[str, str]:
    """env id -> the name of its best baseline among ``cards``: the highest ``evaluation.success_rate``,
    ties to the last name in sorted order. What the wheel ships (its package data is checked against it) and
    which learned policy each shipped dataset records."""
    best: dict[str, dict[str, Any]] = {}
    for card in sorted(cards, key=lambda c: c["name"]):
        have = best.get(card["env"])
        if have is None or card["evaluation"]["success_rate"] >= have["evaluation"]["success_rate"]:
            best[card["env"]] = card
    return {env: card["name"] for env, card in sorted(best.items())}


def baseline_card(name: str) -> dict[str, Any]:
    """The model card of baseline ``name`` (``card.json``): env and env kwargs, algo,
    hyperparameters, steps, seed, ``evaluation`` (success rate over 100 seeded episodes, ...),
    versions, wall time, the command that trained it."""
    return _read_card(baseline_path(name))


@dataclass
class Baseline:
    """A loaded baseline: the SB3 model, its frozen observation statistics (``None`` for HER) and
    its card. ``policy(obs)`` and ``predict(obs)`` take the env's raw observations."""

    name: str
    path: Path
    card: dict[str, Any]
    model: Any
    """The stable-baselines3 model (PPO or SAC)."""
    stats: Any
    """The frozen VecNormalize the model was trained behind, or None (HER keeps raw observations)."""
    _env: Any = field(default=None, repr=False)

    @property
    def env_id(self) -> str:
        return self.card["env"]

    @property
    def env_kwargs(self) -> dict[str, Any]:
        return dict(self.card.get("env_kwargs", {}))

    def normalize(self, obs: Any) -> Any:
        """``obs`` as the model saw observations in training (identity without statistics)."""
        return obs if self.stats is None else self.stats.normalize_obs(obs)

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True):
        """SB3's interface (``(action, state)``) on raw observations, one or a batch; deterministic
        unless asked otherwise."""
        return self.model.predict(self.normalize(observation), state=state, episode_start=episode_start,
                                  deterministic=deterministic)  # fmt: skip

    def policy(self, obs: Any) -> np.ndarray:
        """The deterministic action for one raw observation."""
        return self.predict(obs)[0]

    def __call__(self, obs: Any) -> np.ndarray:
        return self.policy(obs)

    def make_env(self, **extra: Any):
        """A new env as the baseline trained on it (same id and kwargs; ``extra`` adds some, such
        as ``render_mode``); an asymmetric actor-critic's in ``PrivilegedObservation``, whose dict
        the model takes (its actor reads the ``sensed`` part alone)."""
        import gymnasium as gym

        import softgrasp_env  # noqa: F401  (registers the ids)

        env = gym.make(self.env_id, **{**self.env_kwargs, **extra})
        if self.card.get("asymmetric"):
            from ..wrappers import PrivilegedObservation

            env = PrivilegedObservation(env)
        return env

    def close(self) -> None:
        """Close the env made for loading a HER model (if any)."""
        if self._env is not None:
            self._env.close()
            self._env = None


def load_baseline(name: str, *, env: Any = None) -> Baseline:
    """Load the shipped baseline ``name`` (see :func:`list_baselines`): model, frozen observation
    statistics, card. Needs stable-baselines3 and torch (the ``[train]`` extra): without them an
    ImportError says so. A HER model loads onto an env (its replay buffer needs one): ``env`` if
    given, else one made from the card (closed by :meth:`Baseline.close`)."""
    path = baseline_path(name)
    card = _read_card(path)
    require_sb3(f"loading the baseline {name!r}")
    algo = card["algo"]
    found = saved_algo(path / "model.zip")
    if found is not None and found != ("sac" if algo == "her-sac" else algo):
        raise ValueError(f"{str(path / 'model.zip')!r} holds a {found.upper()} model but its card says {algo!r}")
    made = None
    load_env = None
    if algo == "her-sac":
        from stable_baselines3.common.vec_env import DummyVecEnv

        base = Baseline(name, path, card, None, None)
        if env is None:
            env = made = base.make_env()
        load_env = DummyVecEnv([lambda: env])
    model = load_model(algo, path / "model.zip", env=load_env)
    stats = load_stats(path / "vecnormalize.pkl", required=algo != "her-sac")
    return Baseline(name, path, card, model, stats, made)


__all__ = ["TRAINED", "Baseline", "baseline_card", "baseline_path", "best_per_env", "list_baselines", "load_baseline"]
