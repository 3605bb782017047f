"""The finger interface: what one kind of finger adds to the gripper of a grasp scene.

Every kind shares the gripper's two prismatic cores (box links 0 and 1, their motors and gear,
softgrasp_env/scene/gripper.py). A kind adds what touches the cylinder - nothing (``rigid``),
oriented-particle tissue (``tissue``), sprung rigid segments (``segmented``), pybullet FEM pads
(``fem``) - and tells the scene, the env and the renderer what it needs and what it measures.

The life of a kind inside a :class:`~softgrasp_env.scene.GraspScene`::

    FingerKind.check(scene_config)         static: refuse settings that would not run (ValueError)
    kind = FingerKind(scene_config)
    kind.reset_flags, kind.bullet_substeps, kind.ground_shape(client)      the physics server
    kind.extend_gripper(links, client)     links of its own, before the gripper body exists
    kind.mount(site) -> [TissueSpec]       after: constraints, motors; the tissue it wraps the cores in
    kind.connect(world)                    the world (pybullet + tissue) exists
    every physics step: kind.before_step()
    queries: contact_force(), tactile(grid), penetration(), divergence(), visuals()

The base class is the bare-core behaviour (the rigid kind adds nothing to it); a kind overrides
what it adds. Adding a kind is a module with a :class:`FingerConfig` and a :class:`FingerKind`
subclass, and one entry in ``softgrasp_env.fingers.FINGERS``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
import pybullet as p
from pybullet_utils.bullet_client import BulletClient

from ..config import TissueConfig
from .tactile import INNER_NORMAL, TaxelGrid, bin_contacts

if TYPE_CHECKING:
    from ..sim.world import TissueSpec, World


@dataclass(frozen=True, eq=False)
class FingerConfig:
    """Base of a finger kind's own settings (each kind's module defines its subclass). A config
    compares equal to its kind's name, so ``scene_config.fingers == "rigid"`` reads as it did when
    the field held the name alone. Subclasses are ``@dataclass(frozen=True, eq=False)`` so they
    keep this comparison."""

    kind: ClassVar[str] = ""

    def __eq__(self, other: object) -> bool:
        if isinstance(other, str):
            return other == self.kind
        if type(other) is not type(self):
            return NotImplemented
        return all(getattr(self, f.name) == getattr(other, f.name) for f in fields(self))

    def __hash__(self) -> int:
        return hash((type(self), tuple(getattr(self, f.name) for f in fields(self))))


@dataclass(frozen=True)
class FingerSite:
    """Where a kind is mounted: the scene's pybullet bodies and the shape indices the tissue sees
    (softgrasp_env/scene/scene.py owns both)."""

    client: BulletClient
    gripper: int
    """The gripper's multibody: the palm is its base, the finger cores links ``core_links``."""
    cylinder: int
    ground: int
    core_links: tuple[int, int]
    """The left and right finger cores' link indices."""
    core_shapes: tuple[int, int]
    """Indices of the cores among the shapes the tissue sees (World's shape list)."""
    cylinder_shape: int
    """Index of the cylinder among those shapes."""
    gear_force: float
    """Force limit of the gripper's gear constraints [N] (for a kind that gears links of its own to
    the cores, as the cores are geared to each other)."""
    gear_erp: float
    """Share of a gear's position error corrected per step."""


@dataclass(frozen=True, eq=False)
class Visual:
    """Something a renderer draws for a finger kind (softgrasp_env/render.py).

    ``kind="box"``: the link ``link`` of ``body`` as a box of ``half_extents``, at the link's pose.
    ``kind="object"``: a grasped object of ``geometry`` (scene.objects.ObjectGeometry), its
    ``half_extents`` a box round it for the camera.
    ``kind="points"``: ellipsoids of ``radii`` (N, 3) at ``positions()`` (N, 3) turned by
    ``orientations()`` (N, 4, xyzw; ``None``: unturned), coloured ``rgba`` (N, 4).
    ``in_scene``: the physics server has it as a body already (a GUI draws it itself); False for
    what only the tissue solver knows (the particles)."""

    kind: str
    rgba: np.ndarray
    body: int = -1
    link: int = -1
    half_extents: tuple[float, float, float] = (0.0, 0.0, 0.0)
    radii: np.ndarray | None = None
    positions: Callable[[], np.ndarray] | None = None
    orientations: Callable[[], np.ndarray] | None = None
    in_scene: bool = True
    geometry: Any = None


