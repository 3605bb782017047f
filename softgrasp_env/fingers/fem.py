"""Finger kind 'fem': each finger core carries a fully deformable pad simulated by pybullet's own
FEM soft bodies (``resetSimulation(RESET_USE_DEFORMABLE_WORLD)``, ``loadSoftBody`` of a tetrahedral
mesh, NeoHookean material, ``createSoftBodyAnchor`` to pin it to the core link).

It stands in for the oriented-particle tissue (the thesis' method) as the "fully deformable
fingers" anchor the thesis calls too costly for real time: same cores, same motors, same objects,
so the cost and the grasp can be measured side by side instead of asserted.

The pad
-------
An L-shaped block over the core's inner face (the one toward the other finger) and its tip (-z),
``TissueConfig.extrude`` (8 mm) thick, as the tissue it replaces: the inner face is what squeezes
the cylinder, the tip what meets the ground first; the back, sides and top never touch anything in
the grasp (the tissue kind's ``faces='contact'`` covers the same two faces). It is a
structured hex grid, each hex split into 6 tetrahedra around its main diagonal (Kuhn / Freudenthal
split): with every hex split the same way neighbouring hexes share their face diagonals, so the
mesh is conforming without any search. One such split is chiral, and the pad then pushes what it
squeezes sideways along the face. So the split is mirrored across the
face's middle planes (y = 0, z = 0; both grid planes, the cell counts along the face are even),
which keeps it conforming (a mirror fixes the triangulation of the plane it mirrors in) and makes
the pad symmetric as the tissue is. Cells inside the core are left out. The grid is given by the
cells through the pad's thickness (``FemConfig.resolution``: 'coarse' 1, 'fine' 2); the
cells along the face are as near cubic as the core's extents allow.

The nodes on the core's surface are anchored to the core link (``createSoftBodyAnchor``: the node
follows the link rigidly, two-way). The pad does not collide with its own core (a collision filter
pair): its anchored nodes lie on the core's face, and pybullet's contacts would fight the
anchors and tear the pad.

Time step: pybullet's deformable world integrates the elastic forces explicitly (only damping,
contacts and anchors are implicit), so the pads need a shorter step than the scene's 1/240 s; the
scene takes ``FemConfig.substeps`` pybullet steps per world step. The package's documentation
(Results: the methods side by side, "FEM pads") gives the measurements behind these choices.

What pybullet reports: ``getContactPoints`` lists a soft body's face-rigid contacts with their
normal force, but not its node-rigid contacts (PhysicsServerCommandProcessor, 3.2.7), so
``contact_normal_force`` (the env's finger-force observation) reads low: 1-3 N against the 3 N
the finger motors push with in a steady squeeze.

The mesh is written as legacy VTK (UNSTRUCTURED_GRID, tetrahedra only) into a cache directory,
named by a hash of its content, because pybullet's ``loadSoftBody`` reads a file by path. The
nodes are given in the core link's frame; the body is loaded at the link's world pose.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from dataclasses import dataclass

import numba as nb
import numpy as np
import pybullet as p
from pybullet_utils.bullet_client import BulletClient

from ..config import TissueConfig
from ..sim.bullet import _quiet_c_stdout
from ..sim.world import World
from ..tissue.collision import SHAPE_CODES, shape_distance_array
from ..validation import check_choice, check_int
from .base import FingerConfig, FingerKind, Visual

FEM_CELLS_THROUGH = {"coarse": 1, "fine": 2}
"""Tetrahedral-mesh resolution: hex cells through the pad's thickness (8 mm: 8 or 4 mm cells)."""

