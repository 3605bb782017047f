"""The gripper: a palm pulled by a force-limited arm, two prismatic finger cores geared to equal
travel, each driven by a force-limited position motor - and its control.

The palm is a pybullet base held by a fixed constraint whose target the arm moves and whose
force limit is the arm's strength (``SceneConfig.arm_force``); the finger cores are links 0 and
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
from typing import TYPE_CHECKING, Protocol

import numba as nb
import numpy as np
import pybullet as p
from gymnasium import spaces
from pybullet_utils.bullet_client import BulletClient

from ..fingers.base import CORE_RGBA
from ..validation import deprecated
from .config import FINGER_DROP, PALM_HALF_EXTENTS, SceneConfig, arm_force_limit, lowest_grip

if TYPE_CHECKING:
    from ..fingers import FingerKind
FINGER_GEAR_FORCE = 100.0
"""Force limit of the gear that keeps both fingers' travel equal [N]: far above what the motors
(``finger_force``) or the tissue can make, so it never gives way."""
FINGER_GEAR_ERP = 0.2
"""Share of the gear's position error corrected per step: pybullet's gear constraint acts on
velocities only by default (erp 0), and the travel difference then drifted by 3 mm in 60 s."""
PALM_RGBA = (0.4, 0.4, 0.45, 1.0)

GRIP_TOP = 0.20
"""Highest the arm takes the grip point [m]."""
WORKSPACE_HALF_WIDTH = 0.15
"""The arm takes the grip point at most this far from the origin in x and in y [m]."""
MAX_LEAD = 0.02
"""Farthest the arm's setpoint may lead the palm [m], as a real arm's tracking limit would."""


@dataclass(frozen=True, eq=False)
class GripperControl:
    """What the gripper is told for the coming physics steps. The arm moves its setpoint (the
    palm's constraint pivot) along a smooth path (:class:`PalmPath`): toward ``palm_target`` when
    one is given (position mode: a planned move, the carry's sway), else at ``palm_velocity``
    (velocity mode: a policy's command)."""

    palm_target: np.ndarray | None
    """(3,) where the arm takes the palm's centre [m, world frame]; None: velocity mode."""
    finger_closing: float
    """Target travel of each finger from fully open [m] (the motors' force limit sets the squeeze)."""
    palm_velocity: np.ndarray | None = None
    """(3,) [m/s]: in position mode the target's own velocity when it moves along a smooth path (so
    the arm follows it without lag; None: a target at rest); in velocity mode the commanded
    velocity (None: stop)."""
    palm_box: tuple[np.ndarray, np.ndarray] | None = None
    """(low, high) the palm's centre must stay within [m] (the workspace, in palm coordinates): the
    path brakes before it reaches a wall."""
    finger_force: float | None = None
    """The finger motors' force limit for this control [N], what they squeeze with once the fingers
    meet resistance; None: the scene's ``finger_force``."""


class PalmPath:
    """The arm's setpoint, one physics step at a time, with speed at most ``v_max`` and
    acceleration at most ``a_max`` exactly: each step changes its velocity by at most a_max dt.
    Position mode heads for the target and brakes on the discrete curve that stops it exactly there
    (:func:`_brake`), plus the target's own velocity; velocity mode takes the commanded velocity.
    Either way it brakes before the walls of ``palm_box`` and before it leads the palm by more
    than ``max_lead`` (a blocked palm, pressing on something, must not find its setpoint far away
    when it comes free). The palm's constraint then tracks a path that is smooth and the same at
    every dt. It runs every physics step, so the step is one compiled call (:func:`_path_step`)
    on a packed state and a packed control; the arithmetic is IEEE double without contraction,
    the same numbers as the same formulas in Python floats."""

    def __init__(self, x0: np.ndarray, *, v_max: float, a_max: float, dt: float, max_lead: float = MAX_LEAD) -> None:
        self._state = np.zeros(_PATH_STATE)
        self._state[0:3] = [float(v) for v in x0]
        self._state[6:10] = float(v_max), float(a_max), float(dt), float(max_lead)
        self._control: GripperControl | None = None  # the control packed last, and its packing
        self._packed = np.zeros(_PATH_CONTROL)

    @property
    def v_max(self) -> float:
        """Top speed [m/s] (fixed at construction, as the other limits)."""
        return float(self._state[6])

    @property
    def a_max(self) -> float:
        """Top acceleration [m/s^2]."""
        return float(self._state[7])

    @property
    def dt(self) -> float:
        """The step [s]."""
        return float(self._state[8])

    @property
    def max_lead(self) -> float:
        """Farthest the setpoint leads the palm [m]."""
        return float(self._state[9])

    @property
    def x(self) -> list[float]:
        """The setpoint [m]."""
        return self._state[0:3].tolist()

    @property
    def v(self) -> list[float]:
        """The setpoint's velocity [m/s]."""
        return self._state[3:6].tolist()

    def step(self, control: GripperControl, palm) -> bool:
        """Advance the setpoint by one step for ``control``, the palm being at ``palm``; False if
        it stayed where it was (at rest). A control is a value (GripperControl): it is packed once
        and its packing kept while the same control comes again."""
        if control is not self._control:
            _pack_control(control, self._packed)
            self._control = control
        return _path_step(self._state, self._packed, float(palm[0]), float(palm[1]), float(palm[2]))


_PATH_STATE = 10
"""PalmPath's packed state: x (3), v (3), v_max, a_max, dt, max_lead."""
_PATH_CONTROL = 14
"""A packed control: has a target, the target (3), the target's velocity or the commanded one (3),
has a box, the box's low (3) and high (3) corners."""


def _pack_control(control: GripperControl, out: np.ndarray) -> None:
    out[:] = 0.0
    if control.palm_target is not None:
        out[0] = 1.0
        out[1:4] = control.palm_target
    if control.palm_velocity is not None:
        out[4:7] = control.palm_velocity
    if control.palm_box is not None:
        out[7] = 1.0
        out[8:11] = control.palm_box[0]
        out[11:14] = control.palm_box[1]


@nb.njit(cache=True)
def _brake(d, adt, dt):
    """The fastest speed for this step from which the path stops exactly at distance ``d`` >= 0,
    braking by at most a dt = ``adt`` per step: the speeds s, s - a dt, s - 2 a dt, ... then 0,
    their steps summing to d. With u = d / (a dt^2) and m = floor((sqrt(8u + 1) - 1) / 2) whole
    braking steps, s = a dt (u + m (m + 1) / 2) / (m + 1); for d < a dt^2 that is d / dt, the
    last step landing on the target. (The continuous curve s^2 / 2a = d overshoots by up to
    a dt^2 / 8 on the last step.)"""
    u = d / (adt * dt)
    m = math.floor(0.5 * (math.sqrt(8.0 * u + 1.0) - 1.0))
    return adt * (u + 0.5 * m * (m + 1)) / (m + 1)


@nb.njit(cache=True)
def _path_step(state, ctl, px, py, pz):
    """PalmPath.step on the packed state and control; the palm at (px, py, pz)."""
    dt, vm, a_max, max_lead = state[8], state[6], state[7], state[9]
    adt = a_max * dt
    x0, x1, x2 = state[0], state[1], state[2]
    wx, wy, wz = ctl[4], ctl[5], ctl[6]
    if ctl[0] != 0.0:
        ex, ey, ez = ctl[1] - x0, ctl[2] - x1, ctl[3] - x2
        d = math.sqrt(ex * ex + ey * ey + ez * ez)
        if d > 0.0:
            s = _brake(d, adt, dt) / d
            wx, wy, wz = wx + ex * s, wy + ey * s, wz + ez * s
    vx, vy, vz = state[3], state[4], state[5]
    if wx == 0.0 and wy == 0.0 and wz == 0.0 and vx == 0.0 and vy == 0.0 and vz == 0.0:
        return False  # at rest, and nothing asks it to move
    w = math.sqrt(wx * wx + wy * wy + wz * wz)
    if w > vm:
        wx, wy, wz = wx * vm / w, wy * vm / w, wz * vm / w
    # a palm that lags (blocked, pressing on something): the setpoint brakes to wait for it at
    # max_lead, as before a wall, so that it is not far away when the palm comes free
    lx, ly, lz = x0 - px, x1 - py, x2 - pz
    lead = math.sqrt(lx * lx + ly * ly + lz * lz)
    if lead > 0.0:
        out = (wx * lx + wy * ly + wz * lz) / lead
        cap = _brake(max(0.0, max_lead - lead), adt, dt)
        if out > cap:
            wx, wy, wz = wx - (out - cap) * lx / lead, wy - (out - cap) * ly / lead, wz - (out - cap) * lz / lead
    if ctl[7] != 0.0:  # brake before the walls, axis by axis
        wx = _wall(wx, x0, ctl[8], ctl[11], adt, dt)
        wy = _wall(wy, x1, ctl[9], ctl[12], adt, dt)
        wz = _wall(wz, x2, ctl[10], ctl[13], adt, dt)
    dx, dy, dz = wx - vx, wy - vy, wz - vz
    dv = math.sqrt(dx * dx + dy * dy + dz * dz)
    if dv > adt:  # at most a_max dt of velocity change a step
        dx, dy, dz = dx * adt / dv, dy * adt / dv, dz * adt / dv
    vx, vy, vz = vx + dx, vy + dy, vz + dz
    state[3], state[4], state[5] = vx, vy, vz
    state[0], state[1], state[2] = x0 + vx * dt, x1 + vy * dt, x2 + vz * dt
    return True


@nb.njit(cache=True)
def _wall(w, x, low, high, adt, dt):
    """Velocity ``w`` along one axis at ``x``, braked to stop at the wall it heads for."""
    if w > 0.0:
        return min(w, _brake(max(0.0, high - x), adt, dt))
    if w < 0.0:
        return max(w, -_brake(max(0.0, x - low), adt, dt))
    return w


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
        open_x = cfg.finger_stroke + fh[0]  # finger centre when fully open
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
        for j in self.core_links:  # travel from fully open (0) to the stop: the pads or the faces meeting
            c.changeDynamics(g, j, jointLowerLimit=0.0, jointUpperLimit=cfg.finger_travel)
        # The fingers are geared to each other (q_left = q_right), as a parallel gripper's rack and
        # pinion does: with two independent force-limited motors both saturated against the
        # cylinder, the pair and the cylinder were free to drift sideways together (neutral
        # equilibrium), 2.5 cm in 15 s for the rigid twin until one finger hit fully open.
        self.finger_gear = c.createConstraint(g, 0, g, 1, p.JOINT_GEAR, [1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
        c.changeConstraint(self.finger_gear, gearRatio=-1.0, maxForce=FINGER_GEAR_FORCE, erp=FINGER_GEAR_ERP)
        self.palm_constraint = c.createConstraint(g, -1, -1, -1, p.JOINT_FIXED, [0, 0, 0], [0, 0, 0],
                                                  np.asarray(start_palm).tolist())  # fmt: skip
        self._orientation = c.getQuaternionFromEuler([0.0, 0.0, self.yaw])
        self._arm_force = arm_force_limit(cfg)
        self._client_id = c._client
        self.control = GripperControl(np.array(start_palm, dtype=np.float64), 0.0)
        """The control applied last."""
        self.path = PalmPath(self.control.palm_target, v_max=cfg.arm_speed, a_max=cfg.arm_acceleration, dt=cfg.sim.dt)
        """The arm's path to the target."""
        self._set_palm_target(self.control.palm_target)
        self._set_finger_closing(0.0)

    @staticmethod
    def palm_offset_of(cfg: SceneConfig) -> float:
        """Height of the palm's centre above the finger cores' centres in ``cfg``'s gripper [m]."""
        return PALM_HALF_EXTENTS[2] + FINGER_DROP + cfg.finger_half_extents[2]

    def apply(self, control: GripperControl, palm) -> None:
        """Follow ``control`` for the coming physics step; ``palm`` is where the palm's centre is
        now. The arm moves its setpoint one step along its path toward the target or at the
        commanded velocity (the palm keeps the start yaw). The finger motors
        get a new target when it changed. Runs every physics step. A control is a value: it is kept
        as given, so its arrays must not be changed afterwards."""
        last = self.control
        if self.path.step(control, palm):
            self._set_palm_target(self.path.x)
        if control.finger_closing != last.finger_closing or control.finger_force != last.finger_force:
            self._set_finger_closing(control.finger_closing, control.finger_force)
        self.control = control

    @property
    def setpoint(self) -> np.ndarray:
        """Where the arm has the palm's centre now (the constraint's pivot) [m]."""
        return np.array(self.path.x, dtype=np.float64)

    def _set_palm_target(self, pos) -> None:
        # pybullet's own function with the client's id and arguments by position (pybullet parses
        # each keyword at ~0.4 us): this runs every physics step the arm moves
        p.changeConstraint(self.palm_constraint, pos, self._orientation, self._arm_force,
                           physicsClientId=self._client_id)  # fmt: skip

    def _set_finger_closing(self, closing: float, force: float | None = None) -> None:
        cfg = self.config
        force = cfg.finger_force if force is None else float(force)
        for j in self.core_links:
            self.client.setJointMotorControl2(self.body, j, p.POSITION_CONTROL, targetPosition=float(closing),
                                              force=force, maxVelocity=cfg.finger_speed)  # fmt: skip

    def finger_closing(self) -> np.ndarray:
        """Travel of each finger from fully open [m]."""
        return np.array([self.client.getJointState(self.body, j)[0] for j in self.core_links])


@dataclass(frozen=True, eq=False)
class Workspace:
    """Where the arm may take the grip point (the midpoint of the finger cores): a box, as a real
    arm's reach would be."""

    low: np.ndarray
    """(3,) lowest x, y, z [m]."""
    high: np.ndarray
    """(3,) highest x, y, z [m]."""

    @classmethod
    def of(cls, cfg: SceneConfig) -> Workspace:
        """x, y within WORKSPACE_HALF_WIDTH of the origin; the fingertips down to GROUND_CLEARANCE
        above the ground with the tissue's depth (``tissue.extrude``) below them whatever the kind,
        so every kind has the same workspace; up to GRIP_TOP."""
        fh = cfg.finger_half_extents
        w = WORKSPACE_HALF_WIDTH
        return cls(np.array([-w, -w, lowest_grip(fh[2], cfg.tissue.extrude)]), np.array([w, w, GRIP_TOP]))

    def clip(self, grip: np.ndarray) -> np.ndarray:
        """``grip`` moved into the box."""
        return np.clip(grip, self.low, self.high)


class PalmReadout(Protocol):
    """What an action mapping reads of the scene (GraspScene has it): declared here, not imported,
    so that the gripper module does not depend on the scene built on it."""

    @property
    def palm_target(self) -> np.ndarray | None: ...

    def grip_to_palm(self) -> np.ndarray: ...

    def palm_state(self) -> tuple[np.ndarray, ...]: ...


FINGER_ACTIONS = ("position", "force")
"""What the action's last entry commands (GripperActions): the fingers' closing travel, the motors
squeezing with the scene's finger_force at most; or the squeeze force itself."""


class GripperActions:
    """The env's action, ``Box(-1, 1, (4,))``, as a gripper control: x, y, z move the grip point,
    kept in the workspace; the last entry commands the fingers. How x, y, z move the arm is the
    subclass's (:class:`VelocityActions`). The last entry: with ``finger="position"`` the
    closing travel (-1 fully open, +1 closed to the stop, ``finger_travel``), the motors limited to the scene's
    ``finger_force``; with ``finger="force"`` the squeeze, 0 at -1 to ``finger_force`` at +1, the
    motors driving the fingers closed with that force (they close until they meet resistance and
    never open: the grip-force task starts with the cylinder between them)."""

    space = spaces.Box(-1.0, 1.0, shape=(4,), dtype=np.float32)

    def __init__(self, speed: float, control_frequency: float, workspace: Workspace, finger_travel: float, *,
                 finger: str = "position", finger_force: float | None = None, max_force: float | None = None) -> None:  # fmt: skip
        if max_force is not None:
            deprecated("GripperActions(max_force=...)", "GripperActions(finger_force=...)")
            if finger_force is not None:
                raise TypeError("GripperActions: give finger_force= (the new name of max_force=), not both")
            finger_force = max_force
        self.speed = float(speed)
        self.control_frequency = float(control_frequency)
        self.workspace = workspace
        self.finger_travel = float(finger_travel)
        """Each finger's closing travel from fully open to its stop [m] (``SceneConfig.finger_travel``)."""
        if finger not in FINGER_ACTIONS:
            raise ValueError(f"finger must be one of {FINGER_ACTIONS}, got {finger!r}")
        if finger == "force" and not (finger_force is not None and math.isfinite(finger_force) and finger_force > 0.0):
            raise ValueError(f"finger='force' needs finger_force > 0 [N], got {finger_force!r}")
        self.finger = finger
        self.finger_force = None if finger_force is None else float(finger_force)
        """The squeeze at full action with ``finger="force"`` [N] (the scene's ``finger_force``)."""

    def closing(self, action: np.ndarray) -> float:
        """The finger closing for ``action``'s last entry [m] (fully closed when it sets the force)."""
        if self.finger == "force":
            return self.finger_travel
        return 0.5 * (float(action[3]) + 1.0) * self.finger_travel

    def squeeze(self, action: np.ndarray) -> float | None:
        """The motors' force limit for ``action``'s last entry [N] (None: the scene's)."""
        if self.finger == "force":
            return 0.5 * (float(action[3]) + 1.0) * self.finger_force
        return None

    def control(self, action: np.ndarray, scene: PalmReadout) -> GripperControl:
        """The control for ``action`` (clipped to [-1, 1] already) in ``scene``'s state now."""
        raise NotImplementedError


class VelocityActions(GripperActions):
    """The arm's actions: x, y, z are the palm's velocity, ``speed`` at full action
    (the vector capped at ``speed`` by the arm); the arm reaches it with its acceleration limit and
    brakes before the workspace's walls."""

    def control(self, action: np.ndarray, scene: PalmReadout) -> GripperControl:
        ws, g2p = self.workspace, scene.grip_to_palm()
        return GripperControl(None, self.closing(action), palm_velocity=action[:3] * self.speed,
                              palm_box=(ws.low + g2p, ws.high + g2p), finger_force=self.squeeze(action))  # fmt: skip


__all__ = ["FINGER_ACTIONS", "GRIP_TOP", "Gripper", "GripperActions", "GripperControl", "PalmPath", "VelocityActions",
           "Workspace"]
