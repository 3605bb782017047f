"""The grasp scene (thesis 5.2.1): a static ground, a rigid cylinder, and the gripper whose two
finger cores carry a finger kind (softgrasp_env/fingers/), in one pybullet server with the
oriented-particle world around it (softgrasp_env/sim/world.py).

Frames: z up, the cylinder stands at ``cylinder_xy`` on the ground. One :meth:`GraspScene.step`
is one physics step: the control (if given) goes to the gripper, the finger kind's per-step hook
runs, then the world steps (tissue, then pybullet).

The scene owns the slots of the world's rigid arrays (``SLOTS``) and of the shapes the tissue
sees (``SHAPES``): everything else reads the bodies through the scene's named accessors.
"""

from __future__ import annotations

import math

import numpy as np
import pybullet as p
from pybullet_utils.bullet_client import BulletClient

from ..fingers import FingerKind, FingerSite, Visual
from ..sim.bullet import RigidRef, connect
from ..sim.world import ShapeSpec, World
from .config import PALM_HALF_EXTENTS, SceneConfig, grasp_height
from .gripper import FINGER_GEAR_ERP, FINGER_GEAR_FORCE, PALM_RGBA, Gripper, GripperControl
from .objects import OBJECT_KINDS, ObjectGeometry, object_geometry

SLOTS = ("left_core", "right_core", "cylinder", "palm")
"""The rigid bodies the world tracks, in the order of its rigid arrays (``world.colliders``)."""
LEFT, RIGHT, CYLINDER, PALM = range(len(SLOTS))
SHAPES = ("ground", "cylinder", "left_core", "right_core", "palm")
"""The collision shapes the tissue sees, in order."""
CYLINDER_SHAPE = SHAPES.index("cylinder")

CYLINDER_RGBA = (0.9, 0.6, 0.2, 1.0)
MAX_RIGID_SPEED = 20.0
"""A rigid body faster than this [m/s] has diverged."""
MAX_RIGID_SPIN = 500.0
"""A rigid body turning faster than this [rad/s] has diverged."""


