"""Finger kind 'segmented' (``fingers="segmented"``): the thesis' "traditional" fix
for rigid fingers that meet a cylinder only approximately aligned - several rigid bodies per
finger, joined by joints - built so that it can be compared side by side with the rigid twin and
the tissue.

Each finger keeps its prismatic core link (joint 0 / 1, the same box, mass, motor and gear as the
other kinds) and carries ``SegmentedConfig.segments`` rigid segments on its inner face, which are what
grips the cylinder:

- **Layout: side by side along the face's long horizontal axis y**, each segment the full height
  of the core (60 mm), ``(2 * 20 mm - gaps) / n`` wide, 6 mm thick, 2 mm in front of the core's
  inner face (a pivot boss; segment face + boss = 8 mm, the tissue pad's thickness). Full-height
  segments side by side rather than a stack along z: under a jaw wedge the core face is tilted
  about y, so the distance from the face to the (vertical) cylinder side grows along z; segments
  stacked along z, each pivoting about y, would all align but only the lowest would reach the
  cylinder, whereas one full-height segment pivoting about y lies flush along the whole line of
  contact - the line (not the point of the rigid twin's edge) is what keeps the cylinder from
  swinging out about the axis through the two fingers' contacts.
- **Joints: a two-axis gimbal per segment**, a revolute about the core's y (pitch: conforms to the
  wedge) then a revolute about the segment's z (yaw: turns the face to the cylinder's local
  tangent under gripper yaw / offset / the curvature). The gimbal sits at the segment's centre, so
  neither axis carries a gravity torque. Pitch and yaw are self-centring under a normal load: a
  round cylinder's normal force passes through its axis, so a segment yawed by phi about a pivot
  at distance D from that axis feels -F D phi (stable), and a pitched flat face touches along an
  edge, which turns it back flush. No twist about the face normal (x): that would let the cylinder
  turn in the grasp. The gimbal's middle link is a small massless-looking body (1 g, no collision
  shape), the pybullet way of chaining two revolutes.
- **Springs: a force-limited POSITION_CONTROL motor per passive joint whose force limit is set
  every physics step to the spring-damper torque |k q + c q'|** (``SegmentedConfig.spring =
  'motor'``, the default). pybullet has no spring joints for multibodies. An explicit torque
  -(k q + c q') (``'torque'``: TORQUE_CONTROL each step) is unstable here: a segment's inertia
  about its yaw axis is ~2e-7 kg m^2, so even k = 0.05 N m/rad gives omega dt = 2.1 at 1/240 s,
  and at the defaults the damper alone (c dt / I = 4.1 > 2) throws a joint kicked by 0.01 rad to
  pybullet's 100 rad/s joint-rate clamp within 5 steps.
  A plain POSITION_CONTROL motor with a fixed force limit is no spring either: it is a hard
  velocity constraint that holds the rest angle exactly until its limit, then gives way at a
  constant torque. Re-limiting the motor to the spring torque each step keeps both good parts:
  blocked by a contact (the case that matters, holding), the motor row saturates and pushes back
  with exactly k q + c q' - the static stiffness is k at any dt; free, it drives the joint toward
  rest at no more than ``SPRING_POSITION_GAIN`` of the angle per step, so it can never overshoot
  rest and never gain energy (free motion is over-damped where a real spring of that stiffness
  would ring faster than dt can resolve).
- **Loaded but not blocked** (a torque the segment can give way to, e.g. a contact that slides),
  the saturated row is an explicit spring-damper: with a = k dt^2 / I and b = c dt / I (I the
  joint's effective inertia, 1 / (M^-1)_jj from pybullet's mass matrix) it settles iff b < 2 and
  a + 2 b < 4, decaying by sqrt(1 - b) per step. The default dampers are near critical, b = 4.1
  (yaw) and 2.2 (pitch) at 1/240 s, outside that: the joint fell into a period-2 cycle (q, q/2, q,
  ...: 30 % off k q = tau under a constant 3e-3 N m on a yaw joint, and 0.065 <-> 0.13 rad
  chatter of a yaw joint holding the cylinder under a 0.1 rad wedge). So the damping the row
  carries is capped at ``MAX_STEP_DAMPING`` = b <= 0.5 (``damping_applied``): then a constant
  torque settles at exactly tau / k (1e-15) for a < 3. At the defaults a = 2.6 (yaw) / 1.4
  (pitch) with 3 segments; narrower segments have less yaw inertia (a = 5.8 at 4, 31 at 8, see
  ``step_stiffness``), where a free load still makes them chatter - only a blocking contact
  (the holding case) gives k exactly there.

Segment friction is ``SceneConfig.tissue.friction_static`` like the rigid twin's links (pybullet has one
coefficient), set in a changeDynamics call of its own and checked. Links of one multibody do not
collide with each other in pybullet (no self-collision flag), so segments and core overlap freely
where a segment pitches by more than the 2 mm boss allows (atan(2 / 30) = 0.067 rad): a real
finger would have its face relieved there; the core's box stays that of the other kinds so the
comparison changes one thing only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pybullet as p
from pybullet_utils.bullet_client import BulletClient

from ..config import TissueConfig
from ..sim.world import TissueSpec
from ..validation import check_choice, check_int, check_range
from .base import FingerConfig, FingerKind, FingerSite, Visual

SEGMENT_DEPTH = 0.008
"""How far the segments stand in front of their core (2 mm boss + 6 mm segment) [m]: the pad
depth of this kind, as the tissue's is extrude plus its particles' normal radius."""
SEGMENT_THICKNESS = 0.006
"""Thickness of a segment along the closing axis x [m]."""
SEGMENT_STANDOFF = SEGMENT_DEPTH - SEGMENT_THICKNESS
"""Gap between the core's inner face and a segment's back at rest (the pivot boss): 2 mm [m]."""
SEGMENT_GAP = 0.001
"""Gap between neighbouring segments along y [m]."""
SEGMENT_DENSITY = 2700.0
"""Mass density of a segment [kg/m^3] (aluminium): 12.3 g per segment at 3 segments."""
CARRIAGE_MASS = 0.005
"""Mass of a finger's carriage, the link its segments hang on [kg] (no collision shape)."""
CARRIAGE_INERTIA = 1e-7
"""Principal moments of inertia of a carriage [kg m^2]."""
GIMBAL_MASS = 0.001
"""Mass of a gimbal's middle link [kg] (no collision shape; the smallest that keeps pybullet's
articulated solve well conditioned next to the 12 g segments)."""
GIMBAL_INERTIA = 1e-8
"""Principal moments of inertia of a gimbal's middle link [kg m^2] (a 1 g, 5 mm cube's is 4e-9)."""
PITCH_LIMIT = 0.35
"""Travel of a segment about y either way [rad]: half the largest wedge the tissue held (0.45
rad) plus headroom."""
YAW_LIMIT = 0.3
"""Travel of a segment about z either way [rad]: where a 13 mm wide segment's back edge would
meet the core across the 2 mm boss."""
SPRING_POSITION_GAIN = 0.5
"""The spring motor's position gain: the share of its angle a free joint is driven back per step
at most (pybullet's rhs = gain * (0 - q) / dt; <= 1, so rest is never overshot)."""
MAX_STEP_DAMPING = 0.5
"""Largest damping the spring motor applies, as b = c_applied dt / I per step (I the joint's
effective inertia): the saturated motor is an explicit spring-damper, stable iff b < 2 and
k dt^2 / I + 2 b < 4 (module docstring)."""
DIVERGED_JOINT_RATE = 90.0
"""A passive joint turning faster than this [rad/s] has diverged: pybullet clamps joint rates at
100 rad/s (its maxJointVelocity), where the explicit 'torque' springs end up within 5 steps; the
motor springs stayed below 40 rad/s in the grasps measured."""