# --- material ---------------------------------------------------------------------------------------
# pybullet's NeoHookean force is Smith et al. 2018's stable Neo-Hookean (btDeformableNeoHookeanForce):
# first Piola stress P = mu (1 - 1 / (I_C + 1)) F + (lambda (J - 1) - 3/4 mu) cof F, with its own
# parameters mu, lambda [Pa] and a damping coefficient [s] (Rayleigh stiffness damping: the stress
# of the strain rate times it). Linearised about F = I that is Lame's mu_L = 3/4 mu and lambda_L =
# lambda - 5/8 mu (Smith et al. sec. 3.4: mu = 4/3 mu_L, lambda = lambda_L + 5/6 mu_L). The pads
# take the tissue's material: shear modulus G (TissueConfig.shear_modulus) and Poisson's ratio 0,
# the linear elasticity the tissue's continuum group energy discretises (its finite-element
# reference's too), so mu_L = G, lambda_L = 0.


def neo_hookean_parameters(shear_modulus: float) -> tuple[float, float]:
    """pybullet's (NeoHookeanMu, NeoHookeanLambda) [Pa] for a pad of shear modulus ``shear_modulus``
    [Pa] and Poisson's ratio 0 at small strain."""
    return 4.0 / 3.0 * shear_modulus, 5.0 / 6.0 * shear_modulus


FEM_DAMPING = 0.01
"""The stable Neo-Hookean's damping coefficient [s]. Tried at 1/240 s on the earlier, stiffer pads
(Lame mu 9 kPa, nu 0.41): a pad ten times stiffer or with a tenth of this damping blew up in the
approach, before any contact (explicit elastic forces, see FemConfig.substeps); at 1/960 s three
times this damping let the cylinder slide out and fall over (14.6 mm of slip in a 1 s hold,
against 4 mm)."""
FEM_COLLISION_MARGIN = 0.001
"""Collision margin of the pad [m]: contacts begin this far from a rigid surface."""
FEM_SDF_VOXEL = 0.005
"""Voxel size of the sparse signed-distance field that pybullet's deformable-rigid node contacts
are evaluated on [m] (the deformable world's own default too; stated here, not inherited)."""


FEM_GROUND_HALF_EXTENTS = (1.0, 1.0, 0.05)
"""The ground of the fem scene: a static box, its top face at z = 0 [m]."""


def fem_ground_shape(client: BulletClient) -> int:
    """Collision shape of the ground for the fem scene: a box, not pybullet's plane (pads above a
    GEOM_PLANE get phantom contacts with it and tear). The rigid bodies meet the box's top face as
    they met the plane."""
    h = FEM_GROUND_HALF_EXTENTS
    return client.createCollisionShape(p.GEOM_BOX, halfExtents=list(h), collisionFramePosition=[0.0, 0.0, -h[2]])


@dataclass(frozen=True)
class PadMesh:
    """A tetrahedral pad mesh in its core's link frame."""

    node_x: np.ndarray
    """(N, 3) rest positions [m]."""
    tets: np.ndarray
    """(T, 4) node indices, each positively oriented."""
    node_anchored: np.ndarray
    """(N,) True for nodes on the core's surface (pinned to the core)."""

    @property
    def node_count(self) -> int:
        return int(self.node_x.shape[0])

    @property
    def volume(self) -> float:
        x = self.node_x[self.tets]
        return float(np.einsum("ij,ij->i", np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), x[:, 3] - x[:, 0]).sum() / 6.0)


def _axis(lo: float, hi: float, cell: float) -> np.ndarray:
    """Grid lines from lo to hi, as near ``cell`` apart as an even count allows: an even count puts
    a grid plane at the middle, the mirror plane of the split (see pad_mesh)."""
    n = 2 * max(1, int(round(0.5 * (hi - lo) / cell)))
    return np.linspace(lo, hi, n + 1)


