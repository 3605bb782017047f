"""Views of a grasp scene that show every finger kind, not only its cores. Read-only on the
simulation: what to draw comes from ``GraspScene.visuals()`` (the scene's cylinder and palm, then
the finger kind's own: cores, tissue particles, segments, FEM pad nodes; softgrasp_env/fingers/).

``rgb_array``: a separate pybullet server (DIRECT) holds visual-only copies of everything; each
frame copies the poses over and draws with pybullet's CPU renderer, so rendering never touches the
physics server. ``human``: the physics server is the pybullet GUI, which draws its own bodies;
only what is not a pybullet body there (the tissue particles) is added as visual-only bodies (no
collision shape, no mass: they take no part in the dynamics) and moved each frame.

The camera (:class:`Camera`, the env's ``render_camera`` / ``camera_*`` arguments): ``"follow"``
(default) frames the gripper and the cylinder wherever they are, every frame: it aims at the
middle of the box around every rigid part drawn (palm, cores or segments, cylinder) and backs off
until that box fits the view; ``"fixed"`` looks at the cylinder's start from a fixed distance, so
a video shows the lift as motion. ``camera_target`` / ``camera_distance`` fix either one. The
ground is a checkerboard of 5 cm squares, so that motion shows when the camera follows it; the
TinyRenderer draws shadows from one directional light.
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pybullet as p

from .fingers import Visual
from .scene import GraspScene
from .scene.scene import object_visual_shape
from .sim.bullet import connect

GROUND_RGBA = (0.82, 0.84, 0.86, 1.0)
GROUND_HALF = 0.5
"""The drawn ground is a square of twice this side [m]: the TinyRenderer's time goes with the
pixels drawn, so a ground out to the horizon (3 m) took 67 ms a frame at 480 x 360, this one
37 ms (the white beyond it is free), the 0.6 m one before 28 ms."""
GROUND_SQUARE = 0.05
"""Side of the ground's checkerboard squares [m]."""
FOV = 50.0
"""Vertical field of view [deg]."""
LIGHT_DIRECTION = (0.5, -0.35, 1.0)
"""Towards the light, world frame: from above and to the side, so the shadows fall beside the
bodies where the camera sees them."""
FIT_MARGIN = 1.25
"""Follow mode backs off until the box around the bodies spans 1 / FIT_MARGIN of the view."""
FIXED_TARGET_HEIGHT, FIXED_DISTANCE = 0.12, 0.55
"""The fixed camera's aim above the cylinder's start and its distance [m]: the whole start (the
palm up to 25 cm high, up to 21 cm from the cylinder) is in the picture."""
MIN_DISTANCE = 0.2
"""Follow mode comes no closer than this [m]: a lone cylinder would fill the frame."""
CAMERA_MODES = ("follow", "fixed")


