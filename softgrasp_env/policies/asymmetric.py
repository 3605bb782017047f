"""Asymmetric actor-critic policies for stable-baselines3: the critic reads privileged state, the
actor only what the gripper senses.

On a dict observation (``softgrasp_env.wrappers.PrivilegedObservation``: ``sensed`` and
``privileged``) the critic learns values from both keys, so it can tell a heavy, slippery object
from a light one before the taxels do, while the actor - the part that runs on a robot - reads
``sensed`` alone (Pinto et al. 2018, "Asymmetric actor critic for image-based robot learning";
Akinola et al. 2024, TacSL). Both are ordinary SB3 policies (custom feature extractors, no fork of
the algorithms): :class:`AsymmetricSACPolicy` for SAC, :class:`AsymmetricActorCriticPolicy` for
PPO. A model saved with them loads with ``SAC.load`` / ``PPO.load`` once this module is
importable (it needs the ``[train]`` extra: stable-baselines3 and torch).
"""

from __future__ import annotations

from typing import Any

from ._sb3 import require_sb3

require_sb3("softgrasp_env.policies.asymmetric")  # a clear ImportError on a core install

import torch as th  # noqa: E402  (after the check above)
from gymnasium import spaces  # noqa: E402
from stable_baselines3.common.policies import ActorCriticPolicy  # noqa: E402
from stable_baselines3.common.preprocessing import get_flattened_obs_dim  # noqa: E402
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor, MlpExtractor  # noqa: E402
from stable_baselines3.sac.policies import Actor, SACPolicy  # noqa: E402
from torch import nn  # noqa: E402

from ..wrappers import SENSED  # noqa: E402

ACTOR_KEYS: tuple[str, ...] = (SENSED,)
"""The keys the actor reads by default: the gripper's own observation."""


class KeysExtractor(BaseFeaturesExtractor):
    """The entries of ``keys`` of a dict observation, each flattened, concatenated in that order
    (every key of the space, in its order, when ``keys`` is None). Keys it is not given never enter
    its output: a NaN there leaves the features as they were."""

    def __init__(self, observation_space: spaces.Dict, keys: tuple[str, ...] | None = None) -> None:
        if not isinstance(observation_space, spaces.Dict):
            raise ValueError(f"KeysExtractor reads a Dict observation, got {observation_space}")
        keys = tuple(observation_space.spaces) if keys is None else tuple(keys)
        unknown = [k for k in keys if k not in observation_space.spaces]
        if unknown or not keys:
            raise ValueError(f"keys {list(keys)!r}: each must be one of the observation's {list(observation_space.spaces)}")
        super().__init__(observation_space, features_dim=sum(get_flattened_obs_dim(observation_space[k]) for k in keys))
        self.keys = keys

    def forward(self, observations: dict[str, th.Tensor]) -> th.Tensor:
        return th.cat([th.flatten(observations[k], start_dim=1) for k in self.keys], dim=1)


def _checked(observation_space: spaces.Space, actor_keys: tuple[str, ...], kwargs: dict[str, Any],
             what: str) -> tuple[str, ...]:  # fmt: skip
    """The actor's keys, checked, and ``kwargs`` set for the critic (every key, features not shared)."""
    if not isinstance(observation_space, spaces.Dict):
        raise ValueError(f"{what} needs a Dict observation (wrap the env in "
                         f"softgrasp_env.wrappers.PrivilegedObservation), got {observation_space}")  # fmt: skip
    actor_keys = tuple(actor_keys)
    if not actor_keys or any(k not in observation_space.spaces for k in actor_keys):
        raise ValueError(f"actor_keys {list(actor_keys)!r}: each must be one of the observation's "
                         f"{list(observation_space.spaces)}")  # fmt: skip
    if kwargs.get("share_features_extractor"):
        raise ValueError(f"{what}: the actor and the critic read different keys; "
                         "share_features_extractor=True would give the actor the critic's")  # fmt: skip
    kwargs["share_features_extractor"] = False
    if kwargs.get("features_extractor_class", KeysExtractor) is not KeysExtractor:
        raise ValueError(f"{what} reads its keys with KeysExtractor; got features_extractor_class="
                         f"{kwargs['features_extractor_class']!r}")  # fmt: skip
    kwargs["features_extractor_class"] = KeysExtractor
    return actor_keys


