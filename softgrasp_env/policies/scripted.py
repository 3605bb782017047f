"""A scripted grasp policy for the SoftGrasp environments: reads only the observation.

Move the grip point over the cylinder (horizontally first: from above, the open fingers would
otherwise come down on its top), down onto its centre, close the fingers, and once both fingers
press on the cylinder, lift to a little above the success height and hold there. Works for the vector
observation of SoftGrasp-v2 / SoftGraspRigid-v2 / SoftGraspSparse-v2 (and their v1) and for the ``observation``
entry of SoftGraspGoal-v1's dict.

Part of the installed package (``from softgrasp_env.policies import ScriptedGraspPolicy``); the
repository's ``agents.scripted`` is the same class under its old name.
"""

from __future__ import annotations

import numpy as np

from ..observation import CARRY_OBS_NAMES, OBS_NAMES

_I = {name: k for k, name in enumerate(OBS_NAMES)}
_SIZES = (len(OBS_NAMES), len(CARRY_OBS_NAMES))
"""Without and with the carry test's clock (the v1 and v2 ids); the policy does not read the clock:
it holds on from the grasp to the episode's end either way."""


class ScriptedGraspPolicy:
    """``policy(obs) -> action``; stateless, so it can be used from any point of an episode. It
    also has SB3's ``predict`` (batched observations too), so tools that evaluate an SB3 model
    (``stable_baselines3.common.evaluation.evaluate_policy``, agents.evaluate) evaluate it alike.

    ``step_length`` is the arm's displacement at full action [m] (``gripper_speed /
    control_frequency`` of the env, 7.5 mm by default); ``grip_force`` the per-finger normal force
    [N] above which the cylinder counts as gripped; ``lift_to`` the lift height it holds [m];
    ``descend_tolerance`` how near the cylinder's axis the grip must be horizontally before it
    comes down from above [m]."""

    def __init__(self, *, step_length: float = 0.0075, grip_force: float = 0.5, lift_to: float = 0.065,
                 align_tolerance: float = 0.004, descend_tolerance: float = 0.01) -> None:  # fmt: skip
        self.descend_tolerance = float(descend_tolerance)
        self.step_length = float(step_length)
        self.grip_force = float(grip_force)
        self.lift_to = float(lift_to)
        self.align_tolerance = float(align_tolerance)

    def predict(self, observation, state=None, episode_start=None, deterministic: bool = True):
        """SB3's policy interface: ``(action, state)``. ``observation`` is one observation or a
        batch (leading axis: the envs of a VecEnv), a vector or the goal env's dict; the action has
        the same leading shape. Stateless (``state`` is passed back unchanged) and deterministic
        whatever ``deterministic`` says."""
        obs = observation["observation"] if isinstance(observation, dict) else observation
        obs = np.asarray(obs, dtype=np.float64)
        if obs.ndim == 1:
            return self(obs), state
        if obs.ndim != 2 or obs.shape[1] not in _SIZES:
            raise ValueError(f"observation must have shape (n,) or (n_envs, n) with n in {_SIZES}, got {obs.shape}")
        return np.stack([self(o) for o in obs]), state

    def __call__(self, obs) -> np.ndarray:
        if isinstance(obs, dict):
            obs = obs["observation"]
        obs = np.asarray(obs, dtype=np.float64)
        if obs.ndim != 1 or obs.shape[0] not in _SIZES:
            raise ValueError(f"observation must have shape (n,) with n in {_SIZES}, got {obs.shape} (batches: use predict)")
        rel = obs[_I["cyl_rel_x"] : _I["cyl_rel_z"] + 1]
        forces = obs[[_I["force_left"], _I["force_right"]]]
        lift = obs[_I["lift"]]
        action = np.zeros(4, dtype=np.float32)
        gripped = bool((forces >= self.grip_force).all())
        if gripped:
            action[2] = np.clip((self.lift_to - lift) / self.step_length, -1.0, 1.0)
            action[3] = 1.0
            return action
        action[:3] = np.clip(rel / self.step_length, -1.0, 1.0)
        if np.hypot(rel[0], rel[1]) > self.descend_tolerance and rel[2] < 0.0:
            action[2] = 0.0  # above it and not yet over it: no lower until over it
        aligned = bool(np.abs(rel).max() <= self.align_tolerance)
        action[3] = 1.0 if aligned or (forces > 0.0).any() else -1.0
        return action


__all__ = ["ScriptedGraspPolicy"]