class GraspScene:
    """Builds and drives the scene; :meth:`step` advances it by one physics step."""

    def __init__(self, config: SceneConfig | None = None, *, gui: bool = False, client: BulletClient | None = None) -> None:
        """Build the scene in a new physics server, or in ``client`` after emptying it
        (``resetSimulation``): an env's reset rebuilds rather than restores, because pybullet's
        ``restoreState`` is not bit-exact (it drifted 2.3 mm in 120 steps) and a rebuild is."""
        self.config = cfg = config if config is not None else SceneConfig()
        self.fingers: FingerKind = cfg.kind(cfg)
        fingers = self.fingers
        if client is None:
            client = connect(gui=gui)
            if fingers.reset_flags:  # a fresh server is empty; only a world of another type needs a reset
                client.resetSimulation(fingers.reset_flags)
        else:
            client.resetSimulation(fingers.reset_flags)
        self.client = c = client
        sim = cfg.sim
        c.setGravity(0.0, 0.0, -sim.gravity)
        # One pybullet step per world step, no substeps: the tissue and the rigid bodies share dt.
        c.setPhysicsEngineParameter(fixedTimeStep=sim.dt, numSubSteps=0, deterministicOverlappingPairs=1)
        # A kind may take several pybullet steps per world step (the FEM pads). Set before any
        # motor command: pybullet turns a motor's force limit into an impulse limit with the time
        # step current when the command is sent.
        self.bullet_steps = fingers.bullet_substeps
        # ... and a kind may run the whole world (tissue and pybullet) in several shorter steps (the
        # compliant tissue, where its coupling to pybullet would ring at a long step)
        self.world_steps = fingers.world_substeps
        if self.bullet_steps * self.world_steps > 1:
            c.setPhysicsEngineParameter(fixedTimeStep=sim.dt / (self.bullet_steps * self.world_steps))

        # --- ground
        self.ground = c.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=fingers.ground_shape(c))
        c.changeDynamics(self.ground, -1, lateralFriction=cfg.ground_friction)

        # --- the object (a free rigid body): the cylinder, or cfg.object
        r, h = cfg.cylinder_radius, cfg.cylinder_height
        self.object_geometry: ObjectGeometry | None = None
        """The grasped object's shape, mass properties and resting pose; None for the cylinder."""
        if cfg.object is None:
            cyl_col = c.createCollisionShape(p.GEOM_CYLINDER, radius=r, height=h)
            cyl_vis = c.createVisualShape(p.GEOM_CYLINDER, radius=r, length=h, rgbaColor=list(CYLINDER_RGBA))
            self.cylinder = c.createMultiBody(
                baseMass=cfg.cylinder_mass, baseCollisionShapeIndex=cyl_col, baseVisualShapeIndex=cyl_vis,
                basePosition=[cfg.cylinder_xy[0], cfg.cylinder_xy[1], 0.5 * h],
            )  # fmt: skip
            c.changeDynamics(self.cylinder, -1, lateralFriction=cfg.cylinder_friction, linearDamping=0.0,
                             angularDamping=0.0)  # fmt: skip
            self.cylinder_rest_z = 0.5 * h
            object_shape = ShapeSpec("cylinder", (r, 0.5 * h, 0.0), rigid=CYLINDER)
        else:
            geo = self.object_geometry = object_geometry(cfg.object)
            self.cylinder = _create_object(c, geo, cfg.cylinder_mass, (*cfg.cylinder_xy, geo.rest_height))
            c.changeDynamics(self.cylinder, -1, lateralFriction=cfg.cylinder_friction, linearDamping=0.0,
                             angularDamping=0.0)  # fmt: skip
            self.cylinder_rest_z = geo.rest_height
            object_shape = ShapeSpec(geo.tissue_kind, geo.tissue_params, rigid=CYLINDER, local_x=geo.tissue_local_x)

        # --- gripper, its finger cores at the cylinder's mid height plus the start height
        fh = cfg.finger_half_extents
        self.grasp_height = grasp_height(cfg)
        """Height of the finger centres when they grip the object [m]: the cylinder's middle
        (scene.config.grasp_height)."""
        palm_offset = Gripper.palm_offset_of(cfg)
        self.start_palm = np.array([cfg.gripper_xy[0], cfg.gripper_xy[1] + cfg.lateral_offset,
                                    self.grasp_height + palm_offset + cfg.start_height])  # fmt: skip
        self.gripper = Gripper(c, cfg, fingers, start_palm=self.start_palm, yaw=cfg.yaw)
        self.palm_offset = self.gripper.palm_offset
        """Height of the palm's centre above the finger centres [m]."""
        g = self.gripper.body
        site = FingerSite(client=c, gripper=g, cylinder=self.cylinder, ground=self.ground,
                          core_links=self.gripper.core_links, core_shapes=(SHAPES.index("left_core"),
                                                                           SHAPES.index("right_core")),
                          cylinder_shape=CYLINDER_SHAPE, gear_force=FINGER_GEAR_FORCE, gear_erp=FINGER_GEAR_ERP)  # fmt: skip
        tissue = fingers.mount(site)

        # --- what the tissue sees
        # Cores are infinitely heavy inside the solve in the thesis coupling; under the consistent one
        # they slide along their joints (World). The palm, held by the stiff arm, never moves in it.
        rigid = {
            "left_core": RigidRef(g, 0, gravity=False, in_solve=False, free_base=False, core=True),
            "right_core": RigidRef(g, 1, gravity=False, in_solve=False, free_base=False, core=True),
            "cylinder": RigidRef(self.cylinder, -1, gravity=True, in_solve=True, free_base=True),
            "palm": RigidRef(g, -1, gravity=False, in_solve=False, free_base=False),  # held by the arm
        }
        shapes = {
            "ground": ShapeSpec("plane", (0.0, 0.0, 0.0)),
            "cylinder": object_shape,
            "left_core": ShapeSpec("box", tuple(fh), rigid=LEFT),
            "right_core": ShapeSpec("box", tuple(fh), rigid=RIGHT),
            "palm": ShapeSpec("box", PALM_HALF_EXTENTS, rigid=PALM),
        }
        self.world = World(c, sim, [rigid[s] for s in SLOTS], [shapes[s] for s in SHAPES], tissue,
                           substeps=self.world_steps)
        fingers.connect(self.world)

    # --- stepping --------------------------------------------------------------------------------

    def step(self, control: GripperControl | None = None) -> None:
        """One physics step of the whole scene: ``control`` (or the last one) to the gripper, the
        finger kind's hook, the kind's extra pybullet substeps (no tissue there), then ``world.step()``
        (tissue, then pybullet)."""
        self.gripper.apply(self.gripper.control if control is None else control, self.world.position(PALM))
        self.fingers.before_step()
        for _ in range(self.bullet_steps - 1):
            self.client.stepSimulation()
        self.world.step()

    @property
    def steps(self) -> int:
        """Physics steps since the scene was built."""
        return self.world.step_count

    @property
    def control(self) -> GripperControl:
        """The control the gripper follows now."""
        return self.gripper.control

    # --- the state, by name ----------------------------------------------------------------------

    @property
    def palm_target(self) -> np.ndarray | None:
        """Where the arm takes the palm's centre (None while it follows a commanded velocity) [m]."""
        return self.gripper.control.palm_target

    @property
    def palm_setpoint(self) -> np.ndarray:
        """Where the arm has the palm's centre on its way (the constraint's pivot) [m]."""
        return self.gripper.setpoint

    def grip_point(self) -> np.ndarray:
        """Midpoint of the two finger cores [m] (the cores' centres of mass)."""
        x = self.world.colliders.rigid_x
        return 0.5 * (x[LEFT] + x[RIGHT])

    def grip_to_palm(self) -> np.ndarray:
        """The palm's centre minus the grip point [m]."""
        return self.world.colliders.rigid_x[PALM] - self.grip_point()

    def palm_state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The palm's (position, quaternion xyzw, linear velocity, angular velocity), read after
        the last step (views into the world's arrays: copy to keep)."""
        col = self.world.colliders
        return col.rigid_x[PALM], col.rigid_q[PALM], col.rigid_v[PALM], col.rigid_w[PALM]

    def cylinder_state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The cylinder's (position, quaternion xyzw, linear velocity, angular velocity), as
        :meth:`palm_state`."""
        col = self.world.colliders
        return col.rigid_x[CYLINDER], col.rigid_q[CYLINDER], col.rigid_v[CYLINDER], col.rigid_w[CYLINDER]

    def set_cylinder_mass(self, mass: float) -> None:
        """Make the cylinder ``mass`` [kg] from the next step on, its inertia scaled with it (a
        load that grows while it is held: accuracy.shear_under_load). pybullet and the tissue's
        view of it change together, so the tissue predicts the cylinder it will meet."""
        if not (math.isfinite(mass) and mass > 0.0):
            raise ValueError(f"cylinder mass must be a finite mass > 0 kg, got {mass!r}")
        info = self.client.getDynamicsInfo(self.cylinder, -1)
        scale = mass / info[0]
        inertia = [float(v) * scale for v in info[2]]
        self.client.changeDynamics(self.cylinder, -1, mass=float(mass), localInertiaDiagonal=inertia)
        self.world.set_mass_properties(CYLINDER)

    def palm_position(self) -> np.ndarray:
        return np.asarray(self.client.getBasePositionAndOrientation(self.gripper.body)[0])

    def cylinder_pose(self) -> tuple[np.ndarray, np.ndarray]:
        pos, orn = self.client.getBasePositionAndOrientation(self.cylinder)
        return np.asarray(pos), np.asarray(orn)

    def lift_height(self) -> float:
        """Height of the cylinder's centre above where it rests on the ground [m]."""
        return float(self.cylinder_pose()[0][2] - self.cylinder_rest_z)

    def finger_closing(self) -> np.ndarray:
        """Travel of each finger from fully open [m]."""
        return self.gripper.finger_closing()

    def cylinder_tilt(self) -> float:
        """Angle between the cylinder's axis and the vertical [rad]; for another object, the turn of
        its tilt axis (objects.ObjectGeometry.tilt_axis) from where it points at rest: a standing
        object's up direction from the vertical, a lying capsule's axis from the horizontal, 0 for
        a sphere."""
        x, y, z, w = self.cylinder_pose()[1]
        if self.object_geometry is None:
            axis_z = 1.0 - 2.0 * (x * x + y * y)
            return float(math.acos(max(-1.0, min(1.0, axis_z))))
        return self.object_tilt(np.array([x, y, z, w]))

    def object_tilt(self, q: np.ndarray) -> float:
        """The object's tilt at orientation ``q`` (x, y, z, w) [rad] (:meth:`cylinder_tilt`)."""
        g = self.object_geometry
        if g is None:
            return float(math.acos(max(-1.0, min(1.0, float(self.object_up(q)[2])))))
        if g.tilt_axis is None:
            return 0.0
        z = float((_matrix(q) @ np.array(g.tilt_axis))[2])
        if g.tilt_axis == g.up:
            return float(math.acos(max(-1.0, min(1.0, z))))
        return float(math.asin(min(1.0, abs(z))))

    def object_up(self, q: np.ndarray) -> np.ndarray:
        """The world direction of the object's up axis at orientation ``q`` (x, y, z, w): the
        cylinder's axis, or the body direction that points up when the object rests."""
        x, y, z, w = (float(v) for v in q)
        if self.object_geometry is None:
            return np.array([2.0 * (x * z + y * w), 2.0 * (y * z - x * w), 1.0 - 2.0 * (x * x + y * y)])
        return _matrix(q) @ np.array(self.object_geometry.up)

    @property
    def shape_description(self) -> tuple[np.ndarray, np.ndarray]:
        """(kind one-hot over objects.OBJECT_KINDS, half extents at rest (3,) [m]) of the object:
        what the observation's shape entries hold (copies)."""
        if self._shape_description is None:
            cfg = self.config
            shape = cfg.object_shape
            kind = np.zeros(len(OBJECT_KINDS))
            kind[OBJECT_KINDS.index(shape.kind)] = 1.0
            if self.object_geometry is None:
                extent = np.array([cfg.cylinder_radius, cfg.cylinder_radius, 0.5 * cfg.cylinder_height])
            else:
                g = self.object_geometry
                extent = np.array([0.5 * (g.half_width(1.0, 0.0) + g.half_width(-1.0, 0.0)),
                                   0.5 * (g.half_width(0.0, 1.0) + g.half_width(0.0, -1.0)), 0.5 * g.top])  # fmt: skip
            self._shape_description = (kind, extent)
        return self._shape_description[0].copy(), self._shape_description[1].copy()

    _shape_description: tuple[np.ndarray, np.ndarray] | None = None

    # --- what the fingers measure ----------------------------------------------------------------

    def finger_forces(self) -> np.ndarray:
        """Normal force each finger (left, right) pressed on the cylinder with in the last physics
        step [N], as its kind measures it (pybullet's contacts of its links, plus the tissue's or
        the pads' contacts)."""
        return self.fingers.contact_force()

    def penetration(self) -> tuple[float, float]:
        """(deepest overlap of a finger with the cylinder or the ground, deepest intrusion of a
        finger's soft part into its own core) now [m], the same measure for every finger kind."""
        return self.fingers.penetration()

    def diverged(self) -> bool:
        """True once the simulation has blown up (:meth:`divergence` says how)."""
        return self.divergence() is not None

    def divergence(self) -> str | None:
        """Why the simulation counts as blown up, or ``None``: a non-finite value, a body faster
        than 20 m/s or 500 rad/s, or what the finger kind says (a particle faster than 20 m/s or
        3 cm from its core, a finger segment turning faster than its limit)."""
        w = self.world
        if not w.is_finite():
            return "non-finite state"
        col = w.colliders
        v, om = float(np.abs(col.rigid_v).max()), float(np.abs(col.rigid_w).max())
        if v > MAX_RIGID_SPEED or om > MAX_RIGID_SPIN:
            return (f"a rigid body at {v:.1f} m/s, {om:.0f} rad/s (limits {MAX_RIGID_SPEED:g} m/s, "
                    f"{MAX_RIGID_SPIN:g} rad/s)")  # fmt: skip
        return self.fingers.divergence()

    def visuals(self) -> list[Visual]:
        """What a renderer draws: the cylinder and the palm, then what the finger kind shows."""
        cfg = self.config
        if self.object_geometry is None:
            cylinder = Visual("cylinder", np.asarray(CYLINDER_RGBA), body=self.cylinder, link=-1,
                              half_extents=(cfg.cylinder_radius, cfg.cylinder_radius, 0.5 * cfg.cylinder_height))  # fmt: skip
        else:
            g = self.object_geometry
            reach = float(np.linalg.norm(g.support_points, axis=1).max())
            reach = max(reach, g.top - g.rest_height, g.rest_height)
            cylinder = Visual("object", np.asarray(CYLINDER_RGBA), body=self.cylinder, link=-1,
                              half_extents=(reach, reach, reach), geometry=g)  # fmt: skip
        palm = Visual("box", np.asarray(PALM_RGBA), body=self.gripper.body, link=-1, half_extents=PALM_HALF_EXTENTS)
        return [cylinder, palm, *self.fingers.visuals()]

    def close(self) -> None:
        if self.client is not None:
            try:
                self.client.disconnect()
            except p.error:  # the server is gone already
                pass
            self.client = None


def _matrix(q) -> np.ndarray:
    """The rotation matrix of the quaternion ``q`` (x, y, z, w)."""
    x, y, z, w = (float(v) for v in q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])  # fmt: skip