CORE_RGBA = (0.3, 0.3, 0.8, 1.0)
"""Colour of a bare finger core."""


class FingerKind:
    """One kind of finger in one scene; the base class adds nothing to the bare cores."""

    name: ClassVar[str] = ""
    """The kind's name in ``FINGERS`` (and ``gym.make(..., fingers=name)``)."""
    config_type: ClassVar[type[FingerConfig]] = FingerConfig
    """The kind's own settings (``SceneConfig.fingers`` holds an instance)."""
    has_tissue: ClassVar[bool] = False
    """True if the kind wraps its cores in oriented-particle tissue (the env's ``soft``)."""
    description: ClassVar[str] = ""
    """One line for tables and help texts."""
    no_tactile: ClassVar[str | None] = None
    """Why the kind cannot give a tactile reading (``tactile`` raises, ``gym.make(..., tactile=...)``
    refuses it), or None when it can."""

    def __init__(self, scene_config) -> None:
        self.scene_config = scene_config
        self.config = scene_config.fingers
        self.site: FingerSite | None = None
        self.world: World | None = None

    # --- from the configs alone ---------------------------------------------------------------------

    @classmethod
    def pad_thickness(cls, config: FingerConfig, tissue: TissueConfig) -> float:
        """How far the finger reaches out from its core's inner face and tip [m] (0: bare core)."""
        return 0.0

    @classmethod
    def check(cls, scene_config) -> None:
        """Raise ValueError for settings of the whole scene this kind cannot run with."""

    # --- building -----------------------------------------------------------------------------------

    reset_flags: ClassVar[int] = 0
    """Flags of ``resetSimulation`` the kind needs (pybullet's deformable world, say)."""

    @property
    def bullet_substeps(self) -> int:
        """pybullet steps per world step (each ``sim.dt / bullet_substeps`` long)."""
        return 1

    @property
    def world_substeps(self) -> int:
        """Whole-world steps (tissue and pybullet) per physics step of ``sim.dt``: more than 1 where
        the kind's coupling to pybullet is only stable in shorter steps."""
        return 1

    def ground_shape(self, client: BulletClient) -> int:
        """The ground's collision shape (its top face at z = 0)."""
        return client.createCollisionShape(p.GEOM_PLANE)

    def extend_gripper(self, links: dict[str, list], client: BulletClient) -> None:
        """Append links of the kind's own to the gripper's createMultiBody lists (which hold the
        two cores) before the gripper is created."""

    @property
    def finger_links(self) -> tuple[tuple[int, ...], tuple[int, ...]]:
        """Gripper links whose pybullet contacts with the cylinder count as each finger's."""
        return ((0,), (1,))

    def mount(self, site: FingerSite) -> list[TissueSpec]:
        """The gripper exists: set up what the kind needs on it; return the tissue it wraps the
        cores in (none for a kind without tissue)."""
        self.site = site
        return []

    def connect(self, world: World) -> None:
        """The world (pybullet bodies and tissue) exists."""
        self.world = world

    # --- every physics step -------------------------------------------------------------------------

    def before_step(self) -> None:
        """Runs before every physics step (the segments' springs, say)."""

    # --- queries ------------------------------------------------------------------------------------

    def contact_force(self) -> np.ndarray:
        """Normal force each finger (left, right) pressed on the cylinder with in the last physics
        step [N]: pybullet's contacts of the finger's links; kinds add what pybullet does not see."""
        s = self.site
        # One query for every gripper link: (bodyA, bodyB, linkIndexA, linkIndexB (-2: any),
        # physicsClientId) by position, pybullet's own function (keywords cost ~0.4 us each, the
        # client's wrapper ~1 us; this runs every physics step). Each finger's sum runs link by
        # link in the query's order, the order a query per link gives.
        points = p.getContactPoints(s.cylinder, s.gripper, -1, -2, s.client._client)
        f = [0.0, 0.0]
        if points:
            for k, links in enumerate(self.finger_links):
                for link in links:
                    for pt in points:
                        if pt[4] == link:
                            f[k] += pt[9]
        return np.array(f)

    def taxel_grid(self, rows: int, cols: int) -> TaxelGrid:
        """A ``rows`` x ``cols`` grid of taxels over each core's inner face (the whole face)."""
        fh = self.scene_config.finger_half_extents
        return TaxelGrid(rows, cols, float(fh[1]), float(fh[2]))

    def tactile(self, grid: TaxelGrid) -> np.ndarray:
        """The pads' taxels now, (2, rows, cols, channels) (fingers/tactile.py): here pybullet's
        contact points of each finger's links with any other body, their normal force and both
        lateral friction forces, binned where they touch the core's inner face; no shear (a rigid
        pad does not deform). Kinds with tissue add its loads and its shear."""
        if self.no_tactile is not None:
            raise NotImplementedError(f"fingers={self.name!r} give no tactile reading: {self.no_tactile}")
        s = self.site
        out = grid.empty()
        params = grid.params()
        c = s.client
        for k, links in enumerate(self.finger_links):
            rows = [pt for link in links for pt in c.getContactPoints(bodyA=s.gripper, linkIndexA=link)
                    if pt[2] != s.gripper]  # not the gripper's own links  # fmt: skip
            if not rows:
                continue
            pos, orn = c.getLinkState(s.gripper, s.core_links[k], computeForwardKinematics=1)[:2]
            # contactNormalOnB points from B (the other body) to A (the finger): the normal force
            # pushes the finger along it. The lateral friction forces are not turned with the
            # query's order (pybullet swaps positions and the normal only): they act along their
            # directions on the body Bullet's pair holds first, the one made first (its broadphase
            # pairs are sorted by creation), and against them on the other. Checked: the cylinder
            # held aloft gets m g from the two fingers' friction (tests/fingers/test_tactile.py).
            a = np.array([pt[5] + pt[7] + pt[11] + pt[13] + (pt[9], pt[10], pt[12], 1.0 if s.gripper < pt[2] else -1.0)
                          for pt in rows])  # fmt: skip
            bin_contacts(k, a, np.array(pos + orn), INNER_NORMAL[k], params, out)
        return out

    def penetration(self) -> tuple[float, float]:
        """(deepest overlap of the gripper with the cylinder or the ground, deepest intrusion of a
        finger's soft part into its own core) now [m]: here the depth of pybullet's own contacts
        (a bare core's); kinds add their soft parts' overlaps."""
        s = self.site
        pen = 0.0
        for other in (s.cylinder, s.ground):
            for pt in s.client.getContactPoints(bodyA=s.gripper, bodyB=other):
                pen = max(pen, -pt[8])
        return pen, 0.0

    def divergence(self) -> str | None:
        """Why the kind's own state counts as blown up, or None (the scene checks the rigid bodies
        and the world's finiteness itself)."""
        return None

    def visuals(self) -> list[Visual]:
        """What a renderer draws for the fingers: here the two bare cores."""
        s = self.site
        fh = tuple(self.scene_config.finger_half_extents)
        return [Visual("box", np.asarray(CORE_RGBA), body=s.gripper, link=link, half_extents=fh) for link in s.core_links]


__all__ = ["CORE_RGBA", "FingerConfig", "FingerKind", "FingerSite", "Visual"]
