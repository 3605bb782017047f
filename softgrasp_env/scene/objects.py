"""The objects a scene can grasp: their shapes, mass properties and resting poses, built the same
way for pybullet and for the tissue.

Every object is a rigid body whose frame is its principal frame (origin at the centre of mass,
axes along the principal axes of inertia), because that is the frame pybullet reports a base in
and the tissue's rigid slots use. A shape's geometry is described in that frame; the object stands
on the ground in its resting orientation :attr:`ObjectGeometry.rest_q` with its centre of mass
:attr:`ObjectGeometry.rest_height` above the ground.

Kinds and their ``size`` (SI, metres):

==========  ======================================  ==============================================
kind        size                                    rests
==========  ======================================  ==============================================
cylinder    (radius, height)                        upright on a flat end
sphere      (radius,)                               on the ground
box         (x, y, z) full edge lengths             upright, edges along the world axes
capsule     (radius, length of the straight part)   lying, its axis along y (the fingers' faces)
cone        (bottom radius, top radius, height)     upright on its bottom face (a frustum)
elliptic    (semi-axis x, semi-axis y, height)      upright (an elliptic cylinder)
hull        (scale,) of a shipped convex mesh       on the mesh's flat base
==========  ======================================  ==============================================

The tissue collides with each exactly (softgrasp_env.tissue.collision, a hull by its face planes);
pybullet with its primitives, or, for the cone, the elliptic cylinder and the hulls, a convex mesh
(the smooth shapes as 64-sided polygons, inscribed, which sag at most r (1 - cos(pi / 64)) =
0.12 % of the radius inside the tissue's shape) with no collision margin.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace
from importlib import resources

import numpy as np

OBJECT_KINDS = ("cylinder", "sphere", "box", "capsule", "cone", "elliptic", "hull")
"""The shape kinds an object can have."""

SIZE_ARITY = {"cylinder": 2, "sphere": 1, "box": 3, "capsule": 2, "cone": 3, "elliptic": 3, "hull": 1}
SIZE_NAMES = {
    "cylinder": ("radius", "height"),
    "sphere": ("radius",),
    "box": ("x", "y", "z"),
    "capsule": ("radius", "length"),
    "cone": ("bottom radius", "top radius", "height"),
    "elliptic": ("semi-axis x", "semi-axis y", "height"),
    "hull": ("scale",),
}

MIN_SIZE = 0.005
"""The smallest dimension an object may have [m], as the cylinder's radius (a hull's scale has no unit)."""
MAX_SIZE = 0.5
"""The largest dimension an object may have [m]."""
POLYGON_SIDES = 64
"""Sides of the convex polygon pybullet's mesh gives a round cross-section (cone, elliptic)."""

MESHES = ("pebble-0", "pebble-1", "pebble-2")
"""The shipped convex meshes (``kind="hull"``): irregular convex solids on a flat base, made by
the repository's ``scripts/make_objects.py`` (seeded) and shipped as Wavefront OBJ files in
``softgrasp_env/scene/meshes/``. Metres, z up, the base at z = 0."""


