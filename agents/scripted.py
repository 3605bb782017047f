"""A scripted grasp policy for the SoftGrasp environments: reads only the observation.

Move the grip point onto the cylinder's centre, close the fingers, and once both fingers press on
the cylinder, lift to a little above the success height and hold there. Works for the vector
observation of SoftGrasp-v0 / SoftGraspRigid-v0 / SoftGraspSparse-v0 and for the ``observation``
entry of SoftGraspGoal-v0's dict.
"""

from __future__ import annotations

import numpy as np

from softgrasp_env.env import OBS_NAMES

_I = {name: k for k, name in enumerate(OBS_NAMES)}


class ScriptedGraspPolicy:
    """``policy(obs) -> action``; stateless, so it can be used from any point of an episode.

    ``step_length`` is the arm's displacement at full action [m] (``gripper_speed /
    control_frequency`` of the env, 7.5 mm by default); ``grip_force`` the per-finger normal force
    [N] above which the cylinder counts as gripped; ``lift_to`` the lift height it holds [m]."""

    def __init__(self, *, step_length: float = 0.0075, grip_force: float = 0.5, lift_to: float = 0.065,
                 align_tolerance: float = 0.004) -> None:  # fmt: skip
        self.step_length = float(step_length)
        self.grip_force = float(grip_force)
        self.lift_to = float(lift_to)
        self.align_tolerance = float(align_tolerance)

    def __call__(self, obs) -> np.ndarray:
        if isinstance(obs, dict):
            obs = obs["observation"]
        obs = np.asarray(obs, dtype=np.float64)
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
        aligned = bool(np.abs(rel).max() <= self.align_tolerance)
        action[3] = 1.0 if aligned or (forces > 0.0).any() else -1.0
        return action
