"""Scripted demonstrations in an off-policy learner's replay buffer (``train.py --demos N``).

On the goal id a sparse-reward learner sees a reward only once the cylinder is within 2 cm of a
goal 5-8 cm up, and HER's relabelled goals are only where exploration put the cylinder: in 965
episodes (75k steps) of HER + SAC on SoftGraspGoal-v3 exploration raised it 3 cm once
(benchmarks/her_exploration.py), so the critic had nothing above the table to learn from. Nair et
al. 2018 ("Overcoming exploration in reinforcement learning with demonstrations") and Vecerik et
al. 2017 (DDPG from demonstrations) put demonstrations into the buffer for that; here the env's
own scripted grasp (softgrasp_env.policies.ScriptedGraspPolicy) makes them, and HER relabels them
with the heights they reached like any other episode. Only the buffer is filled: no
behaviour-cloning loss, no Q-filter (Nair et al.'s further terms), so a result with demos
measures what the data alone gives.

The transitions are stored as SB3's off-policy loop stores its own
(OffPolicyAlgorithm._store_transition): the raw observations (a VecNormalize run normalises at
sampling; its running statistics are updated with the demonstrations' observations as they would
be with the learner's), the action scaled to [-1, 1], the env's reward, and a time limit marked as
a truncation, not a termination. The demonstrations use their own reset seeds
(:func:`demo_seeds`), apart from the cards' evaluation seeds (1000-1099).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.off_policy_algorithm import OffPolicyAlgorithm
from stable_baselines3.common.vec_env import VecNormalize

DEMO_SEED_BASE = 2_000_000
MAX_DEMOS = 10_000


def demo_seeds(seed: int, episodes: int) -> list[int]:
    """Reset seeds of a run's demonstrations: ``DEMO_SEED_BASE + MAX_DEMOS * seed + i``, distinct
    per run seed and from the evaluation seeds."""
    if not 0 <= episodes <= MAX_DEMOS:
        raise ValueError(f"demonstrations: 0 to {MAX_DEMOS} episodes, got {episodes}")
    return [DEMO_SEED_BASE + MAX_DEMOS * seed + i for i in range(episodes)]


def _batched(obs: Any) -> Any:
    """One env's observation with the leading n_envs axis of SB3's buffers."""
    if isinstance(obs, dict):
        return {k: np.asarray(v)[None] for k, v in obs.items()}
    return np.asarray(obs)[None]


def add_demonstrations(model: OffPolicyAlgorithm, env_id: str, env_kwargs: dict[str, Any], episodes: int, *,
                       seed: int, norm: VecNormalize | None = None) -> dict[str, Any]:  # fmt: skip
    """Run ``episodes`` episodes of the scripted grasp on ``env_id`` (with ``env_kwargs``, an env
    of its own) and add every transition to ``model``'s replay buffer (see the module docstring).
    Returns ``{"episodes", "transitions", "successes", "seeds"}``."""
    if not isinstance(model, OffPolicyAlgorithm):
        raise TypeError(
            f"demonstrations fill a replay buffer; {type(model).__name__} has none (an off-policy algo: sac, her-sac)"
        )
    if model.n_envs != 1:
        raise ValueError(f"demonstrations are added to a single-env buffer; the model has {model.n_envs} envs")
    from softgrasp_env.policies import ScriptedGraspPolicy

    seeds = demo_seeds(seed, episodes)
    env = gym.make(env_id, **env_kwargs)
    try:
        policy = ScriptedGraspPolicy.for_env(env)
        transitions = successes = 0
        for s in seeds:
            obs, _ = env.reset(seed=s)
            if norm is not None:
                norm.obs_rms.update(_batched(obs))
            while True:
                action = np.asarray(policy(obs), dtype=np.float32)
                next_obs, reward, terminated, truncated, info = env.step(action)
                if norm is not None:
                    norm.obs_rms.update(_batched(next_obs))
                done = terminated or truncated
                # SB3 stores a time limit as done plus TimeLimit.truncated (the target bootstraps there)
                infos = [
                    {"TimeLimit.truncated": bool(truncated and not terminated), "is_success": info.get("is_success")}
                ]
                model.replay_buffer.add(_batched(obs), _batched(next_obs), model.policy.scale_action(action[None]),
                                        np.array([reward], dtype=np.float32), np.array([done]), infos)  # fmt: skip
                transitions += 1
                obs = next_obs
                if done:
                    successes += bool(info.get("is_success"))
                    break
    finally:
        env.close()
    return {"episodes": episodes, "transitions": transitions, "successes": successes,
            "seeds": f"{seeds[0]}-{seeds[-1]}" if seeds else ""}  # fmt: skip


__all__ = ["DEMO_SEED_BASE", "MAX_DEMOS", "add_demonstrations", "demo_seeds"]
