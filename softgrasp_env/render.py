"""Views of a grasp scene that show every finger kind, not only its cores. Read-only on the
simulation: what to draw comes from ``GraspScene.visuals()`` (the scene's cylinder and palm, then
the finger kind's own: cores, tissue particles, segments, FEM pad nodes; softgrasp_env/fingers/).

``rgb_array``: a separate pybullet server (DIRECT) holds visual-only copies of everything; each
frame copies the poses over and draws with pybullet's CPU renderer, so rendering never touches the
physics server. ``human``: the physics server is the pybullet GUI, which draws its own bodies;
only what is not a pybullet body there (the tissue particles) is added as visual-only bodies (no
collision shape, no mass: they take no part in the dynamics) and moved each frame.
"""

from __future__ import annotations

import math

import numpy as np
import pybullet as p

from .fingers import Visual
from .scene import GraspScene
from .sim.bullet import connect

GROUND_RGBA = (0.82, 0.84, 0.86, 1.0)
GROUND_HALF_EXTENTS = (0.3, 0.3, 0.001)


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
        self._rigid: list[tuple[Visual, int]] = []  # (what, its mirror body)
        self._points: list[tuple[Visual, list[int]]] = []  # (what, a mirror body per point)

    @property
    def particle_bodies(self) -> list[int]:
        """The bodies drawn for the tissue particles (and pad nodes), in the scene's order."""
        return [b for _, bodies in self._points for b in bodies]

    def invalidate(self) -> None:
        """The scene was rebuilt: build the copies again on the next frame."""
        self._scene = None

    def render(self, scene: GraspScene) -> np.ndarray | None:
        if self._scene is not scene:
            self._build(scene)
        cid = self._client._client
        sc = scene.client
        for v, mirror in self._rigid:
            if v.link < 0:
                pos, orn = sc.getBasePositionAndOrientation(v.body)
            else:
                pos, orn = sc.getLinkState(v.body, v.link)[4:6]  # the link (visual) frame
            p.resetBasePositionAndOrientation(mirror, pos, orn, physicsClientId=cid)
        for v, bodies in self._points:
            x = v.positions()
            q = v.orientations() if v.orientations is not None else None
            for k, body in enumerate(bodies):
                p.resetBasePositionAndOrientation(body, x[k].tolist(), (0.0, 0.0, 0.0, 1.0) if q is None else q[k].tolist(),
                                                  physicsClientId=cid)  # fmt: skip
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
        visuals = scene.visuals()
        if self.human:
            self._client = c = scene.client  # resetSimulation in a rebuild already removed old copies
            c.configureDebugVisualizer(p.COV_ENABLE_GUI, 0)
            c.resetDebugVisualizerCamera(0.34, 35.0, -25.0, [0.0, 0.0, 0.07])
            # The GUI redraws after every body it is sent; hundreds of particle bodies took ~20 s
            # that way. Pausing its rendering while they are created is pybullet's usual remedy.
            c.configureDebugVisualizer(p.COV_ENABLE_RENDERING, 0)
            visuals = [v for v in visuals if not v.in_scene]  # the GUI draws the scene's own bodies
        else:
            if self._client is None:
                self._client = connect()
            c = self._client
            c.resetSimulation()
            ground = c.createVisualShape(p.GEOM_BOX, halfExtents=list(GROUND_HALF_EXTENTS), rgbaColor=list(GROUND_RGBA))
            c.createMultiBody(baseMass=0.0, baseVisualShapeIndex=ground, basePosition=[0.0, 0.0, -GROUND_HALF_EXTENTS[2]])
        self._rigid, self._points = [], []
        for v in visuals:
            if v.kind == "points":
                self._points.append((v, self._point_bodies(c, v)))
            else:
                if v.kind == "cylinder":
                    shape = c.createVisualShape(p.GEOM_CYLINDER, radius=v.half_extents[0], length=2.0 * v.half_extents[2],
                                                rgbaColor=list(v.rgba))  # fmt: skip
                else:
                    shape = c.createVisualShape(p.GEOM_BOX, halfExtents=list(v.half_extents), rgbaColor=list(v.rgba))
                self._rigid.append((v, c.createMultiBody(baseMass=0.0, baseVisualShapeIndex=shape)))
        if self.human:
            c.configureDebugVisualizer(p.COV_ENABLE_RENDERING, 1)
        self._scene = scene

    @staticmethod
    def _point_bodies(c, v: Visual) -> list[int]:
        """A visual-only body per point: one visual shape per distinct (radii, colour), and one
        batched createMultiBody each."""
        n = len(v.radii)
        ids = np.empty(n, dtype=np.int64)
        keys = np.concatenate([np.round(v.radii, 9), np.asarray(v.rgba, dtype=np.float64).reshape(n, 4)], axis=1)
        uniq, inverse = np.unique(keys, axis=0, return_inverse=True)
        x = v.positions()
        for u, key in enumerate(uniq):
            members = np.flatnonzero(inverse.ravel() == u)
            verts, idx, normals = ellipsoid_mesh(tuple(key[:3]))
            shape = c.createVisualShape(p.GEOM_MESH, vertices=verts, indices=idx, normals=normals, rgbaColor=key[3:].tolist())
            bodies = c.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=-1, baseVisualShapeIndex=shape,
                                       batchPositions=x[members].tolist())  # fmt: skip
            ids[members] = [bodies] if isinstance(bodies, int) else list(bodies)
        return ids.tolist()

    def close(self) -> None:
        if self._client is not None and not self.human:
            try:
                self._client.disconnect()
            except p.error:
                pass
        self._client = None
        self._scene = None
