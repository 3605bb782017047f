"""The grasp scene (thesis 5.2.1): a static ground, a gripper whose two finger links are the rigid
cores, and a rigid cylinder. With ``fingers='tissue'`` each core is wrapped in oriented-particle
tissue; with ``fingers='rigid'`` the same cores touch the cylinder through pybullet's own contacts.

Frames: z up, the cylinder stands at the origin. The gripper palm is a pybullet base driven by a
force-limited fixed constraint (the "arm"); the fingers are prismatic links closing along the
palm's x axis, each driven by a force-limited position motor: the motors push, the tissue pushes
back, so the squeeze is a force, not a teleport.
"""

from __future__ import annotations

import math

import numpy as np
import pybullet as p
from pybullet_utils.bullet_client import BulletClient

from .config import FINGER_DROP, PALM_HALF_EXTENTS, SceneConfig
from .fem import FemPads, fem_ground_shape
from .segmented import SegmentedFingers
from .sim.bullet import RigidRef, connect
from .sim.world import ShapeSpec, TissueSpec, World
from .tissue.builder import build_combined_body, core_shape_from_bullet

CYLINDER_SHAPE = 1
"""Index of the cylinder among the shapes the tissue sees (see the ``shapes`` list below)."""
FINGER_GEAR_FORCE = 100.0
"""Force limit of the gear that keeps both fingers' travel equal [N]: far above what the motors
(``finger_force``) or the tissue can make, so it never gives way."""
FINGER_GEAR_ERP = 0.2
"""Share of the gear's position error corrected per step: pybullet's gear constraint acts on
velocities only by default (erp 0), and the travel difference then drifted by 3 mm in 60 s."""