SEGMENT_SPRINGS: tuple[str, ...] = ("motor", "torque")
"""How the segments' springs are made in pybullet (SegmentedConfig.spring)."""
SEGMENT_RGBA = (0.2, 0.6, 0.75, 1.0)


@dataclass(frozen=True, eq=False)
class SegmentedConfig(FingerConfig):
    """Settings of the segmented fingers."""

    kind = "segmented"
    segments: int = 3
    """Segments per finger, side by side along the face's 40 mm: 3 gives 13 mm wide segments,
    narrower than the cylinder's flat-contact zone, so one of them always takes a lateral offset of
    up to the face's half width on its centre part."""
    stiffness_pitch: float = 0.3
    """Spring stiffness of a segment's pitch joint (about the face's long axis y) [N m/rad]."""
    stiffness_yaw: float = 0.03
    """Spring stiffness of a segment's yaw joint (about z) [N m/rad]."""
    damping_pitch: float = 0.002
    """Damping of a segment's pitch joint [N m s/rad] ('motor' springs apply at most 0.5 I / dt of
    it, I the joint's inertia: 4.5e-4 at 3 segments and 1/240 s; the module docstring says why)."""
    damping_yaw: float = 0.0002
    """Damping of a segment's yaw joint [N m s/rad] (capped likewise: 2.4e-5 at the defaults)."""
    spring: str = "motor"
    """How the springs are made in pybullet: 'motor' - a force-limited position motor re-limited
    every step to the spring-damper torque (stable at any dt); 'torque' - the explicit torque
    -(k q + c q') every step (unstable at these inertias; kept to measure it)."""

    def __post_init__(self) -> None:
        o = "SegmentedConfig"
        check_int("segments", self.segments, 1, 8, owner=o)
        check_range("stiffness_pitch", self.stiffness_pitch, 0.0, 100.0, lo_open=True, owner=o)
        check_range("stiffness_yaw", self.stiffness_yaw, 0.0, 100.0, lo_open=True, owner=o)
        check_range("damping_pitch", self.damping_pitch, 0.0, 10.0, owner=o)
        check_range("damping_yaw", self.damping_yaw, 0.0, 10.0, owner=o)
        check_choice("spring", self.spring, SEGMENT_SPRINGS, owner=o)