@dataclass(frozen=True)
class Camera:
    """Where an ``rgb_array`` frame is seen from (and the GUI's view in ``human`` mode).

    ``mode``: ``"follow"`` frames the gripper and the cylinder every frame; ``"fixed"`` looks at
    the cylinder's start. ``distance`` [m] (None: follow fits the bodies, fixed uses 0.55),
    ``yaw`` and ``pitch`` [deg] (pybullet's: yaw about z, pitch negative looking down), ``target``
    (x, y, z) [m] (None: follow aims at the bodies, fixed at the cylinder's start 12 cm up)."""

    mode: str = "follow"
    distance: float | None = None
    yaw: float = 35.0
    pitch: float = -25.0
    target: tuple[float, float, float] | None = None

    def view(self, scene: GraspScene, corners: np.ndarray, aspect: float):
        """(target, distance) for this frame; ``corners`` (N, 3) are the corners of every rigid
        part drawn (the boxes of the palm, cores, segments and the cylinder's)."""
        if self.mode == "fixed":
            cx, cy = scene.config.cylinder_xy
            target = np.array([cx, cy, FIXED_TARGET_HEIGHT]) if self.target is None else np.asarray(self.target, float)
            return target, FIXED_DISTANCE if self.distance is None else float(self.distance)
        corners = np.asarray(corners, dtype=float).copy()
        corners[:, 2] = np.maximum(corners[:, 2], 0.0)  # the ground is the floor of the picture
        lo, hi = corners.min(axis=0), corners.max(axis=0)
        target = 0.5 * (lo + hi) if self.target is None else np.asarray(self.target, dtype=float)
        if self.distance is not None:
            return target, float(self.distance)
        return target, max(MIN_DISTANCE, self.fit(target, corners, aspect))

    def fit(self, target: np.ndarray, points: np.ndarray, aspect: float) -> float:
        """The distance from ``target`` at which every one of ``points`` (N, 3) is in the view, with
        FIT_MARGIN to spare. A point at camera coordinates (x, y, z) seen from distance 1 is seen
        from d at depth d - 1 - z (the camera backs off along its axis, OpenGL's -z): it is in the
        picture if |x| <= depth tan(horizontal half-fov) and |y| <= depth tan(vertical half-fov)."""
        view = np.asarray(p.computeViewMatrixFromYawPitchRoll(target.tolist(), 1.0, self.yaw, self.pitch, 0.0, 2))
        view = view.reshape(4, 4).T  # pybullet gives it column by column
        cam = np.concatenate([points, np.ones((len(points), 1))], axis=1) @ view.T
        tan_v = math.tan(math.radians(FOV / 2.0))
        tan_h = tan_v * aspect
        need = np.maximum(FIT_MARGIN * np.abs(cam[:, 0]) / tan_h, FIT_MARGIN * np.abs(cam[:, 1]) / tan_v) + cam[:, 2] + 1.0
        return float(need.max())