class GraspScene:
    """Builds and drives the scene; :meth:`step` advances it by one physics step."""

    def __init__(self, config: SceneConfig | None = None, *, gui: bool = False, client: BulletClient | None = None) -> None:
        """Build the scene in a new physics server, or in ``client`` after emptying it
        (``resetSimulation``): an env's reset rebuilds rather than restores, because pybullet's
        ``restoreState`` is not bit-exact (it drifted 2.3 mm in 120 steps) and a rebuild is."""
        self.config = cfg = config if config is not None else SceneConfig()
        if client is None:
            client = connect(gui=gui)
            if cfg.fingers == "fem":  # --- fem hook: pybullet's deformable world (fem.py)
                client.resetSimulation(p.RESET_USE_DEFORMABLE_WORLD)
        elif cfg.fingers == "fem":  # --- fem hook: every rebuild asks for the deformable world again
            client.resetSimulation(p.RESET_USE_DEFORMABLE_WORLD)
        else:
            client.resetSimulation()
        self.client = c = client
        sim = cfg.sim
        c.setGravity(0.0, 0.0, -sim.gravity)
        # One pybullet step per world step, no substeps: the tissue and the rigid bodies share dt.
        c.setPhysicsEngineParameter(fixedTimeStep=sim.dt, numSubSteps=0, deterministicOverlappingPairs=1)
        # --- fem hook: the pads take fem_substeps pybullet steps per world step (see step()). Set
        # before any motor command: pybullet turns a motor's force limit into an impulse limit with
        # the time step current when the command is sent.
        self.bullet_steps = cfg.fem_substeps if cfg.fingers == "fem" else 1
        if self.bullet_steps > 1:
            c.setPhysicsEngineParameter(fixedTimeStep=sim.dt / self.bullet_steps)

        # --- ground
        # --- fem hook: pybullet's deformable world cannot collide soft bodies with a plane (fem.py)
        plane = fem_ground_shape(c) if cfg.fingers == "fem" else c.createCollisionShape(p.GEOM_PLANE)
        self.ground = c.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=plane)
        c.changeDynamics(self.ground, -1, lateralFriction=cfg.ground_friction)

        # --- cylinder (a free rigid body)
        r, h = cfg.cylinder_radius, cfg.cylinder_height
        cyl_col = c.createCollisionShape(p.GEOM_CYLINDER, radius=r, height=h)
        cyl_vis = c.createVisualShape(p.GEOM_CYLINDER, radius=r, length=h, rgbaColor=[0.9, 0.6, 0.2, 1.0])
        self.cylinder = c.createMultiBody(
            baseMass=cfg.cylinder_mass, baseCollisionShapeIndex=cyl_col, baseVisualShapeIndex=cyl_vis,
            basePosition=[cfg.cylinder_xy[0], cfg.cylinder_xy[1], 0.5 * h],
        )  # fmt: skip
        c.changeDynamics(self.cylinder, -1, lateralFriction=cfg.cylinder_friction, linearDamping=0.0,
                         angularDamping=0.0)  # fmt: skip
        self.cylinder_rest_z = 0.5 * h

        # --- gripper: palm base + two prismatic finger links
        fh = cfg.finger_half_extents
        self.grasp_height = 0.5 * h  # finger centres at the cylinder's mid height
        self.palm_offset = PALM_HALF_EXTENTS[2] + FINGER_DROP + fh[2]  # palm centre above finger centres
        palm_col = c.createCollisionShape(p.GEOM_BOX, halfExtents=PALM_HALF_EXTENTS)
        palm_vis = c.createVisualShape(p.GEOM_BOX, halfExtents=PALM_HALF_EXTENTS, rgbaColor=[0.4, 0.4, 0.45, 1])
        fin_col = c.createCollisionShape(p.GEOM_BOX, halfExtents=fh)
        fin_vis = c.createVisualShape(p.GEOM_BOX, halfExtents=fh, rgbaColor=[0.3, 0.3, 0.8, 1.0])
        open_x = cfg.finger_max_opening + fh[0]  # finger centre when fully open
        # Jaw wedge: each finger tilted by half the wedge about y, the left (-x) one by -w/2 and the
        # right one by +w/2 (the gap wider at the top for w > 0, measured: inner faces 6.3 cm from the centre at the top, 5.7 at the bottom for w = 0.2). A prismatic joint's axis is given in
        # the link frame, so it is turned back by the tilt to keep both fingers closing along the
        # palm's x axis.
        half = 0.5 * cfg.jaw_wedge
        tilt_left = c.getQuaternionFromEuler([0.0, -half, 0.0])
        tilt_right = c.getQuaternionFromEuler([0.0, half, 0.0])
        axis_left = [math.cos(half), 0.0, -math.sin(half)]  # R_y(-half)^T (+x)
        axis_right = [-math.cos(half), 0.0, -math.sin(half)]  # R_y(+half)^T (-x)
        self.start_palm = np.array([cfg.gripper_xy[0], cfg.gripper_xy[1] + cfg.lateral_offset,
                                    self.grasp_height + self.palm_offset + cfg.start_height])  # fmt: skip
        self.start_yaw = cfg.yaw
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
        # --- segmented fingers (hook): segment links after the two cores, joints 0/1 stay the fingers
        self.segments: SegmentedFingers | None = None
        self.finger_links: tuple[tuple[int, ...], tuple[int, ...]] = ((0,), (1,))
        """Gripper links whose contacts with the cylinder count as each finger's."""
        if cfg.fingers == "segmented":
            self.segments = SegmentedFingers(cfg)
            self.segments.extend_links(links, c)
            self.finger_links = self.segments.finger_links
        self.gripper = c.createMultiBody(
            baseMass=cfg.palm_mass,
            baseCollisionShapeIndex=palm_col,
            baseVisualShapeIndex=palm_vis,
            basePosition=self.start_palm.tolist(),
            baseOrientation=c.getQuaternionFromEuler([0.0, 0.0, cfg.yaw]),
            **links,
        )
        g = self.gripper
        # Damping exists only for the base: pybullet ignores a whole changeDynamics call on a link
        # that asks for damping too (the fingers kept the default friction 0.5 that way), so the
        # friction of each link is set on its own.
        c.changeDynamics(g, -1, linearDamping=0.0, angularDamping=0.0)
        for link in (-1, 0, 1):
            c.changeDynamics(g, link, lateralFriction=cfg.tissue.friction_static)
            if c.getDynamicsInfo(g, link)[1] != cfg.tissue.friction_static:
                raise RuntimeError(f"pybullet did not take the friction of gripper link {link}")
        for j in (0, 1):  # travel from fully open (0) to the faces meeting at the centre
            c.changeDynamics(g, j, jointLowerLimit=0.0, jointUpperLimit=cfg.finger_max_opening)
        # The fingers are geared to each other (q_left = q_right), as a parallel gripper's rack and
        # pinion does: with two independent force-limited motors both saturated against the
        # cylinder, the pair and the cylinder were free to drift sideways together (neutral
        # equilibrium), 2.5 cm in 15 s for the rigid twin until one finger hit fully open.
        self.finger_gear = c.createConstraint(g, 0, g, 1, p.JOINT_GEAR, [1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
        c.changeConstraint(self.finger_gear, gearRatio=-1.0, maxForce=FINGER_GEAR_FORCE, erp=FINGER_GEAR_ERP)
        self.palm_constraint = c.createConstraint(g, -1, -1, -1, p.JOINT_FIXED, [0, 0, 0], [0, 0, 0],
                                                  self.start_palm.tolist())  # fmt: skip
        self.set_palm_target(self.start_palm, yaw=cfg.yaw)
        self.set_finger_target(0.0)
        if self.segments is not None:
            self.segments.attach(c, g, gear_force=FINGER_GEAR_FORCE, gear_erp=FINGER_GEAR_ERP)

        # --- what the tissue sees
        # Cores are infinitely heavy inside the solve in the thesis coupling; under the consistent one
        # they slide along their joints (World). The palm, held by the stiff arm, never moves in it.
        rigid = [
            RigidRef(g, 0, gravity=False, in_solve=False, free_base=False, core=True),  # left core
            RigidRef(g, 1, gravity=False, in_solve=False, free_base=False, core=True),  # right core
            RigidRef(self.cylinder, -1, gravity=True, in_solve=True, free_base=True),
            RigidRef(g, -1, gravity=False, in_solve=False, free_base=False),  # palm, held by the arm
        ]
        shapes = [
            ShapeSpec("plane", (0.0, 0.0, 0.0)),
            ShapeSpec("cylinder", (r, 0.5 * h, 0.0), rigid=2),
            ShapeSpec("box", tuple(fh), rigid=0),
            ShapeSpec("box", tuple(fh), rigid=1),
            ShapeSpec("box", PALM_HALF_EXTENTS, rigid=3),
        ]
        tissue = []
        if cfg.fingers == "tissue":
            # 'contact': the inner face (toward the other finger: +x for the left core, -x for the
            # right one, in the core frame) and the tip (-z). The back and top never meet the
            # cylinder; the sides only when it is offset past the face's end, and then the bare
            # core's pybullet contact takes it.
            faces = {0: ("+x", "-z"), 1: ("-x", "-z")} if cfg.tissue_faces == "contact" else {0: None, 1: None}
            for link, shape_index in ((0, 2), (1, 3)):
                core, offset, orn = core_shape_from_bullet(c, g, link)
                if abs(orn[3]) < 1.0 - 1e-12:
                    raise ValueError("finger collision shape must be aligned with its link frame")
                body = build_combined_body(core, cfg.tissue, shape_offset=offset, faces=faces[link])
                tissue.append(TissueSpec(body, shape_index))
        self.world = World(c, sim, rigid, shapes, tissue)
        # --- fem hook: FEM pads on the cores, anchored to the finger links (fem.py)
        self.fem = FemPads(c, cfg, g, self.cylinder) if cfg.fingers == "fem" else None

    # --- stepping --------------------------------------------------------------------------------

    def step(self) -> None:
        """One physics step of the whole scene (``world.step()``: tissue, then pybullet)."""
        if self.segments is not None:
            self.segments.apply_springs()
        for _ in range(self.bullet_steps - 1):  # --- fem hook: the pads' substeps (no tissue here)
            self.client.stepSimulation()
        self.world.step()

    def diverged(self) -> bool:
        """True once the simulation has blown up (:meth:`divergence` says how). The env and the
        accuracy measurements share it."""
        return self.divergence() is not None

    def divergence(self) -> str | None:
        """Why the simulation counts as blown up, or ``None``: a non-finite value, a body faster
        than 20 m/s or 500 rad/s, a particle faster than 20 m/s or 3 cm from its core, a finger
        segment turning faster than its limit (segmented.py)."""
        w = self.world
        if not w.is_finite():
            return "non-finite state"
        if self.segments is not None:
            why = self.segments.divergence()
            if why is not None:
                return why
        col = w.colliders
        v, om = float(np.abs(col.rigid_v).max()), float(np.abs(col.rigid_w).max())
        if v > 20.0 or om > 500.0:
            return f"a rigid body at {v:.1f} m/s, {om:.0f} rad/s (limits 20 m/s, 500 rad/s)"
        if w.state is not None:
            pv = float(np.abs(w.state.particle_v).max())
            if pv > 20.0:
                return f"a tissue particle at {pv:.1f} m/s (limit 20 m/s)"
            dev = float(w.tissue_deviation())
            if dev > 0.03:
                return f"tissue torn: a particle {dev * 100:.1f} cm from where its core holds it (limit 3 cm)"
        return None

    def finger_forces(self) -> np.ndarray:
        """Normal force each finger (left, right) pressed on the cylinder with in the last physics
        step [N]: the tissue's contacts plus pybullet's contacts of the finger's own links (a core
        can meet the cylinder too, and is all there is of a rigid finger)."""
        c = self.client
        f = np.zeros(2)
        for k, links in enumerate(self.finger_links):
            for link in links:
                for pt in c.getContactPoints(bodyA=self.cylinder, bodyB=self.gripper, linkIndexA=-1, linkIndexB=link):
                    f[k] += pt[9]
        if self.world.solver is not None:
            f += self.world.solver.contact_normal_force(CYLINDER_SHAPE)
        if self.fem is not None:  # --- fem hook: the pads' contacts (fem.py)
            f += self.fem.contact_normal_force()
        return f

    def penetration(self) -> tuple[float, float]:
        """(deepest overlap of a finger with the cylinder or the ground, deepest intrusion of tissue
        into its own core) now [m], the same measure for every finger kind: the tissue's overlap
        with any rigid shape, and the depth of pybullet's own contacts between the gripper and the
        cylinder or the ground (a rigid finger's, or a bare core's)."""
        pen, intrusion = self.world.penetration()
        c = self.client
        for other in (self.cylinder, self.ground):
            for pt in c.getContactPoints(bodyA=self.gripper, bodyB=other):
                pen = max(pen, -pt[8])
        if self.fem is not None:  # --- fem hook: the pads' nodes (fem.py)
            fem_pen, fem_intrusion = self.fem.penetration()
            pen, intrusion = max(pen, fem_pen), max(intrusion, fem_intrusion)
        return pen, intrusion

    # --- control ---------------------------------------------------------------------------------

    def set_palm_target(self, pos: np.ndarray, *, yaw: float | None = None) -> None:
        """Where the arm pulls the palm (its centre) with at most ``palm_force``."""
        yaw = self.start_yaw if yaw is None else yaw
        self.client.changeConstraint(
            self.palm_constraint, jointChildPivot=[float(v) for v in pos],
            jointChildFrameOrientation=self.client.getQuaternionFromEuler([0.0, 0.0, yaw]),
            maxForce=self.config.palm_force,
        )  # fmt: skip
        self.palm_target = np.asarray(pos, dtype=np.float64).copy()

    def set_finger_target(self, closing: float) -> None:
        """Drive both fingers toward ``closing`` metres of travel from fully open, each with at most
        ``finger_force`` and ``finger_speed``."""
        cfg = self.config
        for j in (0, 1):
            self.client.setJointMotorControl2(
                self.gripper, j, p.POSITION_CONTROL, targetPosition=float(closing), force=cfg.finger_force,
                maxVelocity=cfg.finger_speed,
            )  # fmt: skip
        self.finger_target = float(closing)

    # --- queries ---------------------------------------------------------------------------------

    def palm_position(self) -> np.ndarray:
        return np.asarray(self.client.getBasePositionAndOrientation(self.gripper)[0])

    def cylinder_pose(self) -> tuple[np.ndarray, np.ndarray]:
        pos, orn = self.client.getBasePositionAndOrientation(self.cylinder)
        return np.asarray(pos), np.asarray(orn)

    def lift_height(self) -> float:
        """Height of the cylinder's centre above where it rests on the ground [m]."""
        return float(self.cylinder_pose()[0][2] - self.cylinder_rest_z)

    def finger_closing(self) -> np.ndarray:
        """Travel of each finger from fully open [m]."""
        return np.array([self.client.getJointState(self.gripper, j)[0] for j in (0, 1)])

    def cylinder_tilt(self) -> float:
        """Angle between the cylinder's axis and the vertical [rad]."""
        orn = self.cylinder_pose()[1]
        x, y, z, w = orn
        axis_z = 1.0 - 2.0 * (x * x + y * y)
        return float(math.acos(max(-1.0, min(1.0, axis_z))))

    def close(self) -> None:
        if self.client is not None:
            try:
                self.client.disconnect()
            except p.error:
                pass
            self.client = None
