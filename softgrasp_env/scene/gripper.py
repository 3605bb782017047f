"""The gripper: a palm pulled by a force-limited arm, two prismatic finger cores geared to equal
travel, each driven by a force-limited position motor - and its control.

The palm is a pybullet base held by a fixed constraint whose target the arm moves and whose
force limit is the arm's strength (``SceneConfig.palm_force``); the finger cores are links 0 and
1, boxes closing along the palm's x axis. The motors push and whatever the fingers meet pushes
back, so the squeeze is a force, not a teleport. A finger kind (softgrasp_env/fingers/) may add
links of its own to the gripper before it is created (``extend_gripper``).

The control is a value, :class:`GripperControl` (where the arm pulls the palm, how far the fingers
close), handed to the scene's step; :class:`Workspace` is where the arm may take the grip point,
and :class:`GripperActions` maps the env's action onto a control.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pybullet as p
from gymnasium import spaces
from pybullet_utils.bullet_client import BulletClient

from .config import FINGER_DROP, PALM_HALF_EXTENTS, SceneConfig

if TYPE_CHECKING:
    from ..fingers import FingerKind
FINGER_GEAR_FORCE = 100.0
"""Force limit of the gear that keeps both fingers' travel equal [N]: far above what the motors
(``finger_force``) or the tissue can make, so it never gives way."""
FINGER_GEAR_ERP = 0.2
"""Share of the gear's position error corrected per step: pybullet's gear constraint acts on
velocities only by default (erp 0), and the travel difference then drifted by 3 mm in 60 s."""
PALM_RGBA = (0.4, 0.4, 0.45, 1.0)
CORE_RGBA = (0.3, 0.3, 0.8, 1.0)

GRIP_TOP = 0.20
"""Highest the arm takes the grip point [m]."""
WORKSPACE_HALF_WIDTH = 0.15
"""The arm takes the grip point at most this far from the origin in x and in y [m]."""
GROUND_CLEARANCE = 0.003
"""The fingertips come down to this far above the ground at most, pads included [m]."""
MAX_LEAD = 0.02
"""Farthest the arm's target may lead the palm [m], as a real arm's tracking limit would."""


@dataclass(frozen=True, eq=False)
class GripperControl:
    """What the gripper is told for the coming physics steps."""

    palm_target: np.ndarray
    """(3,) where the arm pulls the palm's centre [m, world frame]."""
    finger_closing: float
    """Target travel of each finger from fully open [m] (the motors' force limit sets the squeeze)."""