@dataclass(frozen=True)
class ObjectShape:
    """What is grasped: a shape ``kind`` (:data:`OBJECT_KINDS`) of ``size`` (its table in the module
    docstring) and, for ``kind="hull"``, the shipped ``mesh`` it scales (:data:`MESHES`). The mass and
    friction are the scene's (``SceneConfig.cylinder_mass``, ``cylinder_friction``)."""

    kind: str
    size: tuple[float, ...]
    mesh: str | None = None
    label: str | None = field(default=None, compare=False)
    """What :attr:`name` calls it (a preset's name, kept by :meth:`scaled`); no part of the shape:
    shapes that differ only in it are equal."""

    def __post_init__(self) -> None:
        if self.kind not in OBJECT_KINDS:
            raise ValueError(f"ObjectShape.kind must be one of {OBJECT_KINDS}, got {self.kind!r}")
        size = tuple(self.size) if isinstance(self.size, (tuple, list)) else (self.size,)
        if len(size) != SIZE_ARITY[self.kind]:
            raise ValueError(f"ObjectShape: a {self.kind} takes size=({', '.join(SIZE_NAMES[self.kind])}), "
                             f"{SIZE_ARITY[self.kind]} value(s), got {self.size!r}")  # fmt: skip
        for name, v in zip(SIZE_NAMES[self.kind], size, strict=True):
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
                raise ValueError(f"ObjectShape: the {self.kind}'s {name} must be a finite number, got {v!r}")
        object.__setattr__(self, "size", tuple(float(v) for v in size))
        if self.label is not None and (not isinstance(self.label, str) or not self.label):
            raise ValueError(f"ObjectShape.label must be a non-empty string or None, got {self.label!r}")
        if self.kind == "hull":
            if self.mesh not in MESHES:
                raise ValueError(f"ObjectShape: a hull needs mesh= one of {MESHES}, got {self.mesh!r}")
            if not 0.2 <= self.size[0] <= 3.0:
                raise ValueError(f"ObjectShape: a hull's scale must be in [0.2, 3], got {self.size[0]!r}")
        elif self.mesh is not None:
            raise ValueError(f"ObjectShape: mesh= is for kind='hull' only, got mesh={self.mesh!r} for a {self.kind}")
        if self.kind == "cone":
            r0, r1, _ = self.size
            if r0 < MIN_SIZE or r1 < 0.0:
                raise ValueError(f"ObjectShape: a cone's bottom radius must be at least {MIN_SIZE} m and its top "
                                 f"radius at least 0, got {r0!r}, {r1!r}")  # fmt: skip
            if r1 > r0:
                raise ValueError(f"ObjectShape: a cone stands on its wider face: the top radius ({r1:g} m) must not "
                                 f"exceed the bottom radius ({r0:g} m)")  # fmt: skip
            dims = (r0, self.size[2])
        else:
            dims = self.size if self.kind != "hull" else ()
        for name, v in zip(SIZE_NAMES[self.kind], dims, strict=False):
            if self.kind == "cone" and name == "top radius":
                continue
            if not MIN_SIZE <= v <= MAX_SIZE:
                raise ValueError(f"ObjectShape: the {self.kind}'s {name} must be in [{MIN_SIZE}, {MAX_SIZE}] m, "
                                 f"got {v!r}")  # fmt: skip

    @property
    def name(self) -> str:
        """A short label: :attr:`label` if given (a preset's name), else the kind, or the mesh's name
        for a hull."""
        return self.label or (self.mesh if self.kind == "hull" else self.kind)

    def scaled(self, factor: float) -> ObjectShape:
        """The same shape ``factor`` times as large in every dimension (a hull's scale times
        ``factor``); a size it takes out of range is the error :class:`ObjectShape` raises, naming it."""
        if not isinstance(factor, (int, float)) or isinstance(factor, bool) or not math.isfinite(factor) \
                or factor <= 0.0:  # fmt: skip
            raise ValueError(f"ObjectShape.scaled: the factor must be a finite number > 0, got {factor!r}")
        return ObjectShape(self.kind, tuple(float(factor) * v for v in self.size), mesh=self.mesh, label=self.label)


PRESETS: dict[str, ObjectShape] = {
    "cylinder": ObjectShape("cylinder", (0.03, 0.10)),
    "rod": ObjectShape("cylinder", (0.006, 0.10)),
    "sphere": ObjectShape("sphere", (0.03,)),
    "cube": ObjectShape("box", (0.05, 0.05, 0.05)),
    "slab": ObjectShape("box", (0.025, 0.08, 0.06)),
    "capsule": ObjectShape("capsule", (0.02, 0.04)),
    "cone": ObjectShape("cone", (0.035, 0.02, 0.09)),
    "elliptic": ObjectShape("elliptic", (0.035, 0.02, 0.09)),
    **{m: ObjectShape("hull", (1.0,), mesh=m) for m in MESHES},
}
PRESETS = {name: replace(shape, label=name) for name, shape in PRESETS.items()}
"""The named objects (``object="sphere"``): the default cylinder; a rod (12 mm across: narrower than
a default tissue particle, and still 5 mm in radius at 0.85 of its size); a 5 cm cube; a slab gripped across its 2.5 cm; a capsule lying along the
fingers' faces; a frustum tapering from 35 to 20 mm; an elliptic cylinder with its long axis
along the closing direction; the three shipped pebbles."""


def object_shape(value: str | ObjectShape) -> ObjectShape:
    """``value`` as an :class:`ObjectShape`: a preset's name (:data:`PRESETS`) or the shape itself."""
    if isinstance(value, ObjectShape):
        return value
    if isinstance(value, str):
        if value not in PRESETS:
            raise ValueError(f"object must be one of {tuple(PRESETS)} or an ObjectShape, got {value!r}")
        return PRESETS[value]
    raise TypeError(f"object must be a name ({', '.join(PRESETS)}) or an ObjectShape, got {type(value).__name__}")


# --- meshes -----------------------------------------------------------------------------------------


