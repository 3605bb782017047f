"""Views of a grasp scene that show the tissue, not only the cores. Read-only on the simulation.

``rgb_array``: a separate pybullet server (DIRECT) holds visual-only copies of the ground, cylinder,
palm, finger cores and one ellipsoid per tissue particle; each frame copies the poses over and draws
with pybullet's CPU renderer, so rendering never touches the physics server.
``human``: the physics server is the pybullet GUI; visual-only particle bodies (no collision shape,
no mass, so they take no part in the dynamics) are added to it and moved each frame.
"""

from __future__ import annotations

import math

import numpy as np
import pybullet as p

from .scene import PALM_HALF_EXTENTS, GraspScene
from .sim.bullet import connect

_TISSUE_RGBA = (0.95, 0.55, 0.6, 1.0)
_ATTACHED_RGBA = (0.75, 0.35, 0.45, 1.0)


def ellipsoid_mesh(radii: tuple[float, float, float], *, rings: int = 6, segments: int = 10):
    """(vertices, indices, normals) of a UV ellipsoid with semi-axes ``radii`` [m]: few triangles,
    since a scene has hundreds of particles and the renderer runs on the CPU."""
    a, b, c = radii
    verts, normals = [], []
    for i in range(rings + 1):
        th = math.pi * i / rings
        for j in range(segments):
            ph = 2.0 * math.pi * j / segments
            u = (math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th))
            verts.append([a * u[0], b * u[1], c * u[2]])
            n = np.array([u[0] / a, u[1] / b, u[2] / c])
            normals.append((n / np.linalg.norm(n)).tolist())
    idx = []
    for i in range(rings):
        for j in range(segments):
            k0 = i * segments + j
            k1 = i * segments + (j + 1) % segments
            k2, k3 = k0 + segments, k1 + segments
            idx += [k0, k2, k1, k1, k2, k3]
    return verts, idx, normals