class SegmentedFingers(FingerKind):
    """Layout, building and per-step springs of the segmented fingers of one scene: the carriage,
    gimbal and segment links are appended to the gripper's createMultiBody lists before it is
    created (``extend_gripper``), ``mount`` then gears the carriages to the cores and sets
    friction, limits, inertias and the motors, and the springs are set before every physics step
    (``before_step``). Joints 0 and 1 stay the prismatic fingers."""

    name = "segmented"
    config_type = SegmentedConfig
    description = "sprung rigid segments on each core (the thesis' traditional fix)"

    @classmethod
    def pad_thickness(cls, config: FingerConfig, tissue: TissueConfig) -> float:
        return SEGMENT_DEPTH

    def __init__(self, scene_config) -> None:
        super().__init__(scene_config)
        cfg = scene_config
        seg: SegmentedConfig = self.config
        n = seg.segments
        fh = cfg.finger_half_extents
        width = (2.0 * fh[1] - (n - 1) * SEGMENT_GAP) / n
        if width <= 0.0:
            raise ValueError(f"SegmentedConfig.segments={n} leaves no width for a segment on a "
                             f"{2 * fh[1] * 1000:.0f} mm face")  # fmt: skip
        self.half_extents = (0.5 * SEGMENT_THICKNESS, 0.5 * width, fh[2])
        self.segment_mass = SEGMENT_DENSITY * SEGMENT_THICKNESS * width * 2.0 * fh[2]
        self.centres_y = [-fh[1] + 0.5 * width + i * (width + SEGMENT_GAP) for i in range(n)]
        # Link indices. pybullet orders a multibody's links depth first, so segments hanging off
        # core 0 would push core 1 to joint 1 + 2n: instead each finger's segments hang off a
        # carriage, a base child listed after both cores that slides on the core's own axis and
        # is geared to it 1:1 (see attach). Order: cores 0, 1; then per finger its carriage and,
        # per segment, a gimbal link (pitch joint) and the segment link (yaw joint).
        self.carriage_links = [2, 3 + 2 * n]
        self.gimbal_links = [[c + 1 + 2 * i for i in range(n)] for c in self.carriage_links]
        self.segment_links = [[g + 1 for g in row] for row in self.gimbal_links]
        self._finger_links = ((0, *self.segment_links[0]), (1, *self.segment_links[1]))
        self.pitch_joints = [j for row in self.gimbal_links for j in row]
        self.yaw_joints = [j for row in self.segment_links for j in row]
        self.joints = self.pitch_joints + self.yaw_joints
        """The passive joints (pitch first, then yaw)."""
        self._k = np.array([seg.stiffness_pitch] * len(self.pitch_joints)
                           + [seg.stiffness_yaw] * len(self.yaw_joints))  # fmt: skip
        self._c = np.array([seg.damping_pitch] * len(self.pitch_joints)
                           + [seg.damping_yaw] * len(self.yaw_joints))  # fmt: skip
        self.inertia = np.zeros(len(self.joints))
        """Effective inertia of each passive joint, 1 / (M^-1)_jj at rest [kg m^2] (set by attach)."""
        self.damping_applied = self._c.copy()
        """Damping the 'motor' springs apply [N m s/rad]: c, capped at MAX_STEP_DAMPING I / dt."""
        self.carriage_gears: list[int] = []
        self.client: BulletClient | None = None
        self.gripper = -1

    @property
    def finger_links(self) -> tuple[tuple[int, ...], tuple[int, ...]]:
        """Each finger's core and its segments: their contacts with the cylinder are the finger's."""
        return self._finger_links

    # --- building --------------------------------------------------------------------------------

    def extend_gripper(self, links: dict[str, list], client: BulletClient) -> None:
        """Append the carriages, gimbals and segments to the gripper's createMultiBody link lists
        (which hold the two cores)."""
        if len(links["linkMasses"]) != 2:
            raise ValueError("the segmented fingers' links go right after the two finger cores")
        fh = self.scene_config.finger_half_extents
        seg_col = client.createCollisionShape(p.GEOM_BOX, halfExtents=self.half_extents)
        seg_vis = client.createVisualShape(p.GEOM_BOX, halfExtents=self.half_extents, rgbaColor=list(SEGMENT_RGBA))
        # pivot depth in front of the core's centre: the inner face, the boss, half a segment
        depth = fh[0] + SEGMENT_STANDOFF + 0.5 * SEGMENT_THICKNESS
        for k, inward in ((0, 1.0), (1, -1.0)):  # the left core's inner face is +x, the right's -x
            carriage = self.carriage_links[k]
            assert len(links["linkMasses"]) == carriage
            # the carriage: where its core is, on the core's joint axis, from the base
            self._add(links, CARRIAGE_MASS, -1, -1, list(links["linkPositions"][k]), orn=list(links["linkOrientations"][k]),
                      parent=0, joint=p.JOINT_PRISMATIC, axis=list(links["linkJointAxis"][k]))  # fmt: skip
            for i, y in enumerate(self.centres_y):
                gimbal = self.gimbal_links[k][i]
                assert len(links["linkMasses"]) == gimbal
                self._add(links, GIMBAL_MASS, -1, -1, [inward * depth, y, 0.0], parent=carriage + 1,
                          joint=p.JOINT_REVOLUTE, axis=[0.0, 1.0, 0.0])  # fmt: skip
                self._add(links, self.segment_mass, seg_col, seg_vis, [0.0, 0.0, 0.0], parent=gimbal + 1,
                          joint=p.JOINT_REVOLUTE, axis=[0.0, 0.0, 1.0])  # fmt: skip

    @staticmethod
    def _add(links, mass, col, vis, pos, *, parent, joint, axis, orn=(0.0, 0.0, 0.0, 1.0)) -> None:
        links["linkMasses"].append(mass)
        links["linkCollisionShapeIndices"].append(col)
        links["linkVisualShapeIndices"].append(vis)
        links["linkPositions"].append(pos)
        links["linkOrientations"].append(list(orn))
        links["linkInertialFramePositions"].append([0.0, 0.0, 0.0])
        links["linkInertialFrameOrientations"].append([0.0, 0.0, 0.0, 1.0])
        links["linkParentIndices"].append(parent)  # createMultiBody: 0 is the base, j + 1 link j
        links["linkJointTypes"].append(joint)
        links["linkJointAxis"].append(axis)

    def mount(self, site: FingerSite) -> list[TissueSpec]:
        """After createMultiBody: check the link order, gear each carriage to its core, set segment
        friction, inertias, joint limits, and replace the passive joints' default velocity motors
        by the spring motors."""
        super().mount(site)
        self.client = c = site.client
        self.gripper = g = site.gripper
        gear_force, gear_erp = site.gear_force, site.gear_erp
        cfg = self.scene_config
        for j, kind in [(0, p.JOINT_PRISMATIC), (1, p.JOINT_PRISMATIC)] + [(j, p.JOINT_PRISMATIC) for j in self.carriage_links] \
                + [(j, p.JOINT_REVOLUTE) for j in self.joints]:  # fmt: skip
            if c.getJointInfo(g, j)[2] != kind:
                raise RuntimeError(f"gripper joint {j} is not of the type the segmented fingers were laid out with")
        for k, carriage in enumerate(self.carriage_links):
            # q_carriage = q_core (gear ratio -1 is pybullet's "equal" as for the finger gear):
            # the squeeze goes from the segments through this gear into the core's motor
            gear = c.createConstraint(g, k, g, carriage, p.JOINT_GEAR, [1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
            c.changeConstraint(gear, gearRatio=-1.0, maxForce=gear_force, erp=gear_erp)
            self.carriage_gears.append(gear)
            c.changeDynamics(g, carriage, jointLowerLimit=0.0, jointUpperLimit=cfg.finger_stroke)
        mu = cfg.tissue.friction_static
        for link in self.segment_links[0] + self.segment_links[1]:
            # friction in a call of its own (pybullet drops a whole changeDynamics call on a link
            # that also sets damping), and checked
            c.changeDynamics(g, link, lateralFriction=mu)
            if c.getDynamicsInfo(g, link)[1] != mu:
                raise RuntimeError(f"pybullet did not take the friction of segment link {link}")
        # links without a collision shape get no rotational inertia from pybullet
        for link in self.carriage_links:
            c.changeDynamics(g, link, localInertiaDiagonal=[CARRIAGE_INERTIA] * 3)
        for link in self.pitch_joints:
            c.changeDynamics(g, link, localInertiaDiagonal=[GIMBAL_INERTIA] * 3)
        for j in self.pitch_joints:
            c.changeDynamics(g, j, jointLowerLimit=-PITCH_LIMIT, jointUpperLimit=PITCH_LIMIT)
        for j in self.yaw_joints:
            c.changeDynamics(g, j, jointLowerLimit=-YAW_LIMIT, jointUpperLimit=YAW_LIMIT)
        # pybullet gives every joint a velocity motor (target 0) with a force limit by default: it
        # would hold the carriages and the passive joints still. The carriages follow their cores
        # through the gear alone; the passive joints get only the springs below.
        free = self.carriage_links + self.joints
        c.setJointMotorControlArray(g, free, p.VELOCITY_CONTROL, forces=[0.0] * len(free))
        # the joints' effective inertias (the response of a joint to its own torque, the others
        # free), for the damping cap; the gimbals sit at the segments' centres, so they hardly
        # change with the angles
        n = c.getNumJoints(g)
        mass = np.array(c.calculateMassMatrix(g, [c.getJointState(g, j)[0] for j in range(n)]))
        base = mass.shape[0] - n  # pybullet puts the free base's 6 dofs first
        inv_diag = np.diag(np.linalg.inv(mass))
        self.inertia = np.array([1.0 / inv_diag[base + j] for j in self.joints])
        self.damping_applied = np.minimum(self._c, MAX_STEP_DAMPING * self.inertia / cfg.sim.dt)
        self.apply_springs()
        return []

    # --- every step ------------------------------------------------------------------------------

    def before_step(self) -> None:
        self.apply_springs()

    def joint_states(self) -> tuple[np.ndarray, np.ndarray]:
        """Angles [rad] and rates [rad/s] of the passive joints (pitch joints first, then yaw)."""
        states = self.client.getJointStates(self.gripper, self.joints)
        return np.array([s[0] for s in states]), np.array([s[1] for s in states])

    def apply_springs(self) -> None:
        """Set this step's spring-damper torque tau = -(k q + c q') on every passive joint (see the
        module docstring for why through a re-limited motor)."""
        q, v = self.joint_states()
        c = self.client
        n = len(self.joints)
        if self.config.spring == "torque":
            tau = -(self._k * q + self._c * v)
            c.setJointMotorControlArray(self.gripper, self.joints, p.TORQUE_CONTROL, forces=tau.tolist())
            return
        # The damper as far as the explicit row stays stable (damping_applied, module docstring).
        tau = -(self._k * q + self.damping_applied * v)
        # The motor pushes toward rest; while the damper outweighs the spring on the way back
        # (tau points away from rest) it gets no force: the row cannot push away from its target.
        limit = np.where(tau * q <= 0.0, np.abs(tau), 0.0)
        c.setJointMotorControlArray(
            self.gripper, self.joints, p.POSITION_CONTROL, targetPositions=[0.0] * n, targetVelocities=[0.0] * n,
            positionGains=[SPRING_POSITION_GAIN] * n, velocityGains=[1.0] * n, forces=limit.tolist(),
        )  # fmt: skip

    # --- queries ---------------------------------------------------------------------------------

    def step_stiffness(self) -> np.ndarray:
        """a = k dt^2 / I of each passive joint (pitch first): the saturated motor spring settles
        under a free load for a < 3 (module docstring)."""
        return self._k * self.scene_config.sim.dt**2 / self.inertia

    def is_finite(self) -> bool:
        q, v = self.joint_states()
        return bool(np.isfinite(q).all() and np.isfinite(v).all())

    def diverged(self) -> bool:
        """Non-finite joint states, or a passive joint faster than DIVERGED_JOINT_RATE: a segment
        blown up between its joint limits stays finite and never shows in the cores' or the
        cylinder's velocities, which is all the env checked before."""
        return self.divergence() is not None

    def divergence(self) -> str | None:
        """Why the segments count as blown up (see :meth:`diverged`), or ``None``."""
        q, v = self.joint_states()
        if not (np.isfinite(q).all() and np.isfinite(v).all()):
            return "non-finite segment joint state"
        rate = float(np.abs(v).max())
        if rate > DIVERGED_JOINT_RATE:
            return f"a finger segment turning at {rate:.0f} rad/s (limit {DIVERGED_JOINT_RATE:g} rad/s)"
        return None

    def visuals(self) -> list[Visual]:
        """The cores and every segment, as boxes at their links' poses."""
        return super().visuals() + [
            Visual("box", np.asarray(SEGMENT_RGBA), body=self.gripper, link=link, half_extents=self.half_extents)
            for row in self.segment_links for link in row
        ]  # fmt: skip


__all__ = ["SEGMENT_DEPTH", "SEGMENT_SPRINGS", "SegmentedConfig", "SegmentedFingers"]