@functools.lru_cache(maxsize=None)
def load_mesh(name: str) -> tuple[np.ndarray, np.ndarray]:
    """A shipped mesh's (vertices (V, 3) [m], triangles (F, 3) int, counter-clockwise seen from
    outside), read from its OBJ file."""
    if name not in MESHES:
        raise ValueError(f"mesh must be one of {MESHES}, got {name!r}")
    text = resources.files("softgrasp_env.scene").joinpath("meshes", f"{name}.obj").read_text()
    verts, faces = [], []
    for line in text.splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            verts.append([float(v) for v in parts[1:4]])
        elif parts[0] == "f":
            faces.append([int(v.split("/")[0]) - 1 for v in parts[1:4]])
    v, f = np.array(verts, dtype=np.float64), np.array(faces, dtype=np.int64)
    v.setflags(write=False)
    f.setflags(write=False)
    return v, f


def mesh_mass_properties(vertices: np.ndarray, triangles: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """(volume [m^3], centroid (3,) [m], inertia tensor per unit density about the centroid (3, 3)
    [m^5]) of the closed solid bounded by ``triangles`` (outward, counter-clockwise): the sum over
    the tetrahedra each triangle makes with the origin of their signed volumes and second moments,
    int x x^T dV = det / 120 (a a^T + b b^T + c c^T + s s^T), s = a + b + c (the divergence
    theorem; e.g. Blow & Binstock, "How to find the inertia tensor (or other mass properties) of a
    3D solid body represented by a triangle mesh", 2004)."""
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    det = np.einsum("ij,ij->i", a, np.cross(b, c))
    volume = float(det.sum() / 6.0)
    if not volume > 0.0:
        raise ValueError(f"mesh_mass_properties: the mesh encloses no volume ({volume:g} m^3): are its triangles "
                         "counter-clockwise seen from outside?")  # fmt: skip
    s = a + b + c
    centroid = (det[:, None] * s).sum(axis=0) / (24.0 * volume)
    cov = sum(np.einsum("i,ij,ik->jk", det, v, v) for v in (a, b, c, s)) / 120.0
    cov -= volume * np.outer(centroid, centroid)
    inertia = np.trace(cov) * np.eye(3) - cov
    return volume, centroid, inertia


def mesh_planes(vertices: np.ndarray, triangles: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """(P, 4) the distinct face planes (unit outward normal n, offset d; inside where n . x <= d) of
    a convex mesh, coplanar triangles merged."""
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1)[:, None]
    d = np.einsum("ij,ij->i", n, a)
    planes: list[np.ndarray] = []
    for row in np.column_stack((n, d)):
        if not any(np.abs(row - q).max() < tol for q in planes):
            planes.append(row)
    return np.array(planes)


def _quat_from_matrix(m: np.ndarray) -> tuple[float, float, float, float]:
    """(x, y, z, w) of the rotation matrix ``m`` (Shepperd's method: the largest diagonal term)."""
    t = np.trace(m)
    if t > 0.0:
        s = 2.0 * math.sqrt(1.0 + t)
        q = ((m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, 0.25 * s)
    else:
        i = int(np.argmax(np.diag(m)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(1.0 + m[i, i] - m[j, j] - m[k, k])
        v = [0.0, 0.0, 0.0]
        v[i] = 0.25 * s
        v[j] = (m[j, i] + m[i, j]) / s
        v[k] = (m[k, i] + m[i, k]) / s
        q = (v[0], v[1], v[2], (m[k, j] - m[j, k]) / s)
    norm = math.sqrt(sum(x * x for x in q))
    return tuple(float(x / norm) for x in q)  # type: ignore[return-value]


# --- the geometry of an object in its principal frame -------------------------------------------------


@dataclass(frozen=True)
class ObjectGeometry:
    """An :class:`ObjectShape` in its principal frame, for a given mass: what the scene builds.

    ``tissue`` is the shape the tissue collides with, (kind, params, local_x) for
    softgrasp_env.sim.world.ShapeSpec; ``vertices`` the points pybullet's convex mesh is made of
    (None for its primitives)."""

    shape: ObjectShape
    volume: float
    """[m^3]"""
    inertia_per_mass: tuple[float, float, float]
    """Principal moments of inertia per kg [m^2]."""
    rest_q: tuple[float, float, float, float]
    """Orientation (x, y, z, w) of the principal frame when the object rests on the ground."""
    rest_height: float
    """Height of the centre of mass above the ground at rest [m]."""
    top: float
    """Height of the object's highest point above the ground at rest [m]."""
    up: tuple[float, float, float]
    """The body-frame direction that points up at rest."""
    tilt_axis: tuple[float, float, float] | None
    """The body-frame direction whose turn is the object's tilt (None: a sphere, which has none):
    :attr:`up` for an object standing, whose tilt is that axis' angle from the vertical; a lying
    capsule's own axis, whose tilt is its angle from the horizontal (rolling about it is no tilt)."""
    tissue_kind: str
    tissue_params: tuple[float, ...]
    tissue_local_x: tuple[float, float, float]
    vertices: np.ndarray | None
    """(V, 3) body-frame points of pybullet's convex mesh, or None (a primitive)."""
    triangles: np.ndarray | None
    """(F, 3) the mesh's triangles over ``vertices``, counter-clockwise seen from outside (what
    pybullet draws), or None."""
    support_points: np.ndarray
    """(K, 3) points whose convex hull is the shape at rest (relative to the centre of mass, world
    axes), dense enough for its horizontal extent (:meth:`half_width`) to within 0.2 %."""

    def half_width(self, dx: float, dy: float) -> float:
        """How far the object reaches from its centre of mass along the horizontal unit direction
        (dx, dy) at rest [m]: its support function."""
        return float((self.support_points[:, 0] * dx + self.support_points[:, 1] * dy).max())


def _ring(rx: float, ry: float, z: float, n: int = POLYGON_SIDES) -> np.ndarray:
    t = np.arange(n) * (2.0 * math.pi / n)
    return np.column_stack((rx * np.cos(t), ry * np.sin(t), np.full(n, z)))


def _ring_triangles(n: int, apex: bool) -> np.ndarray:
    """Triangles closing two rings of n vertices (0..n-1 below, n..2n-1 above, both counter-clockwise
    seen from +z; ``apex``: one vertex n above instead), with the bottom face fanned from vertex 0
    and the top from vertex n."""
    tris = []
    for i in range(n):
        j = (i + 1) % n
        if apex:
            tris.append((i, j, n))
        else:
            tris += [(i, j, n + j), (i, n + j, n + i)]
    tris += [(0, j + 1, j) for j in range(1, n - 1)]
    if not apex:
        tris += [(n, n + j, n + j + 1) for j in range(1, n - 1)]
    return np.array(tris, dtype=np.int64)


def _rotate(q: tuple[float, float, float, float], v: np.ndarray) -> np.ndarray:
    x, y, z, w = q
    m = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])  # fmt: skip
    return v @ m.T


_IDENTITY = (0.0, 0.0, 0.0, 1.0)
_LYING_ALONG_Y = (-math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5))
"""A quarter turn about x: the body's z axis along the world's y."""


@functools.lru_cache(maxsize=256)
def object_geometry(shape: ObjectShape) -> ObjectGeometry:
    """The :class:`ObjectGeometry` of ``shape`` (exact mass properties for a uniform density:
    analytic for the round kinds, the mesh's own for a hull)."""
    k, s = shape.kind, shape.size
    vertices = triangles = None
    tilt_axis: tuple[float, float, float] | None = None  # None below: the up axis
    local_x = (0.0, 0.0, 0.0)
    rest_q, up = _IDENTITY, (0.0, 0.0, 1.0)
    if k == "cylinder":
        r, h = s
        vol = math.pi * r * r * h
        i = (r * r / 4 + h * h / 12, r * r / 4 + h * h / 12, r * r / 2)
        tissue = ("cylinder", (r, 0.5 * h, 0.0))
        rest, top = 0.5 * h, h
        pts = np.vstack((_ring(r, r, -0.5 * h), _ring(r, r, 0.5 * h)))
    elif k == "sphere":
        (r,) = s
        vol = 4.0 / 3.0 * math.pi * r**3
        i = (0.4 * r * r,) * 3
        tissue = ("sphere", (r, 0.0, 0.0))
        tilt_axis = ()  # no tilt
        rest, top = r, 2 * r
        pts = _ring(r, r, 0.0)
    elif k == "box":
        x, y, z = s
        vol = x * y * z
        i = ((y * y + z * z) / 12, (x * x + z * z) / 12, (x * x + y * y) / 12)
        tissue = ("box", (0.5 * x, 0.5 * y, 0.5 * z))
        rest, top = 0.5 * z, z
        pts = np.array([[sx * 0.5 * x, sy * 0.5 * y, 0.0] for sx in (-1, 1) for sy in (-1, 1)])
    elif k == "capsule":
        r, length = s
        half = 0.5 * length
        vc, vs = math.pi * r * r * length, 4.0 / 3.0 * math.pi * r**3
        vol = vc + vs
        fc, fs = vc / vol, vs / vol  # mass fractions of the straight part and the two caps
        # the caps: a hemisphere's moment about its flat face's diameter, 2/5 m r^2, moved to the
        # capsule's centre past its own centroid (3 r / 8 from the face): 2/5 r^2 + L^2 + 3/4 L r
        ix = fc * (r * r / 4 + length * length / 12) + fs * (0.4 * r * r + half * half + 0.75 * half * r)
        i = (ix, ix, fc * r * r / 2 + fs * 0.4 * r * r)
        tissue = ("capsule", (r, half, 0.0))
        rest_q, up = _LYING_ALONG_Y, (0.0, -1.0, 0.0)
        tilt_axis = (0.0, 0.0, 1.0)
        rest, top = r, 2 * r
        pts = np.vstack((_ring(r, r, -half), _ring(r, r, half)))
        pts = _rotate(rest_q, pts)
    elif k == "cone":
        r0, r1, h = s
        # radius r(z) = r0 + (r1 - r0) z / h from the base; volume, centroid and moments by
        # 3-point Gauss-Legendre in z, exact for these polynomials of degree <= 5
        g, w = np.polynomial.legendre.leggauss(3)
        z = 0.5 * h * (g + 1.0)
        wz = 0.5 * h * w
        rz = r0 + (r1 - r0) * z / h
        area = math.pi * rz * rz
        vol = float((wz * area).sum())
        zc = float((wz * area * z).sum() / vol)
        izz = float((wz * area * rz * rz / 2).sum()) / vol
        ixx = float((wz * area * (rz * rz / 4 + (z - zc) ** 2)).sum()) / vol
        i = (ixx, ixx, izz)
        tissue = ("cone", (r0, r1, 0.5 * h))
        local_x = (0.0, 0.0, 0.5 * h - zc)
        rest, top = zc, h
        rings = [_ring(r0, r0, -zc)]
        if r1 > 0.0:
            rings.append(_ring(r1, r1, h - zc))
        else:
            rings.append(np.array([[0.0, 0.0, h - zc]]))
        vertices = np.vstack(rings)
        triangles = _ring_triangles(POLYGON_SIDES, apex=r1 == 0.0)
        pts = vertices
    elif k == "elliptic":
        a, b, h = s
        vol = math.pi * a * b * h
        i = (b * b / 4 + h * h / 12, a * a / 4 + h * h / 12, (a * a + b * b) / 4)
        tissue = ("elliptic", (a, b, 0.5 * h))
        rest, top = 0.5 * h, h
        vertices = np.vstack((_ring(a, b, -0.5 * h), _ring(a, b, 0.5 * h)))
        triangles = _ring_triangles(POLYGON_SIDES, apex=False)
        pts = vertices
    else:  # hull
        from ..tissue.collision import hull_params

        v0, triangles = load_mesh(shape.mesh)
        tri = triangles
        v0 = v0 * s[0]
        vol, c, inertia = mesh_mass_properties(v0, tri)
        moments, axes = np.linalg.eigh(inertia / vol)
        if np.linalg.det(axes) < 0.0:
            axes[:, 2] = -axes[:, 2]
        # the principal frame: body = axes^T (world - c); at rest the body turns by axes
        vertices = (v0 - c) @ axes
        rest_q = _quat_from_matrix(axes)
        up = tuple(float(u) for u in axes[2])  # axes^T z
        i = tuple(float(m) for m in moments)
        tissue = ("hull", hull_params(vertices, mesh_planes(vertices, tri)))
        rest, top = float(c[2]), float(v0[:, 2].max())
        pts = v0 - c
    if tilt_axis is None:
        tilt_axis = up
    return ObjectGeometry(shape=shape, volume=vol, tilt_axis=tilt_axis or None, inertia_per_mass=tuple(float(x) for x in i), rest_q=rest_q,
                          rest_height=float(rest), top=float(top), up=up, tissue_kind=tissue[0],
                          tissue_params=tuple(float(x) for x in tissue[1]), tissue_local_x=local_x,
                          vertices=vertices, triangles=triangles, support_points=np.asarray(pts, dtype=np.float64))  # fmt: skip


__all__ = ["MESHES", "OBJECT_KINDS", "PRESETS", "ObjectGeometry", "ObjectShape", "load_mesh", "mesh_mass_properties",
           "mesh_planes", "object_geometry", "object_shape"]  # fmt: skip
