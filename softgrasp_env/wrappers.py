"""Gymnasium wrappers for the SoftGrasp envs.

:class:`PrivilegedObservation` gives a learner the simulator's knowledge beside the observation,
for an asymmetric actor-critic: the critic learns from state no gripper senses (the object's pose,
mass and friction) while the actor acts on the observation alone (Pinto et al. 2018, "Asymmetric
actor critic for image-based robot learning"; TacSL's asymmetric actor-critic distillation, Akinola
et al. 2024). ``softgrasp_env.policies.asymmetric`` holds the stable-baselines3 policies that read
it that way.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from .observation import PRIVILEGED_NAMES

SENSED = "sensed"
"""The key of the env's own observation in :class:`PrivilegedObservation`'s dict."""
PRIVILEGED = "privileged"
"""The key of the privileged state (``PRIVILEGED_NAMES``)."""


class PrivilegedObservation(gym.ObservationWrapper):
    """Observations as ``{"sensed": the env's observation, "privileged": env.privileged_state()}``.

    ``sensed`` is the wrapped env's observation unchanged (its space, its float32 values);
    ``privileged`` the :data:`~softgrasp_env.observation.PRIVILEGED_NAMES` entries as float32, read
    after every reset and step. Rewards, terminations and infos pass through. The env must be a
    SoftGrasp env with a vector observation (the goal env's dict observations are HER's).
    """

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        if not isinstance(env.observation_space, spaces.Box):
            raise ValueError(f"PrivilegedObservation wraps an env with a vector (Box) observation; "
                             f"{_name(env)} has {env.observation_space}")  # fmt: skip
        if not callable(getattr(env.unwrapped, "privileged_state", None)):
            raise ValueError(f"PrivilegedObservation needs a SoftGrasp env (privileged_state()); got {_name(env)}")
        self.observation_space = spaces.Dict({
            SENSED: env.observation_space,
            PRIVILEGED: spaces.Box(-np.inf, np.inf, shape=(len(PRIVILEGED_NAMES),), dtype=np.float32),
        })  # fmt: skip

    def observation(self, observation: Any) -> dict[str, np.ndarray]:
        return {SENSED: observation, PRIVILEGED: self.env.unwrapped.privileged_state().astype(np.float32)}


def _name(env: gym.Env) -> str:
    return env.spec.id if env.spec is not None else type(env.unwrapped).__name__


__all__ = ["PRIVILEGED", "SENSED", "PrivilegedObservation"]
