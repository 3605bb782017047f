"""The registered environment ids (``gym.make(id)`` after ``import softgrasp_env``)."""

from __future__ import annotations

import math

import gymnasium as gym
from gymnasium.envs.registration import WrapperSpec

MAX_EPISODE_STEPS = 100
"""5 s at the default 20 Hz control frequency."""

_SPECS: dict[str, tuple[str, dict]] = {
    "SoftGrasp-v2": ("softgrasp_env.env:SoftGraspEnv", {"fingers": "tissue", "reward_type": "dense", "carry": True}),
    "SoftGraspRigid-v2": ("softgrasp_env.env:SoftGraspEnv", {"fingers": "rigid", "reward_type": "dense", "carry": True}),
    "SoftGraspSparse-v2": ("softgrasp_env.env:SoftGraspEnv", {"fingers": "tissue", "reward_type": "sparse", "carry": True}),
    "SoftGrasp-v1": ("softgrasp_env.env:SoftGraspEnv", {"fingers": "tissue", "reward_type": "dense", "carry": False}),
    "SoftGraspRigid-v1": ("softgrasp_env.env:SoftGraspEnv", {"fingers": "rigid", "reward_type": "dense", "carry": False}),
    "SoftGraspSparse-v1": ("softgrasp_env.env:SoftGraspEnv", {"fingers": "tissue", "reward_type": "sparse", "carry": False}),
    "SoftGraspGoal-v1": ("softgrasp_env.env:SoftGraspGoalEnv", {"fingers": "tissue"}),
    "SoftGraspEasy-v1": ("softgrasp_env.env:SoftGraspEnv", {"fingers": "tissue", "reward_type": "dense", "task": "easy"}),
    "SoftGraspEasyRigid-v1": ("softgrasp_env.env:SoftGraspEnv", {"fingers": "rigid", "reward_type": "dense", "task": "easy"}),
}

ENV_IDS: tuple[str, ...] = tuple(_SPECS)
"""The reach task with the carry test (v2: approach from above and away, misaligned fingers, lift,
then the arm sways the cylinder sideways for the last 1.5 s) with soft fingers and the dense lift
reward; its rigid-only twin; the sparse-reward variant; the same three without the carry test
(v1, kept because their published baselines reproduce on them: a v1 success is a static hold,
which a rigid grasp near the cylinder's top rim achieves as well as a soft one); the
goal-conditioned variant (dict observations, ``compute_reward`` for HER); and the gentle start of
v0 (``task="easy"``: the open fingers around the cylinder's top, aligned), soft and rigid, for
debugging a policy or the physics. v0 (the gentle start as the only task, on the physics before
the accuracy work) is gone: its results cannot be reproduced by this code."""


def steps_to_succeed(env: gym.Env) -> int | None:
    """The fewest env steps after which ``env`` (a SoftGrasp env, wrapped or not) can report success:
    with the carry test, the step at which the carry is over (``carry_start + carry_duration``,
    100 steps at the defaults); None without it (a lift can succeed at any step)."""
    from .tasks import CarryTest

    base = env.unwrapped
    task, args = getattr(base, "task", None), getattr(base, "args", None)
    if not isinstance(task, CarryTest) or args is None:
        return None
    per_step = args.substeps
    n = max(1, math.floor((task.start + task.duration) / (task.dt * per_step)) - 1)
    while not task.over(n * per_step):  # the task's own rule decides, rounding included
        n += 1
    return n


def check_time_limit(env: gym.Env) -> gym.Env:
    """The last step of ``gym.make`` for every id (registered as an additional wrapper, so it runs
    after the TimeLimit is on and ``env.spec.max_episode_steps`` is the episode's length; the env
    itself only ever sees a spec without it): warn when the time limit ends every episode before
    success is possible, e.g. ``max_episode_steps=60`` with the carry test ending at 5 s. Returns
    ``env`` itself: it adds no wrapper."""
    limit = env.spec.max_episode_steps if env.spec is not None else None
    needed = steps_to_succeed(env)
    if limit is not None and needed is not None and limit < needed:
        base = env.unwrapped
        gym.logger.warn(
            f"{env.spec.id}: max_episode_steps={limit} ends every episode at {limit / base.control_frequency:g} s, "
            f"before the carry test is over at {needed / base.control_frequency:g} s (step {needed}): no episode can "
            f"succeed. Give max_episode_steps >= {needed}, or carry=False / an earlier carry_start.")  # fmt: skip
    return env


CHECK_TIME_LIMIT = WrapperSpec("CheckTimeLimit", f"{__name__}:check_time_limit", {})
"""``check_time_limit`` as gym.make applies it: after the TimeLimit (it wraps nothing)."""


def register_envs() -> None:
    """Register every id in :data:`ENV_IDS` (idempotent: ids already registered are left alone)."""
    for env_id, (entry_point, kwargs) in _SPECS.items():
        if env_id not in gym.registry:
            # disable_env_checker: gymnasium 1.4.0's PassiveEnvChecker, when the first reset raises
            # (a mistyped reset option), keeps None as that reset's result and fails every later
            # step with "cannot unpack non-iterable NoneType". Our ids are checked in full by
            # gymnasium's and SB3's check_env in tests/test_env.py instead.
            gym.register(id=env_id, entry_point=entry_point, kwargs=dict(kwargs), max_episode_steps=MAX_EPISODE_STEPS,
                         disable_env_checker=True, additional_wrappers=(CHECK_TIME_LIMIT,))  # fmt: skip