def object_visual_shape(c: BulletClient, geo: ObjectGeometry, rgba) -> int:
    """pybullet's visual shape of the object ``geo`` in ``c`` (for the scene, and for a renderer's
    own copy), coloured ``rgba``."""
    k, t = geo.shape.kind, geo.tissue_params
    if geo.vertices is not None:
        return c.createVisualShape(p.GEOM_MESH, vertices=geo.vertices.tolist(), indices=geo.triangles.ravel().tolist(),
                                   rgbaColor=list(rgba))  # fmt: skip
    if k == "sphere":
        return c.createVisualShape(p.GEOM_SPHERE, radius=t[0], rgbaColor=list(rgba))
    if k == "box":
        return c.createVisualShape(p.GEOM_BOX, halfExtents=list(t), rgbaColor=list(rgba))
    if k == "capsule":
        return c.createVisualShape(p.GEOM_CAPSULE, radius=t[0], length=2.0 * t[1], rgbaColor=list(rgba))
    raise ValueError(f"no pybullet shape for a {k}")


def _create_object(c: BulletClient, geo: ObjectGeometry, mass: float, position: tuple[float, float, float]) -> int:
    """A free body of ``geo``'s shape and ``mass`` [kg] resting at ``position`` (its centre of mass)
    [m], its frame the principal one (objects.py) and its inertia the exact one: pybullet's own
    for a mesh comes from its bounding box."""
    k, t = geo.shape.kind, geo.tissue_params
    if geo.vertices is not None:
        col = c.createCollisionShape(p.GEOM_MESH, vertices=geo.vertices.tolist())
    elif k == "sphere":
        col = c.createCollisionShape(p.GEOM_SPHERE, radius=t[0])
    elif k == "box":
        col = c.createCollisionShape(p.GEOM_BOX, halfExtents=list(t))
    elif k == "capsule":
        col = c.createCollisionShape(p.GEOM_CAPSULE, radius=t[0], height=2.0 * t[1])
    else:
        raise ValueError(f"no pybullet shape for a {k}")
    vis = object_visual_shape(c, geo, CYLINDER_RGBA)
    body = c.createMultiBody(baseMass=mass, baseCollisionShapeIndex=col, baseVisualShapeIndex=vis,
                             basePosition=list(position), baseOrientation=list(geo.rest_q))  # fmt: skip
    inertia = [mass * v for v in geo.inertia_per_mass]
    # a mesh's rounding margin (1 mm by default) would stand the object on a cushion the tissue
    # does not see
    c.changeDynamics(body, -1, localInertiaDiagonal=inertia)
    if geo.vertices is not None:
        c.changeDynamics(body, -1, collisionMargin=0.0)
    return body


__all__ = ["CYLINDER_SHAPE", "SHAPES", "SLOTS", "GraspScene", "object_visual_shape"]