def _checker_texture(squares: int) -> str:
    """A ``squares`` x ``squares`` checkerboard as an uncompressed TGA file (pybullet's loader reads
    it; no imaging library needed), written once per process into a temporary folder."""
    global _TEXTURE
    if _TEXTURE is None or not Path(_TEXTURE).exists():
        light, dark = (np.array(GROUND_RGBA[:3]) * 255).astype(np.uint8), (np.array(GROUND_RGBA[:3]) * 215).astype(np.uint8)
        px = 8  # pixels per square
        ij = np.add.outer(np.arange(squares * px) // px, np.arange(squares * px) // px) % 2
        img = np.where(ij[..., None] == 0, light, dark)[..., ::-1]  # TGA stores BGR
        n = squares * px
        header = bytes([0, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, n & 255, n >> 8, n & 255, n >> 8, 24, 0])
        folder = Path(tempfile.mkdtemp(prefix="softgrasp-render-"))
        path = folder / "ground.tga"
        path.write_bytes(header + np.ascontiguousarray(img).tobytes())
        _TEXTURE = str(path)
    return _TEXTURE


_TEXTURE: str | None = None
_UNIT_CORNERS = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])


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

    def __init__(self, width: int, height: int, *, human: bool = False, camera: Camera | None = None) -> None:
        self.width = int(width)
        self.height = int(height)
        self.human = human
        self.camera = camera if camera is not None else Camera()
        self._client = None  # the viewer server (rgb_array) or the scene's GUI server (human)
        self._scene: GraspScene | None = None
        self._rigid: list[tuple[Visual, int | None]] = []  # (what, its mirror body; None: the GUI's own)
        self._scene_changed = True  # the GUI camera is set on the first frame of a scene
        self.last_segmentation: np.ndarray | None = None
        """The last frame's (H, W) body ids of the viewer's copies (-1: background), from the same
        render; :attr:`mirror_bodies` says which copy is which."""
        self._points: list[tuple[Visual, list[int]]] = []  # (what, a mirror body per point)

    @property
    def mirror_bodies(self) -> list[tuple[Visual, int | None]]:
        """(what, its copy's body id in the viewer) for every rigid part drawn."""
        return list(self._rigid)

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
        corners = []  # of every rigid part, for the follow camera
        for v, mirror in self._rigid:
            if v.link < 0:
                pos, orn = sc.getBasePositionAndOrientation(v.body)
            else:
                pos, orn = sc.getLinkState(v.body, v.link)[4:6]  # the link (visual) frame
            rot = np.asarray(p.getMatrixFromQuaternion(orn)).reshape(3, 3)
            corners.append(np.asarray(pos) + (_UNIT_CORNERS * np.asarray(v.half_extents)) @ rot.T)
            if mirror is not None:
                p.resetBasePositionAndOrientation(mirror, pos, orn, physicsClientId=cid)
        for v, bodies in self._points:
            x = v.positions()
            corners.append(x + np.abs(v.radii).max(axis=1, keepdims=True) * np.sign(x - x.mean(axis=0)))
            q = v.orientations() if v.orientations is not None else None
            for k, body in enumerate(bodies):
                p.resetBasePositionAndOrientation(body, x[k].tolist(), (0.0, 0.0, 0.0, 1.0) if q is None else q[k].tolist(),
                                                  physicsClientId=cid)  # fmt: skip
        cam = self.camera
        target, distance = cam.view(scene, np.concatenate(corners), self.width / self.height)
        if self.human:
            if cam.mode == "follow" or self._scene_changed:
                self._client.resetDebugVisualizerCamera(distance, cam.yaw, cam.pitch, target.tolist())
                self._scene_changed = False
            return None
        view = p.computeViewMatrixFromYawPitchRoll(cameraTargetPosition=target.tolist(), distance=distance,
                                                   yaw=cam.yaw, pitch=cam.pitch, roll=0.0, upAxisIndex=2,
                                                   physicsClientId=cid)  # fmt: skip
        proj = p.computeProjectionMatrixFOV(fov=FOV, aspect=self.width / self.height, nearVal=0.01, farVal=5.0,
                                            physicsClientId=cid)  # fmt: skip
        # One directional light with shadows (the TinyRenderer's shadow map); ambient light keeps
        # the shaded sides readable, little specular (the bodies are matte).
        img = p.getCameraImage(self.width, self.height, view, proj, renderer=p.ER_TINY_RENDERER,
                               lightDirection=list(LIGHT_DIRECTION), lightColor=[1.0, 1.0, 1.0],
                               lightAmbientCoeff=0.55, lightDiffuseCoeff=0.5, lightSpecularCoeff=0.05,
                               shadow=1, physicsClientId=cid)  # fmt: skip
        rgba = np.asarray(img[2], dtype=np.uint8).reshape(self.height, self.width, 4)
        self.last_segmentation = np.asarray(img[4], dtype=np.int32).reshape(self.height, self.width)
        return np.ascontiguousarray(rgba[:, :, :3])

    def _build(self, scene: GraspScene) -> None:
        visuals = scene.visuals()
        self._scene_changed = True
        if self.human:
            self._client = c = scene.client  # resetSimulation in a rebuild already removed old copies
            c.configureDebugVisualizer(p.COV_ENABLE_GUI, 0)
            # The GUI redraws after every body it is sent; hundreds of particle bodies took ~20 s
            # that way. Pausing its rendering while they are created is pybullet's usual remedy.
            c.configureDebugVisualizer(p.COV_ENABLE_RENDERING, 0)
        else:
            if self._client is None:
                self._client = connect()
            c = self._client
            c.resetSimulation()
            # one textured quad (a box's faces map the texture in ways of their own): the squares
            # come out GROUND_SQUARE wide
            h = GROUND_HALF
            ground = c.createVisualShape(p.GEOM_MESH, vertices=[[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]],
                                         indices=[0, 1, 2, 0, 2, 3], uvs=[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
                                         normals=[[0.0, 0.0, 1.0]] * 4, rgbaColor=[1.0, 1.0, 1.0, 1.0])  # fmt: skip
            body = c.createMultiBody(baseMass=0.0, baseVisualShapeIndex=ground)
            squares = round(2.0 * h / GROUND_SQUARE)
            c.changeVisualShape(body, -1, textureUniqueId=c.loadTexture(_checker_texture(squares)))
        self._rigid, self._points = [], []
        for v in visuals:
            if v.kind == "points":
                if not (self.human and v.in_scene):
                    self._points.append((v, self._point_bodies(c, v)))
            elif self.human and v.in_scene:
                self._rigid.append((v, None))  # the GUI draws it; the follow camera still frames it
            else:
                if v.kind == "object":
                    shape = object_visual_shape(c, v.geometry, v.rgba)
                elif v.kind == "cylinder":
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
