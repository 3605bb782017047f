"""A scripted grasp policy for the SoftGrasp environments: reads only the observation.

Move the grip point over the cylinder (horizontally first: from above, the open fingers would
otherwise come down on its top), down onto its centre, close the fingers, and once both fingers
press on the cylinder, lift to a little above the success height and hold there. Works for the vector
observation of every SoftGrasp id (with or without the carry test's clock and taxels) and for the
``observation`` entry of the goal ids' dict.

Part of the installed package (``from softgrasp_env.policies import ScriptedGraspPolicy``); the
repository's ``agents.scripted`` is the same class under its old name.
"""

from __future__ import annotations

import numpy as np

from ..fingers.tactile import TAXEL_CHANNELS
from ..observation import CARRY_OBS_NAMES, OBS_NAMES, SHAPE_OBS_NAMES
from ..validation import retired_choice

_I = {name: k for k, name in enumerate(OBS_NAMES)}
_SIZES = tuple(n + k for n in (len(OBS_NAMES), len(CARRY_OBS_NAMES)) for k in (0, len(SHAPE_OBS_NAMES)))
"""Without and with the carry test's clock (``carry=False`` / ``True``), each without and with the
object's shape description (``observe_shape``); the policy reads neither: it holds on from the
grasp to the episode's end either way, and finds the object by its centre."""
_PER_TAXEL = 2 * len(TAXEL_CHANNELS)
"""An env made with ``tactile=(rows, cols)`` appends 2 x rows x cols x channels entries, which this
policy does not read."""


def _valid(n: int) -> bool:
    """Whether ``n`` is an observation length of a SoftGrasp env: with or without the clock, with or
    without taxels."""
    return any(n == base or (n > base and (n - base) % _PER_TAXEL == 0) for base in _SIZES)