class SceneRenderer:
    """Draws a :class:`GraspScene`; ``render`` returns an (H, W, 3) uint8 image (None in human mode)."""

    def __init__(self, width: int, height: int, *, human: bool = False) -> None:
        self.width = int(width)
        self.height = int(height)
        self.human = human
        self._client = None  # the viewer server (rgb_array) or the scene's GUI server (human)
        self._scene: GraspScene | None = None
        self._particles: list[int] = []
        self._mirror: dict[str, int] = {}

    def invalidate(self) -> None:
        """The scene was rebuilt: build the copies again on the next frame."""
        self._scene = None

    def render(self, scene: GraspScene) -> np.ndarray | None:
        if self._scene is not scene:
            self._build(scene)
        cid = self._client._client
        sc = scene.client
        if not self.human:
            for name, (body, link) in (("cylinder", (scene.cylinder, -1)), ("palm", (scene.gripper, -1)),
                                       ("left", (scene.gripper, 0)), ("right", (scene.gripper, 1))):  # fmt: skip
                if link < 0:
                    pos, orn = sc.getBasePositionAndOrientation(body)
                else:
                    st = sc.getLinkState(body, link)
                    pos, orn = st[4], st[5]  # the link (visual) frame
                p.resetBasePositionAndOrientation(self._mirror[name], pos, orn, physicsClientId=cid)
        state = scene.world.state
        if state is not None:
            x, q = state.particle_x, state.particle_q
            for k, body in enumerate(self._particles):
                p.resetBasePositionAndOrientation(body, x[k].tolist(), q[k].tolist(), physicsClientId=cid)
        if self.human:
            return None
        # A fixed camera on the cylinder's start, so a video shows the lift as motion.
        cx, cy = scene.config.cylinder_xy
        view = p.computeViewMatrixFromYawPitchRoll(cameraTargetPosition=[cx, cy, 0.08], distance=0.36,
                                                   yaw=35.0, pitch=-25.0, roll=0.0, upAxisIndex=2,
                                                   physicsClientId=cid)  # fmt: skip
        proj = p.computeProjectionMatrixFOV(fov=50.0, aspect=self.width / self.height, nearVal=0.01, farVal=3.0,
                                            physicsClientId=cid)  # fmt: skip
        img = p.getCameraImage(self.width, self.height, view, proj, renderer=p.ER_TINY_RENDERER,
                               lightDirection=[0.4, -0.6, 1.0], physicsClientId=cid)  # fmt: skip
        rgba = np.asarray(img[2], dtype=np.uint8).reshape(self.height, self.width, 4)
        return np.ascontiguousarray(rgba[:, :, :3])

    def _build(self, scene: GraspScene) -> None:
        if self.human:
            self._client = scene.client  # resetSimulation in a rebuild already removed old copies
            self._client.configureDebugVisualizer(p.COV_ENABLE_GUI, 0)
            self._client.resetDebugVisualizerCamera(0.34, 35.0, -25.0, [0.0, 0.0, 0.07])
        else:
            if self._client is None:
                self._client = connect()
            self._client.resetSimulation()
            self._mirror_rigid(scene)
        self._particles = []
        model = scene.world.model
        if self.human:
            # The GUI redraws after every body it is sent; hundreds of particle bodies took ~20 s
            # that way. Pausing its rendering while they are created is pybullet's usual remedy.
            self._client.configureDebugVisualizer(p.COV_ENABLE_RENDERING, 0)
        if model is not None:
            c = self._client
            radii = np.round(model.particle_radii, 9)
            ids = np.empty(model.particle_count, dtype=np.int64)
            # One visual shape per distinct (radii, attached) and one batched createMultiBody each.
            keys = np.concatenate([radii, model.particle_attached[:, None].astype(np.float64)], axis=1)
            uniq, inverse = np.unique(keys, axis=0, return_inverse=True)
            for u, key in enumerate(uniq):
                members = np.flatnonzero(inverse.ravel() == u)
                verts, idx, normals = ellipsoid_mesh(tuple(key[:3]))
                vis = c.createVisualShape(p.GEOM_MESH, vertices=verts, indices=idx, normals=normals,
                                          rgbaColor=_ATTACHED_RGBA if key[3] else _TISSUE_RGBA)  # fmt: skip
                pos = scene.world.state.particle_x[members].tolist()
                bodies = c.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=-1, baseVisualShapeIndex=vis,
                                           batchPositions=pos)  # fmt: skip
                bodies = [bodies] if isinstance(bodies, int) else list(bodies)
                ids[members] = bodies
            self._particles = ids.tolist()
        if self.human:
            self._client.configureDebugVisualizer(p.COV_ENABLE_RENDERING, 1)
        self._scene = scene

    def _mirror_rigid(self, scene: GraspScene) -> None:
        c = self._client
        cfg = scene.config
        ground = c.createVisualShape(p.GEOM_BOX, halfExtents=[0.3, 0.3, 0.001], rgbaColor=[0.82, 0.84, 0.86, 1])
        c.createMultiBody(baseMass=0.0, baseVisualShapeIndex=ground, basePosition=[0.0, 0.0, -0.001])
        cyl = c.createVisualShape(p.GEOM_CYLINDER, radius=cfg.cylinder_radius, length=cfg.cylinder_height,
                                  rgbaColor=[0.9, 0.6, 0.2, 1.0])  # fmt: skip
        palm = c.createVisualShape(p.GEOM_BOX, halfExtents=PALM_HALF_EXTENTS, rgbaColor=[0.4, 0.4, 0.45, 1])
        finger = c.createVisualShape(p.GEOM_BOX, halfExtents=cfg.finger_half_extents, rgbaColor=[0.3, 0.3, 0.8, 1])
        self._mirror = {
            "cylinder": c.createMultiBody(baseMass=0.0, baseVisualShapeIndex=cyl),
            "palm": c.createMultiBody(baseMass=0.0, baseVisualShapeIndex=palm),
            "left": c.createMultiBody(baseMass=0.0, baseVisualShapeIndex=finger),
            "right": c.createMultiBody(baseMass=0.0, baseVisualShapeIndex=finger),
        }

    def close(self) -> None:
        if self._client is not None and not self.human:
            try:
                self._client.disconnect()
            except p.error:
                pass
        self._client = None
        self._scene = None