def pad_mesh(half_extents: tuple[float, float, float], thickness: float, cells_through: int, *, side: int = +1) -> PadMesh:
    """The L-shaped pad over the inner face (x = side * hx) and the tip (z = -hz) of a core box with
    ``half_extents``, ``thickness`` deep, ``cells_through`` hex cells through the thickness."""
    hx, hy, hz = half_extents
    cell = thickness / cells_through
    # grid lines: through the core's width, then through the pad; the tip layer, then up the face
    xs = np.concatenate([_axis(-hx, hx, cell)[:-1], np.linspace(hx, hx + thickness, cells_through + 1)])
    ys = _axis(-hy, hy, cell)
    zs = np.concatenate([np.linspace(-hz - thickness, -hz, cells_through + 1)[:-1], _axis(-hz, hz, cell)])
    nx, ny, nz = len(xs), len(ys), len(zs)
    grid = np.stack(np.meshgrid(xs, ys, zs, indexing="ij"), axis=-1).reshape(-1, 3)
    gid = np.arange(nx * ny * nz).reshape(nx, ny, nz)
    # the hex's corners, v[4a + 2b + c] = (i + a, j + b, k + c); 6 tets along the diagonal v0-v7,
    # one per order in which the path from v0 to v7 steps along x (4), y (2) and z (1)
    orders = ((4, 2, 1), (4, 1, 2), (2, 4, 1), (2, 1, 4), (1, 4, 2), (1, 2, 4))
    eps = 1e-9
    tets = []
    for i in range(nx - 1):
        for k in range(nz - 1):
            cx, cz = 0.5 * (xs[i] + xs[i + 1]), 0.5 * (zs[k] + zs[k + 1])
            if cx < hx and cz > -hz:  # inside the core
                continue
            # mirrored below the face's middle (z < 0): see the docstring
            fz = cz < 0.0
            for j in range(ny - 1):
                fy = 0.5 * (ys[j] + ys[j + 1]) < 0.0
                v = [gid[i + a, j + (1 - b if fy else b), k + (1 - c if fz else c)]
                     for a in (0, 1) for b in (0, 1) for c in (0, 1)]  # fmt: skip
                for s0, s1, _ in orders:
                    tets.append((v[0], v[s0], v[s0 + s1], v[7]))
    tets = np.array(tets, dtype=np.int64)
    used = np.unique(tets)
    remap = -np.ones(len(grid), dtype=np.int64)
    remap[used] = np.arange(len(used))
    x = grid[used].copy()
    tets = remap[tets]
    x[:, 0] *= side
    # orient every tet positively (pybullet's boundary faces then point outward)
    e = x[tets]
    vol6 = np.einsum("ij,ij->i", np.cross(e[:, 1] - e[:, 0], e[:, 2] - e[:, 0]), e[:, 3] - e[:, 0])
    flip = vol6 < 0
    tets[flip] = tets[flip][:, [0, 2, 1, 3]]
    ax = np.abs(x[:, 0])
    anchored = (np.abs(ax - hx) < eps) & (x[:, 2] >= -hz - eps) | (np.abs(x[:, 2] + hz) < eps) & (ax <= hx + eps)
    return PadMesh(x, tets, anchored)


def write_vtk(mesh: PadMesh, path: str) -> None:
    """Legacy-VTK UNSTRUCTURED_GRID of tetrahedra (cell type 10), one point / cell per line as
    bullet's reader (btSoftBodyHelpers::CreateFromVtkFile) parses it."""
    lines = ["# vtk DataFile Version 2.0", "softgrasp fem pad", "ASCII", "DATASET UNSTRUCTURED_GRID",
             f"POINTS {mesh.node_count} double"]  # fmt: skip
    lines += [f"{a:.12g} {b:.12g} {c:.12g}" for a, b, c in mesh.node_x]
    lines.append(f"CELLS {len(mesh.tets)} {5 * len(mesh.tets)}")
    lines += [f"4 {a} {b} {c} {d}" for a, b, c, d in mesh.tets]
    lines.append(f"CELL_TYPES {len(mesh.tets)}")
    lines += ["10"] * len(mesh.tets)
    tmp = f"{path}.{os.getpid()}.tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(tmp, path)  # atomic: parallel processes may write the same cached file