class AsymmetricSACPolicy(SACPolicy):
    """SAC's policy with an actor on ``actor_keys`` (default ``("sensed",)``) and critics (and their
    targets) on every key of the observation."""

    def __init__(self, observation_space: spaces.Space, action_space: spaces.Space, lr_schedule: Any, *args: Any,
                 actor_keys: tuple[str, ...] = ACTOR_KEYS, **kwargs: Any) -> None:  # fmt: skip
        keys = _checked(observation_space, actor_keys, kwargs, type(self).__name__)
        # set before SACPolicy.__init__, which builds the actor
        object.__setattr__(self, "actor_keys", keys)
        super().__init__(observation_space, action_space, lr_schedule, *args, **kwargs)

    def make_actor(self, features_extractor: BaseFeaturesExtractor | None = None) -> Actor:
        return super().make_actor(KeysExtractor(self.observation_space, self.actor_keys))

    def _get_constructor_parameters(self) -> dict[str, Any]:
        return {**super()._get_constructor_parameters(), "actor_keys": self.actor_keys}


class _SplitMlpExtractor(nn.Module):
    """PPO's two MLPs (SB3's ``MlpExtractor``) on features of different widths: the policy net on the
    actor's, the value net on the critic's."""

    def __init__(self, pi_dim: int, vf_dim: int, net_arch: Any, activation_fn: type[nn.Module], device: Any) -> None:
        super().__init__()
        pi, vf = MlpExtractor(pi_dim, net_arch, activation_fn, device), MlpExtractor(vf_dim, net_arch, activation_fn, device)
        self.policy_net, self.value_net = pi.policy_net, vf.value_net
        self.latent_dim_pi, self.latent_dim_vf = pi.latent_dim_pi, vf.latent_dim_vf

    def forward(self, features: th.Tensor) -> tuple[th.Tensor, th.Tensor]:
        raise RuntimeError("the actor and the critic read different features: forward_actor / forward_critic")

    def forward_actor(self, features: th.Tensor) -> th.Tensor:
        return self.policy_net(features)

    def forward_critic(self, features: th.Tensor) -> th.Tensor:
        return self.value_net(features)


class AsymmetricActorCriticPolicy(ActorCriticPolicy):
    """PPO's policy with the action distribution on ``actor_keys`` (default ``("sensed",)``) and the
    value on every key of the observation."""

    def __init__(self, observation_space: spaces.Space, action_space: spaces.Space, lr_schedule: Any, *args: Any,
                 actor_keys: tuple[str, ...] = ACTOR_KEYS, **kwargs: Any) -> None:  # fmt: skip
        keys = _checked(observation_space, actor_keys, kwargs, type(self).__name__)
        object.__setattr__(self, "actor_keys", keys)  # before ActorCriticPolicy.__init__ builds the nets
        super().__init__(observation_space, action_space, lr_schedule, *args, **kwargs)

    def _build(self, lr_schedule: Any) -> None:
        # ActorCriticPolicy made both extractors on every key; the actor's reads its keys only
        self.pi_features_extractor = self.features_extractor = KeysExtractor(self.observation_space, self.actor_keys)
        self.features_dim = self.pi_features_extractor.features_dim
        super()._build(lr_schedule)

    def _build_mlp_extractor(self) -> None:
        self.mlp_extractor = _SplitMlpExtractor(self.pi_features_extractor.features_dim,
                                                self.vf_features_extractor.features_dim, self.net_arch,
                                                self.activation_fn, self.device)  # fmt: skip

    def _get_constructor_parameters(self) -> dict[str, Any]:
        return {**super()._get_constructor_parameters(), "actor_keys": self.actor_keys}


__all__ = ["ACTOR_KEYS", "AsymmetricActorCriticPolicy", "AsymmetricSACPolicy", "KeysExtractor"]