class Gripper:
    """The palm and the two cores of one scene, built in ``client``; :meth:`apply` hands a control
    to pybullet (only what changed since the last one)."""

    def __init__(self, client: BulletClient, cfg: SceneConfig, fingers: FingerKind, *, start_palm: np.ndarray,
                 yaw: float) -> None:  # fmt: skip
        self.client = c = client
        self.config = cfg
        self.yaw = float(yaw)
        fh = cfg.finger_half_extents
        self.palm_offset = self.palm_offset_of(cfg)
        """Height of the palm's centre above the finger cores' centres [m]."""
        palm_col = c.createCollisionShape(p.GEOM_BOX, halfExtents=PALM_HALF_EXTENTS)
        palm_vis = c.createVisualShape(p.GEOM_BOX, halfExtents=PALM_HALF_EXTENTS, rgbaColor=list(PALM_RGBA))
        fin_col = c.createCollisionShape(p.GEOM_BOX, halfExtents=fh)
        fin_vis = c.createVisualShape(p.GEOM_BOX, halfExtents=fh, rgbaColor=list(CORE_RGBA))
        open_x = cfg.finger_max_opening + fh[0]  # finger centre when fully open
        # Jaw wedge: each finger tilted by half the wedge about y, the left (-x) one by -w/2 and the
        # right one by +w/2 (the gap wider at the top for w > 0, measured: inner faces 6.3 cm from
        # the centre at the top, 5.7 at the bottom for w = 0.2). A prismatic joint's axis is given
        # in the link frame, so it is turned back by the tilt to keep both fingers closing along
        # the palm's x axis.
        half = 0.5 * cfg.jaw_wedge
        tilt_left = c.getQuaternionFromEuler([0.0, -half, 0.0])
        tilt_right = c.getQuaternionFromEuler([0.0, half, 0.0])
        axis_left = [math.cos(half), 0.0, -math.sin(half)]  # R_y(-half)^T (+x)
        axis_right = [-math.cos(half), 0.0, -math.sin(half)]  # R_y(+half)^T (-x)
        links = dict(
            linkMasses=[cfg.finger_mass, cfg.finger_mass],
            linkCollisionShapeIndices=[fin_col, fin_col],
            linkVisualShapeIndices=[fin_vis, fin_vis],
            linkPositions=[[-open_x, 0.0, -self.palm_offset], [open_x, 0.0, -self.palm_offset]],
            linkOrientations=[tilt_left, tilt_right],
            linkInertialFramePositions=[[0, 0, 0], [0, 0, 0]],
            linkInertialFrameOrientations=[[0, 0, 0, 1], [0, 0, 0, 1]],
            linkParentIndices=[0, 0],
            linkJointTypes=[p.JOINT_PRISMATIC, p.JOINT_PRISMATIC],
            linkJointAxis=[axis_left, axis_right],  # +q closes both fingers
        )
        fingers.extend_gripper(links, c)  # a kind's own links go after the two cores
        self.core_links = (0, 1)
        self.body = g = c.createMultiBody(
            baseMass=cfg.palm_mass,
            baseCollisionShapeIndex=palm_col,
            baseVisualShapeIndex=palm_vis,
            basePosition=np.asarray(start_palm).tolist(),
            baseOrientation=c.getQuaternionFromEuler([0.0, 0.0, self.yaw]),
            **links,
        )
        # Damping exists only for the base: pybullet ignores a whole changeDynamics call on a link
        # that asks for damping too (the fingers kept the default friction 0.5 that way), so the
        # friction of each link is set on its own.
        c.changeDynamics(g, -1, linearDamping=0.0, angularDamping=0.0)
        mu = cfg.tissue.friction_static
        for link in (-1, *self.core_links):
            c.changeDynamics(g, link, lateralFriction=mu)
            if c.getDynamicsInfo(g, link)[1] != mu:
                raise RuntimeError(f"pybullet did not take the friction of gripper link {link}")
        for j in self.core_links:  # travel from fully open (0) to the faces meeting at the centre
            c.changeDynamics(g, j, jointLowerLimit=0.0, jointUpperLimit=cfg.finger_max_opening)
        # The fingers are geared to each other (q_left = q_right), as a parallel gripper's rack and
        # pinion does: with two independent force-limited motors both saturated against the
        # cylinder, the pair and the cylinder were free to drift sideways together (neutral
        # equilibrium), 2.5 cm in 15 s for the rigid twin until one finger hit fully open.
        self.finger_gear = c.createConstraint(g, 0, g, 1, p.JOINT_GEAR, [1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
        c.changeConstraint(self.finger_gear, gearRatio=-1.0, maxForce=FINGER_GEAR_FORCE, erp=FINGER_GEAR_ERP)
        self.palm_constraint = c.createConstraint(g, -1, -1, -1, p.JOINT_FIXED, [0, 0, 0], [0, 0, 0],
                                                  np.asarray(start_palm).tolist())  # fmt: skip
        self._orientation = c.getQuaternionFromEuler([0.0, 0.0, self.yaw])
        self.control: GripperControl | None = None
        """The control applied last."""
        self.control = GripperControl(np.array(start_palm, dtype=np.float64), 0.0)
        self._set_palm_target(self.control.palm_target)
        self._set_finger_closing(0.0)

    @staticmethod
    def palm_offset_of(cfg: SceneConfig) -> float:
        """Height of the palm's centre above the finger cores' centres in ``cfg``'s gripper [m]."""
        return PALM_HALF_EXTENTS[2] + FINGER_DROP + cfg.finger_half_extents[2]

    def apply(self, control: GripperControl) -> None:
        """Hand ``control`` to pybullet for the coming steps: the arm's target (the palm keeps the
        start yaw) and the finger motors' target, each only if it is new. A control is a value:
        it is kept as given, so its arrays must not be changed afterwards."""
        last = self.control
        if control is last:  # the same control for every physics step of an env step
            return
        if control.palm_target is not last.palm_target:  # a new target (setting an equal one again changes nothing)
            self._set_palm_target(control.palm_target)
        if control.finger_closing != last.finger_closing:
            self._set_finger_closing(control.finger_closing)
        self.control = control

    def _set_palm_target(self, pos: np.ndarray) -> None:
        self.client.changeConstraint(self.palm_constraint, jointChildPivot=[float(v) for v in pos],
                                     jointChildFrameOrientation=self._orientation,
                                     maxForce=self.config.palm_force)  # fmt: skip

    def _set_finger_closing(self, closing: float) -> None:
        cfg = self.config
        for j in self.core_links:
            self.client.setJointMotorControl2(self.body, j, p.POSITION_CONTROL, targetPosition=float(closing),
                                              force=cfg.finger_force, maxVelocity=cfg.finger_speed)  # fmt: skip

    def finger_closing(self) -> np.ndarray:
        """Travel of each finger from fully open [m]."""
        return np.array([self.client.getJointState(self.body, j)[0] for j in self.core_links])


@dataclass(frozen=True, eq=False)
class Workspace:
    """Where the arm may take the grip point (the midpoint of the finger cores): a box, and how far
    its target may lead the palm, as a real arm's reach and tracking limit would."""

    low: np.ndarray
    """(3,) lowest x, y, z [m]."""
    high: np.ndarray
    """(3,) highest x, y, z [m]."""
    max_lead: float = MAX_LEAD

    @classmethod
    def of(cls, cfg: SceneConfig) -> Workspace:
        """x, y within WORKSPACE_HALF_WIDTH of the origin; the fingertips down to GROUND_CLEARANCE
        above the ground with the tissue's depth (``tissue.extrude``) below them whatever the kind,
        so every kind has the same workspace; up to GRIP_TOP."""
        fh = cfg.finger_half_extents
        w = WORKSPACE_HALF_WIDTH
        return cls(np.array([-w, -w, fh[2] + cfg.tissue.extrude + GROUND_CLEARANCE]), np.array([w, w, GRIP_TOP]))

    def clip(self, grip: np.ndarray) -> np.ndarray:
        """``grip`` moved into the box."""
        return np.clip(grip, self.low, self.high)


class GripperActions:
    """The env's action, ``Box(-1, 1, (4,))``, as a gripper control: a displacement of the grip
    point's target (x, y, z, ``step_length`` at full action) kept in the workspace and within
    ``max_lead`` of the palm, and the finger closing (-1 fully open, +1 the faces meeting)."""

    space = spaces.Box(-1.0, 1.0, shape=(4,), dtype=np.float32)

    def __init__(self, step_length: float, workspace: Workspace, finger_max_opening: float) -> None:
        self.step_length = float(step_length)
        self.workspace = workspace
        self.finger_max_opening = float(finger_max_opening)

    def control(self, action: np.ndarray, *, palm_target: np.ndarray, palm: np.ndarray,
                grip_to_palm: np.ndarray) -> GripperControl:  # fmt: skip
        """The control for ``action`` (clipped to [-1, 1] already), given the arm's current target,
        where the palm is and the palm's offset from the grip point."""
        ws = self.workspace
        target_grip = ws.clip((palm_target - grip_to_palm) + action[:3] * self.step_length)
        target = np.clip(target_grip + grip_to_palm, palm - ws.max_lead, palm + ws.max_lead)
        return GripperControl(target, 0.5 * (float(action[3]) + 1.0) * self.finger_max_opening)


__all__ = ["GRIP_TOP", "Gripper", "GripperActions", "GripperControl", "Workspace"]