def cache_dir() -> str:
    d = os.environ.get("SOFTGRASP_FEM_CACHE") or os.path.join(tempfile.gettempdir(), "softgrasp_fem")
    os.makedirs(d, exist_ok=True)
    return d


def vtk_file(mesh: PadMesh) -> str:
    """Path of the mesh's VTK file in the cache (written if missing)."""
    h = hashlib.sha1(np.ascontiguousarray(mesh.node_x).tobytes() + np.ascontiguousarray(mesh.tets).tobytes()).hexdigest()[:16]
    path = os.path.join(cache_dir(), f"pad_{h}.vtk")
    if not os.path.exists(path):
        write_vtk(mesh, path)
    return path


@nb.njit(cache=True)
def _deepest_inside(kind: int, params: np.ndarray, local: np.ndarray) -> float:
    """The largest -signed distance (collision.shape_distance_array) of the rows of ``local`` (N, 3)
    from the shape, 0 if none is inside [m]."""
    deepest = 0.0
    for i in range(local.shape[0]):
        d = -shape_distance_array(kind, params, local[i])[0]
        if d > deepest:
            deepest = d
    return deepest


def object_depth(x: np.ndarray, pos, rot: np.ndarray, kind: str, params, local_x=(0.0, 0.0, 0.0)) -> float:
    """How deep the deepest of the points ``x`` (N, 3) [m, world] lies inside an object's shape,
    0 if none is inside [m].

    The object's body frame is at ``pos`` (3,) [m] turned by ``rot`` (3, 3, body to world: its
    principal frame, as pybullet reports the base); its shape, a ``kind`` of
    collision.SHAPE_CODES with ``params`` (the kind's three, or a hull's whole row), sits at
    ``local_x`` [m] in that frame, unturned (objects.ObjectGeometry.tissue_*)."""
    local = (np.asarray(x, dtype=np.float64) - np.asarray(pos, dtype=np.float64)) @ rot
    local = np.ascontiguousarray(local - np.asarray(local_x, dtype=np.float64))
    return float(_deepest_inside(SHAPE_CODES[kind], np.asarray(params, dtype=np.float64), local))