class ScriptedGraspPolicy:
    """``policy(obs) -> action``; stateless, so it can be used from any point of an episode. It
    also has SB3's ``predict`` (batched observations too), so tools that evaluate an SB3 model
    (``stable_baselines3.common.evaluation.evaluate_policy``, agents.evaluate) evaluate it alike.

    The arm's actions are velocities (``speed`` at full action, the env's ``arm_speed``
    [m/s]): the policy asks for the speed that, held for a control step (``control_period`` [s])
    and then braked at the arm's acceleration ``arm_acceleration`` [m/s^2], stops within the
    distance left, so it does not overshoot (:meth:`for_env` reads these from an env).
    ``grip_force`` is the per-finger normal force [N] above which the cylinder counts
    as gripped; ``lift_to`` the lift height it holds [m]; ``descend_tolerance`` how near the
    cylinder's axis the grip must be horizontally before it comes down from above [m];
    ``min_grip_height`` the lowest the grip point goes [m] (None: no limit): a low object (a sphere,
    a capsule on its side) is gripped there rather than at its centre, so the fingertips stay off
    the ground (:meth:`for_env` sets the arm workspace's floor when the env grasps another object
    than the cylinder: where scene.config.grasp_height puts a low object)."""

    def __init__(self, *, speed: float = 0.15, arm_acceleration: float = 1.5, control_period: float = 0.05,
                 grip_force: float = 0.5, lift_to: float = 0.065, align_tolerance: float = 0.004,
                 descend_tolerance: float = 0.01, min_grip_height: float | None = None,
                 **retired: str) -> None:  # fmt: skip
        # arm="smooth" (before 0.7, when the arm had two kinds) warns; arm="jump" names 0.6.0
        retired_choice(retired, "arm", kept="smooth", gone=("jump",), release="0.6.0", owner="ScriptedGraspPolicy",
                       stacklevel=3)  # fmt: skip
        if retired:
            raise TypeError(f"ScriptedGraspPolicy got unexpected keyword argument(s) {sorted(retired)}")
        self.descend_tolerance = float(descend_tolerance)
        self.speed = float(speed)
        self.arm_acceleration = float(arm_acceleration)
        self.control_period = float(control_period)
        self.grip_force = float(grip_force)
        self.lift_to = float(lift_to)
        self.align_tolerance = float(align_tolerance)
        self.min_grip_height = None if min_grip_height is None else float(min_grip_height)

    @classmethod
    def for_env(cls, env, **kwargs) -> ScriptedGraspPolicy:
        """The policy for ``env`` (a SoftGrasp env, wrapped or not): its arm speed and acceleration
        and control period; ``kwargs`` set the other parameters."""
        args = getattr(env.unwrapped, "args", None)
        if args is None:
            raise TypeError(f"ScriptedGraspPolicy.for_env needs a SoftGrasp env, got {env!r}")
        c = args.control
        plan = env.unwrapped.plan
        if "min_grip_height" not in kwargs and (plan.scene.object is not None or args.ranges.objects
                                            or args.ranges.object_scale):
            # the workspace's floor: a low object is gripped there, another at its centre
            kwargs["min_grip_height"] = float(plan.workspace.low[2])
        return cls(speed=c.arm_speed, arm_acceleration=c.arm_acceleration, control_period=1.0 / c.frequency,
                   **kwargs)  # fmt: skip

    def predict(self, observation, state=None, episode_start=None, deterministic: bool = True):
        """SB3's policy interface: ``(action, state)``. ``observation`` is one observation or a
        batch (leading axis: the envs of a VecEnv), a vector or the goal env's dict; the action has
        the same leading shape. Stateless (``state`` is passed back unchanged) and deterministic
        whatever ``deterministic`` says."""
        obs = observation["observation"] if isinstance(observation, dict) else observation
        obs = np.asarray(obs, dtype=np.float64)
        if obs.ndim == 1:
            return self(obs), state
        if obs.ndim != 2 or not _valid(obs.shape[1]):
            raise ValueError(f"observation must have shape (n,) or (n_envs, n) with n in {_SIZES} (plus taxels), "
                             f"got {obs.shape}")  # fmt: skip
        return np.stack([self(o) for o in obs]), state

    def __call__(self, obs) -> np.ndarray:
        if isinstance(obs, dict):
            obs = obs["observation"]
        obs = np.asarray(obs, dtype=np.float64)
        if obs.ndim != 1 or not _valid(obs.shape[0]):
            raise ValueError(f"observation must have shape (n,) with n in {_SIZES} (plus taxels), got {obs.shape} "
                             "(batches: use predict)")  # fmt: skip
        rel = obs[_I["cyl_rel_x"] : _I["cyl_rel_z"] + 1]
        forces = obs[[_I["force_left"], _I["force_right"]]]
        lift = obs[_I["lift"]]
        action = np.zeros(4, dtype=np.float32)
        gripped = bool((forces >= self.grip_force).all())
        if gripped:
            action[:3] = self.toward(np.array([0.0, 0.0, self.lift_to - lift]))
            action[3] = 1.0
            return action
        target = rel.copy()  # where the grip point goes, relative to it
        if self.min_grip_height is not None:
            target[2] = max(rel[2], self.min_grip_height - obs[_I["grip_z"]])
        move = target.copy()
        if np.hypot(rel[0], rel[1]) > self.descend_tolerance and target[2] < 0.0:
            move[2] = 0.0  # above it and not yet over it: no lower until over it
        action[:3] = self.toward(move)
        aligned = bool(np.abs(target).max() <= self.align_tolerance)
        action[3] = 1.0 if aligned or (forces > 0.0).any() else -1.0
        return action

    def toward(self, move: np.ndarray) -> np.ndarray:
        """The action that heads along ``move`` [m] at the speed that stops there: a command holds
        for one control step T before the next can brake, so the speed s must cover s T plus the
        braking distance s^2 / 2a within the distance d: s = a (sqrt(T^2 + 2 d / a) - T)."""
        d = float(np.linalg.norm(move))
        if d == 0.0:
            return np.zeros(3)
        a, T = self.arm_acceleration, self.control_period
        s = min(self.speed, a * (np.sqrt(T * T + 2.0 * d / a) - T))
        return np.clip(move / d * (s / self.speed), -1.0, 1.0)


__all__ = ["ScriptedGraspPolicy"]
