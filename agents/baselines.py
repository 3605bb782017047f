"""stable-baselines3 agents for the SoftGrasp environments: one preset per algorithm.

The presets follow what works for manipulation tasks of this size in rl-baselines3-zoo
(FetchPickAndPlace / panda-gym: SAC or TQC with HER, gamma 0.95-0.98) and SB3's PPO defaults for
continuous control, sized for a CPU: they are what the shipped baselines (agents/trained/) were
trained with, not tuned results. On this project's 2-core machine one SAC gradient step costs
~34 ms with 256x256 networks, ~18 ms with 128x128 and ~11 ms even at 64x64 (torch's per-op
overhead), against ~3.4 ms for a soft env step; so SAC uses 128x128 networks and one gradient
step every 2 env steps (``train_freq=2``), and PPO SB3's default 64x64 (its update is cheap).
"""

from __future__ import annotations

import copy
from typing import Any

import gymnasium as gym
from stable_baselines3 import PPO, SAC, HerReplayBuffer
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.vec_env import VecEnv

ALGOS = ("ppo", "sac", "her-sac")

PRESETS: dict[str, dict[str, Any]] = {
    "ppo": {
        "policy": "MlpPolicy",
        "n_steps": 1024,
        "batch_size": 256,
        "n_epochs": 10,
        "gamma": 0.98,
        "gae_lambda": 0.95,
        "learning_rate": 3e-4,
        "policy_kwargs": {"net_arch": [64, 64]},
    },
    "sac": {
        "policy": "MlpPolicy",
        "learning_rate": 1e-3,
        "buffer_size": 300_000,
        "batch_size": 256,
        "gamma": 0.98,
        "tau": 0.02,
        "learning_starts": 1000,
        "train_freq": 2,
        "policy_kwargs": {"net_arch": [128, 128]},
    },
    "her-sac": {
        "policy": "MultiInputPolicy",
        "learning_rate": 1e-3,
        "buffer_size": 300_000,
        "batch_size": 256,
        "gamma": 0.95,
        "tau": 0.05,
        "learning_starts": 1000,
        "replay_buffer_class": HerReplayBuffer,
        "replay_buffer_kwargs": {"n_sampled_goal": 4, "goal_selection_strategy": "future"},
        "train_freq": 2,
        "policy_kwargs": {"net_arch": [128, 128]},
    },
}


def default_algo(env_id: str) -> str:
    """HER for goal-conditioned ids (dict observations), SAC otherwise."""
    space = gym.spec(env_id).entry_point
    return "her-sac" if isinstance(space, str) and space.endswith("GoalEnv") else "sac"


ASYMMETRIC_ALGOS = ("ppo", "sac")
"""The algos with an asymmetric actor-critic policy (softgrasp_env.policies.asymmetric)."""


def asymmetric_policy(algo: str) -> type:
    """The asymmetric actor-critic policy class of ``algo`` (the critic reads the privileged state
    of ``softgrasp_env.wrappers.PrivilegedObservation``, the actor only the env's observation)."""
    from softgrasp_env.policies.asymmetric import AsymmetricActorCriticPolicy, AsymmetricSACPolicy

    if algo not in ASYMMETRIC_ALGOS:
        raise ValueError(f"an asymmetric actor-critic is built for {ASYMMETRIC_ALGOS}, not {algo!r} "
                         "(HER's goal env has dict observations of its own)")  # fmt: skip
    return AsymmetricActorCriticPolicy if algo == "ppo" else AsymmetricSACPolicy


def make_model(algo: str, env: gym.Env | VecEnv, *, seed: int | None = None, asymmetric: bool = False,
               **overrides: Any) -> BaseAlgorithm:  # fmt: skip
    """An SB3 model of ``algo`` (one of :data:`ALGOS`) on ``env`` with the preset, updated by
    ``overrides`` (any keyword of the SB3 class). ``asymmetric``: the preset's policy becomes the
    algo's :func:`asymmetric_policy` (``env`` then gives PrivilegedObservation's dict observations)."""
    if algo not in PRESETS:
        raise ValueError(f"algo must be one of {ALGOS}, got {algo!r}")
    if asymmetric and "policy" in overrides:
        raise ValueError(f"asymmetric=True sets the policy; got policy={overrides['policy']!r} too")
    # A deep copy: SB3 writes into the policy_kwargs it is given (use_sde), which would change the
    # preset for every later model and the hyperparameters a run records.
    kwargs = copy.deepcopy({**PRESETS[algo], **overrides})
    policy = asymmetric_policy(algo) if asymmetric else kwargs.pop("policy")
    kwargs.pop("policy", None)
    cls = PPO if algo == "ppo" else SAC
    if "demo_bc" in kwargs:  # behaviour cloning on the kept demonstrations (train.py --demo-bc)
        if algo != "sac":
            raise ValueError(f"demo_bc is built for sac, not {algo}")
        from agents.demos import DemoSAC

        cls = DemoSAC
    return cls(policy, env, seed=seed, device="cpu", verbose=0, **kwargs)


def model_class(algo: str) -> type[BaseAlgorithm]:
    if algo not in PRESETS:
        raise ValueError(f"algo must be one of {ALGOS}, got {algo!r}")
    return PPO if algo == "ppo" else SAC