class FemPads:
    """The two finger pads of a GraspScene with ``fingers='fem'``: loading, anchoring, and what the
    scene reads back (squeeze force, node positions, penetration)."""

    def __init__(self, client: BulletClient, cfg, gripper: int, cylinder: int, *, resolution: str,
                 links: tuple[int, int] = (0, 1)) -> None:  # fmt: skip
        self.client = c = client
        self.gripper, self.cylinder, self.links = gripper, cylinder, links
        self.cylinder_radius, self.cylinder_half_height = cfg.cylinder_radius, 0.5 * cfg.cylinder_height
        self.object_geometry = cfg.object_geometry
        """The grasped object's geometry (objects.ObjectGeometry), None for the cylinder."""
        if self.object_geometry is not None:
            g = self.object_geometry
            self._object_shape = (g.tissue_kind, np.asarray(g.tissue_params, dtype=np.float64),
                                  np.asarray(g.tissue_local_x, dtype=np.float64))  # fmt: skip
        self.core_half_extents = tuple(cfg.finger_half_extents)
        c.setPhysicsEngineParameter(sparseSdfVoxelSize=FEM_SDF_VOXEL)
        fh = cfg.finger_half_extents
        mu, lam = neo_hookean_parameters(cfg.tissue.shear_modulus)
        self.meshes: list[PadMesh] = []
        self.bodies: list[int] = []
        for link, side in zip(links, (+1, -1), strict=True):  # the left core's inner face is +x, the right's -x
            mesh = pad_mesh(fh, cfg.tissue.extrude, FEM_CELLS_THROUGH[resolution], side=side)
            pos, orn = c.getLinkState(gripper, link)[4:6]  # the link frame (its inertial frame is the same)
            with _quiet_c_stdout():  # bullet prints node/link/face/tet counts on C stdout
                body = c.loadSoftBody(
                    vtk_file(mesh), basePosition=pos, baseOrientation=orn, scale=1.0,
                    mass=cfg.tissue.mass_density * mesh.volume, useNeoHookean=1, NeoHookeanMu=mu,
                    NeoHookeanLambda=lam, NeoHookeanDamping=FEM_DAMPING, useMassSpring=0,
                    useBendingSprings=0, collisionMargin=FEM_COLLISION_MARGIN, useSelfCollision=0,
                    frictionCoeff=cfg.tissue.friction_static,
                )  # fmt: skip
            if body < 0:
                raise RuntimeError(f"pybullet could not load the fem pad {vtk_file(mesh)}")
            n = c.getMeshData(body, -1, flags=p.MESH_DATA_SIMULATION_MESH)[0]
            if n != mesh.node_count:
                raise RuntimeError(f"fem pad loaded with {n} nodes, the mesh has {mesh.node_count}")
            # the pad is glued to its core by anchors; contacts with the core would fight them
            c.setCollisionFilterPair(body, gripper, -1, link, 0)
            for i in np.flatnonzero(mesh.node_anchored):
                c.createSoftBodyAnchor(body, int(i), gripper, link, mesh.node_x[i].tolist())
            self.meshes.append(mesh)
            self.bodies.append(body)

    @property
    def node_count(self) -> int:
        return sum(m.node_count for m in self.meshes)

    def node_positions(self) -> list[np.ndarray]:
        """(N, 3) world positions of each pad's nodes [m]."""
        c = self.client
        return [np.asarray(c.getMeshData(b, -1, flags=p.MESH_DATA_SIMULATION_MESH)[1]) for b in self.bodies]

    def contact_normal_force(self) -> np.ndarray:
        """Normal force each pad (left, right) pressed on the object with in the last step [N]."""
        c = self.client
        f = np.zeros(2)
        for k, b in enumerate(self.bodies):
            for pt in c.getContactPoints(bodyA=b, bodyB=self.cylinder):
                f[k] += pt[9]
        return f

    def penetration(self) -> tuple[float, float]:
        """(deepest pad node inside the object or below the ground's top face, deepest node inside
        its own core's box) now [m], 0 where none is; the same measure GraspScene.penetration takes
        for the tissue's particles (whose centres it checks, as here the nodes). The object's shape
        is the one the tissue collides with (objects.ObjectGeometry.tissue_*: exact for the round
        kinds, where pybullet's mesh is an inscribed polygon)."""
        c = self.client
        pos, orn = c.getBasePositionAndOrientation(self.cylinder)
        rot = np.asarray(c.getMatrixFromQuaternion(orn)).reshape(3, 3)
        pen = intrusion = 0.0
        for link, mesh, x in zip(self.links, self.meshes, self.node_positions(), strict=True):
            if self.object_geometry is None:
                local = (x - np.asarray(pos)) @ rot
                radial = self.cylinder_radius - np.hypot(local[:, 0], local[:, 1])
                axial = self.cylinder_half_height - np.abs(local[:, 2])
                inside = float(np.minimum(radial, axial).max(initial=0.0))
            else:
                inside = object_depth(x, pos, rot, *self._object_shape)
            pen = max(pen, inside, float((-x[:, 2]).max(initial=0.0)))
            lpos, lorn = c.getLinkState(self.gripper, link)[4:6]
            lrot = np.asarray(c.getMatrixFromQuaternion(lorn)).reshape(3, 3)
            inside = np.min(np.asarray(self.core_half_extents) - np.abs((x - np.asarray(lpos)) @ lrot), axis=1)
            free = ~mesh.node_anchored  # anchored nodes sit on the core's face by construction
            intrusion = max(intrusion, float(inside[free].max(initial=0.0)))
        return pen, intrusion

    def is_finite(self) -> bool:
        return all(np.isfinite(x).all() for x in self.node_positions())


