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

On the grip-force ids (finger_action "force") the demonstrations come from the tactile grip
script that does best on the id's fingers (softgrasp_env.policies.grip.grip_script): on the
tissue the shear-lag script (ShearLagGripPolicy: 89 % on the soft grip id's cards), on rigid pads,
which do not shear, the slip script (TactileGripPolicy: 89 % on the rigid grip ids' cards). Both set the squeeze from
the taxels. A run without the taxels (``--env-kwargs tactile=None tactile_history=1``) gets the
same episodes: the script runs on the id's own taxels and the buffer stores the observation the
learner has (the taxel entries left out; the taxels are a sensor and change nothing of the
physics), so learners with and without touch start from the same demonstrations. An asymmetric run (``train.py --asymmetric``) stores
each observation as ``PrivilegedObservation`` gives it to the learner: ``sensed`` and
``privileged``.

By default the demonstrations are ordinary transitions: sampled as often as any other, a fading
share of each batch as the learner's own fill the buffer (100 episodes are 10,000 transitions, 3 %
of a 300k run's). ``train.py --demo-share F`` keeps them in every batch instead: the replay
buffer (``softgrasp_env.policies.replay.DemoReplayBuffer``) never overwrites them and draws a fixed fraction F of each batch
from them, the rest from the learner's own transitions. That is the symmetric sampling of Ball et
al. 2023 ("Efficient online reinforcement learning with offline data", RLPD: F = 0.5) and the kept
demonstrations of Vecerik et al. 2017; a learner whose reward only pays after a long carry meets
the carried episodes in every update, not once in thirty.

The transitions are stored as SB3's off-policy loop stores its own
(OffPolicyAlgorithm._store_transition): the raw observations (a VecNormalize run normalises at
sampling; its running statistics are updated with the demonstrations' observations as they would
be with the learner's), the action scaled to [-1, 1], the env's reward, and a time limit marked as
a truncation, not a termination. The demonstrations use their own reset seeds
(:func:`demo_seeds`), apart from the cards' evaluation seeds (1000-1099).
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.off_policy_algorithm import OffPolicyAlgorithm
from stable_baselines3.common.vec_env import VecNormalize
from stable_baselines3.sac import SAC

from softgrasp_env.policies.grip import grip_script
from softgrasp_env.policies.replay import DemoReplayBuffer, DictDemoReplayBuffer, KeptDemonstrations, demo_buffer
from softgrasp_env.wrappers import PRIVILEGED, SENSED, PrivilegedObservation

DEMO_SEED_BASE = 2_000_000
MAX_DEMOS = 10_000


def demo_seeds(seed: int, episodes: int) -> list[int]:
    """Reset seeds of a run's demonstrations: ``DEMO_SEED_BASE + MAX_DEMOS * seed + i``, distinct
    per run seed and from the evaluation seeds."""
    if not 0 <= episodes <= MAX_DEMOS:
        raise ValueError(f"demonstrations: 0 to {MAX_DEMOS} episodes, got {episodes}")
    return [DEMO_SEED_BASE + MAX_DEMOS * seed + i for i in range(episodes)]


class DemoSAC(SAC):
    """SB3's SAC with a behaviour-cloning step on the kept demonstrations after each round of its
    own updates (``train.py --demo-bc LAMBDA``; needs a :class:`DemoReplayBuffer`): for each of the
    round's gradient steps one batch of demonstrations, and the actor moved toward their actions
    where the critic rates them above its own, loss ``LAMBDA * mean(filter * |mu(s) - a_demo|^2)``
    with ``mu`` the actor's deterministic action (both in SB3's [-1, 1] action scale). That is Nair
    et al. 2018's behaviour-cloning loss with its Q-filter (``filter = Q(s, a_demo) > Q(s,
    mu(s))``, the lesser of the twin critics): the learner imitates a demonstration only while it
    knows nothing better there, and the RL objective takes over where it does. Taken as a step of
    its own (same optimiser) rather than a term of the actor's loss, so SAC's own update is SB3's
    unchanged. ``train/bc_loss`` and ``train/bc_filter`` (the share of demonstrations kept by the
    filter) are logged."""

    def __init__(self, *args: Any, demo_bc: float = 0.0, **kwargs: Any) -> None:
        if not (math.isfinite(demo_bc) and demo_bc >= 0.0):
            raise ValueError(f"demo_bc: the behaviour-cloning weight, finite and >= 0; got {demo_bc}")
        super().__init__(*args, **kwargs)
        self.demo_bc = float(demo_bc)

    def train(self, gradient_steps: int, batch_size: int = 64) -> None:
        super().train(gradient_steps, batch_size)
        buffer = self.replay_buffer
        if self.demo_bc == 0.0 or not isinstance(buffer, KeptDemonstrations) or not buffer.kept:
            return
        import torch as th

        losses, kept = [], []
        for _ in range(gradient_steps):
            data = buffer.sample_kept(batch_size, env=self._vec_normalize_env)
            mu = self.actor(data.observations, deterministic=True)
            with th.no_grad():
                q_demo = th.min(th.cat(self.critic(data.observations, data.actions), dim=1), dim=1).values
                q_mu = th.min(th.cat(self.critic(data.observations, mu.detach()), dim=1), dim=1).values
                better = (q_demo > q_mu).float()
            loss = self.demo_bc * (better * ((mu - data.actions) ** 2).sum(dim=1)).mean()
            self.actor.optimizer.zero_grad()
            loss.backward()
            self.actor.optimizer.step()
            losses.append(loss.item())
            kept.append(better.mean().item())
        self.logger.record("train/bc_loss", float(np.mean(losses)))
        self.logger.record("train/bc_filter", float(np.mean(kept)))


def _batched(obs: Any) -> Any:
    """One env's observation with the leading n_envs axis of SB3's buffers."""
    if isinstance(obs, dict):
        return {k: np.asarray(v)[None] for k, v in obs.items()}
    return np.asarray(obs)[None]


def _update_statistics(norm: VecNormalize, obs: Any) -> None:
    """VecNormalize's running observation statistics, updated with one env's observation (per key
    of a dict observation, as VecNormalize itself does)."""
    if isinstance(norm.obs_rms, dict):
        for key, rms in norm.obs_rms.items():
            rms.update(np.asarray(obs[key])[None])
    else:
        norm.obs_rms.update(_batched(obs))


TAXEL_KEYWORDS = ("tactile", "tactile_history")
"""The gym.make keywords a run without the taxels may set; its demonstrations run without them."""


def _grip_env(env: gym.Env) -> bool:
    return env.unwrapped.plan.args.control.finger_action == "force"


def demonstrator(env_id: str, env_kwargs: dict[str, Any]) -> tuple[gym.Env, Any, np.ndarray | None]:
    """The env the demonstrations run in, its scripted policy, and the indices of the learner's
    observation entries in that env's observation (None: the same observation).

    The scripted grasp (ScriptedGraspPolicy) on the lift ids; on a grip-force id its tactile grip
    script (``grip_script``), in the id's own taxels when the learner's env has none (module
    docstring)."""
    from softgrasp_env.policies import ScriptedGraspPolicy

    env = gym.make(env_id, **env_kwargs)
    if not _grip_env(env):
        return env, ScriptedGraspPolicy.for_env(env), None
    if env.unwrapped.plan.taxel_grid is not None:
        return env, grip_script(env), None
    names = env.unwrapped.obs_names
    env.close()
    env = gym.make(env_id, **{k: v for k, v in env_kwargs.items() if k not in TAXEL_KEYWORDS})
    if env.unwrapped.plan.taxel_grid is None:
        env.close()
        raise ValueError(f"demonstrations on {env_id}: the grip script reads the taxels, and {env_id} has none "
                         "by default")  # fmt: skip
    index = {n: k for k, n in enumerate(env.unwrapped.obs_names)}
    missing = [n for n in names if n not in index]
    if missing:  # an observation the taxel env lacks: the learner's env differs by more than its taxels
        env.close()
        raise ValueError(f"demonstrations on {env_id} with {env_kwargs}: the grip script's env (with the taxels) "
                         f"has no entries {missing[:3]}")  # fmt: skip
    return env, grip_script(env), np.array([index[n] for n in names], dtype=np.intp)


def add_demonstrations(model: OffPolicyAlgorithm, env_id: str, env_kwargs: dict[str, Any], episodes: int, *,
                       seed: int, norm: VecNormalize | None = None, privileged: bool = False) -> dict[str, Any]:  # fmt: skip
    """Run ``episodes`` episodes of the scripted policy (:func:`demonstrator`) on ``env_id`` (with
    ``env_kwargs``, an env of its own) and add every transition to ``model``'s replay buffer (see
    the module docstring); ``privileged``: observations as PrivilegedObservation gives them (an
    asymmetric learner's). A buffer that keeps them (:func:`demo_buffer`) keeps them from here on.
    Returns ``{"episodes", "transitions", "successes", "seeds", "policy"}``, and with a keeping
    buffer ``"share"``, the fraction of each batch drawn from them."""
    if not isinstance(model, OffPolicyAlgorithm):
        raise TypeError(
            f"demonstrations fill a replay buffer; {type(model).__name__} has none (an off-policy algo: sac, her-sac)"
        )
    if model.n_envs != 1:
        raise ValueError(f"demonstrations are added to a single-env buffer; the model has {model.n_envs} envs")
    seeds = demo_seeds(seed, episodes)
    env, policy, project = demonstrator(env_id, env_kwargs)
    if privileged:
        env = PrivilegedObservation(env)

    def stored(raw: Any) -> Any:
        """The learner's observation of the demonstrator env's ``raw`` one."""
        sensed = raw[SENSED] if privileged else raw
        if project is not None:
            sensed = sensed[project]
        return {SENSED: sensed, PRIVILEGED: raw[PRIVILEGED]} if privileged else sensed

    try:
        transitions = successes = 0
        for s in seeds:
            if hasattr(policy, "reset"):
                policy.reset()
            raw, _ = env.reset(seed=s)
            obs = stored(raw)
            if norm is not None:
                _update_statistics(norm, obs)
            while True:
                action = np.asarray(policy(raw[SENSED] if privileged else raw), dtype=np.float32)
                raw, reward, terminated, truncated, info = env.step(action)
                next_obs = stored(raw)
                if norm is not None:
                    _update_statistics(norm, next_obs)
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
    out = {"episodes": episodes, "transitions": transitions, "successes": successes,
           "seeds": f"{seeds[0]}-{seeds[-1]}" if seeds else "", "policy": type(policy).__name__}  # fmt: skip
    if isinstance(model.replay_buffer, KeptDemonstrations):
        model.replay_buffer.keep_demonstrations()
        out["share"] = model.replay_buffer.demo_share
    return out


__all__ = ["DEMO_SEED_BASE", "MAX_DEMOS", "TAXEL_KEYWORDS", "DemoReplayBuffer", "DemoSAC", "DictDemoReplayBuffer",
           "add_demonstrations", "demo_buffer", "demo_seeds", "demonstrator"]
