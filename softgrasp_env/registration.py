"""The registered environment ids (``gym.make(id)`` after ``import softgrasp_env``)."""

from __future__ import annotations

import gymnasium as gym

MAX_EPISODE_STEPS = 100
"""5 s at the default 20 Hz control frequency."""

_SPECS: dict[str, tuple[str, dict]] = {
    "SoftGrasp-v0": ("softgrasp_env.env:SoftGraspEnv", {"soft": True, "reward_type": "dense"}),
    "SoftGraspRigid-v0": ("softgrasp_env.env:SoftGraspEnv", {"soft": False, "reward_type": "dense"}),
    "SoftGraspSparse-v0": ("softgrasp_env.env:SoftGraspEnv", {"soft": True, "reward_type": "sparse"}),
    "SoftGraspGoal-v0": ("softgrasp_env.env:SoftGraspGoalEnv", {"soft": True}),
}

ENV_IDS: tuple[str, ...] = tuple(_SPECS)
"""Soft fingers with the dense lift reward; the rigid-only twin; the sparse-reward variant; the
goal-conditioned variant (dict observations, ``compute_reward`` for HER)."""


def register_envs() -> None:
    """Register every id in :data:`ENV_IDS` (idempotent: ids already registered are left alone)."""
    for env_id, (entry_point, kwargs) in _SPECS.items():
        if env_id not in gym.registry:
            gym.register(id=env_id, entry_point=entry_point, kwargs=dict(kwargs), max_episode_steps=MAX_EPISODE_STEPS)