FEM_RGBA = (0.55, 0.8, 0.45, 1.0)
FEM_NODE_RADIUS = 0.0015
"""Radius of the sphere a renderer draws at each pad node [m]."""


@dataclass(frozen=True, eq=False)
class FemConfig(FingerConfig):
    """Settings of the FEM pads (their depth, mass density and friction are the finger surface's:
    ``SceneConfig.tissue.extrude``, ``mass_density``, ``friction_static``)."""

    kind = "fem"
    resolution: str = "coarse"
    """Tetrahedral mesh of the pads, one of FEM_CELLS_THROUGH: 'coarse' - one hex cell (6 tets)
    through the 8 mm pad, about 8-10 mm cells along it; 'fine' - two, about 4 mm cells."""
    substeps: int = 8
    """pybullet steps per world step (``sim.dt``), each ``sim.dt / substeps`` long. pybullet's
    deformable world integrates the elastic forces explicitly (only the damping and the
    constraints are implicit): with fewer than 8 substeps at 1/240 s the coarse pads knock the
    cylinder over at first contact (1) or let it slide 3-5 mm in the hold (2, 4)."""

    def __post_init__(self) -> None:
        check_choice("resolution", self.resolution, tuple(FEM_CELLS_THROUGH), owner="FemConfig")
        check_int("substeps", self.substeps, 1, 64, owner="FemConfig")


class FemFingers(FingerKind):
    """The fem kind in a scene: the deformable world, a box ground, the substeps, and the pads
    (:class:`FemPads`), built once the world exists."""

    name = "fem"
    config_type = FemConfig
    description = "pybullet's FEM soft pads on each core (fully deformable fingers)"
    no_tactile = ("pybullet reports no contact points of its FEM pads' nodes (their contact force reads low too), "
                  "so there is nothing to bin onto taxels")
    reset_flags = p.RESET_USE_DEFORMABLE_WORLD

    def __init__(self, scene_config) -> None:
        super().__init__(scene_config)
        self.pads: FemPads | None = None

    @classmethod
    def pad_thickness(cls, config: FingerConfig, tissue: TissueConfig) -> float:
        """The pad's depth: the tissue's extrude (the same 8 mm by default)."""
        return tissue.extrude

    @property
    def bullet_substeps(self) -> int:
        return self.config.substeps

    def ground_shape(self, client: BulletClient) -> int:
        return fem_ground_shape(client)

    def connect(self, world: World) -> None:
        super().connect(world)
        s = self.site
        self.pads = FemPads(s.client, self.scene_config, s.gripper, s.cylinder, resolution=self.config.resolution,
                            links=s.core_links)  # fmt: skip

    def contact_force(self) -> np.ndarray:
        """pybullet's core contacts plus the pads' face contacts (it reports no node contacts, so
        this reads low: FemPads)."""
        return super().contact_force() + self.pads.contact_normal_force()

    def penetration(self) -> tuple[float, float]:
        pen, intrusion = super().penetration()
        fem_pen, fem_intrusion = self.pads.penetration()
        return max(pen, fem_pen), max(intrusion, fem_intrusion)

    def divergence(self) -> str | None:
        return None if self.pads.is_finite() else "non-finite fem pad node"

    def visuals(self) -> list[Visual]:
        """The cores, and a small sphere at each pad node (the pads' deformation as it is)."""
        pads = self.pads
        n = pads.node_count
        return super().visuals() + [Visual("points", np.tile(FEM_RGBA, (n, 1)), radii=np.full((n, 3), FEM_NODE_RADIUS),
                                           positions=lambda: np.concatenate(pads.node_positions()))]  # fmt: skip


__all__ = ["FEM_CELLS_THROUGH", "FemConfig", "FemFingers", "FemPads", "PadMesh", "fem_ground_shape", "object_depth",
           "pad_mesh", "vtk_file", "write_vtk"]  # fmt: skip
