"""One step of the whole world, in the order the thesis gives (5.2.2).

    read rigid states from pybullet                    (poses, velocities)
    tissue step: predict rigid bodies and particles, collide, shape-match, friction,
                 couple attached particles to the predicted cores -> impulses
    hand the impulses to pybullet                      (velocity change / external force)
    pybullet step                                      (gravity, motors, joints, rigid contacts)
    set attached particles onto the cores' new poses

A world without tissue (rigid-only fingers) is the same recipe with the tissue lines skipped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numba as nb
import numpy as np
import pybullet as p
from pybullet_utils.bullet_client import BulletClient

from ..config import SimConfig
from ..tissue.collision import SHAPE_CODES, check_hull_row
from ..tissue.compliant import world_substeps
from ..tissue.model import TissueModel, concatenate, with_core_shapes
from ..tissue.rigid import Colliders
from ..tissue.rotation import quat_to_matrix
from ..tissue.solver import StepOutput, TissueSolver
from ..tissue.state import TissueState, state_at_rest
from .bullet import RigidRef, StateReader, read_mass_properties
from .coupling import ImpulseApplier, sync_attached


class _SlidingCores:
    """Cores on prismatic links that move inside the solve (consistent coupling): each step, the
    joint axis in the world and the force its motor applied in pybullet's last step along it.

    Inside the solve such a core can only slide along its joint (the joint takes the rest of any
    impulse), and it is predicted under its motor's force: a squeezing finger's motor pushes with
    its force limit, and predicted without it the core recoiled from the tissue like a free body,
    the motor then drove it back in pybullet's step, and the tissue was shifted 1.5 mm a step
    with nothing pushing back (the consistent coupling squeezed 2 N harder than the motors)."""

    def __init__(self, client: BulletClient, refs: list[RigidRef], in_solve: np.ndarray) -> None:
        self._cid = client._client
        self._slots: list[tuple[int, int, int, np.ndarray]] = []
        for k, r in enumerate(refs):
            if r.link < 0 or not in_solve[k]:
                continue
            info = client.getJointInfo(r.body, r.link)
            if info[2] != p.JOINT_PRISMATIC:
                raise ValueError(
                    f"rigid slot {k} (body {r.body} link {r.link}) moves inside the solve but hangs on a joint of type "
                    f"{info[2]}; only prismatic links (or free bases) can: pass in_solve=False and core=False"
                )
            axis = np.asarray(info[13], dtype=np.float64)
            self._slots.append((k, r.body, r.link, axis / np.linalg.norm(axis)))

    def read(self, q: np.ndarray, axis_out: np.ndarray, force_out: np.ndarray) -> None:
        for k, body, link, axis in self._slots:
            a = quat_to_matrix(q[k]) @ axis  # joint axis: in the link frame, which is the CoM frame
            axis_out[k] = a
            force_out[k] = p.getJointState(body, link, physicsClientId=self._cid)[3] * a


class SimulationDiverged(RuntimeError):
    """The tissue solve produced non-finite numbers; they were not handed to pybullet."""


# Which of a kind's three params are lengths that must be > 0 (the others are unused, or for the
# cone a radius that may be 0 at one end: checked on its own).
_POSITIVE_PARAMS = {"plane": (), "sphere": (0,), "box": (0, 1, 2), "cylinder": (0, 1), "capsule": (0, 1),
                    "cone": (2,), "elliptic": (0, 1, 2)}  # fmt: skip
_PARAM_NAMES = {"plane": "(unused)", "sphere": "(radius, -, -)", "box": "(half extents x, y, z)",
                "cylinder": "(radius, half height, -)", "capsule": "(radius, half height, -)",
                "cone": "(bottom radius, top radius, half height)",
                "elliptic": "(semi-axis x, semi-axis y, half height)"}  # fmt: skip


@dataclass(frozen=True)
class ShapeSpec:
    """A collision shape the tissue can touch: ``kind`` in plane/sphere/box/cylinder/capsule/cone/
    elliptic/hull, ``params`` its dimensions (see tissue/collision.py: three for every kind but the
    hull, whose params are its row from ``collision.hull_params``), on rigid slot ``rigid`` (-1 =
    static world geometry) at ``local_x``/``local_q`` in that slot's centre-of-mass frame."""

    kind: str
    params: tuple[float, ...]
    rigid: int = -1
    local_x: tuple[float, float, float] = (0.0, 0.0, 0.0)
    local_q: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        if self.kind not in SHAPE_CODES:
            raise ValueError(f"ShapeSpec.kind must be one of {tuple(SHAPE_CODES)}, got {self.kind!r}")
        try:
            params = tuple(float(x) for x in self.params)
        except (TypeError, ValueError) as e:
            raise ValueError(f"ShapeSpec.params of a {self.kind} must be numbers, got {self.params!r}") from e
        if self.kind == "hull":
            check_hull_row(params, "ShapeSpec('hull') params")
        else:
            if len(params) != 3:
                raise ValueError(f"ShapeSpec.params of a {self.kind} must be 3 numbers {_PARAM_NAMES[self.kind]}, got "
                                 f"{len(params)}: {params!r}")  # fmt: skip
            if not all(math.isfinite(x) for x in params):
                raise ValueError(f"ShapeSpec.params of a {self.kind} must be finite, got {params!r}")
            bad = [k for k in _POSITIVE_PARAMS[self.kind] if not params[k] > 0.0]
            if bad:
                raise ValueError(f"ShapeSpec.params of a {self.kind} {_PARAM_NAMES[self.kind]} must be > 0, got "
                                 f"params[{bad[0]}] = {params[bad[0]]!r}")  # fmt: skip
            if self.kind == "cone" and not (min(params[0], params[1]) >= 0.0 and max(params[0], params[1]) > 0.0):
                raise ValueError(f"ShapeSpec.params of a cone {_PARAM_NAMES['cone']}: the radii must be >= 0 and not "
                                 f"both 0 (one 0 is a full cone), got {params[0]!r} and {params[1]!r}")  # fmt: skip
        object.__setattr__(self, "params", params)


@dataclass(frozen=True)
class TissueSpec:
    """Tissue of one combined body: its model (in the core's centre-of-mass frame) and the index
    of its core among the world's shapes."""

    model: TissueModel
    core_shape: int


def _params_table(shapes: list[ShapeSpec]) -> np.ndarray:
    """(S, K) params of the shapes, each row padded with zeros to the longest (K >= 3: a hull's
    row is longer; without one, the (S, 3) table the kernels always read)."""
    width = max([3] + [len(s.params) for s in shapes])
    table = np.zeros((len(shapes), width))
    for k, s in enumerate(shapes):
        table[k, : len(s.params)] = s.params
    return table


def _mass(inv_mass: float) -> float:
    return math.inf if inv_mass == 0.0 else 1.0 / inv_mass


class World:
    """pybullet rigid bodies plus oriented-particle tissue, stepped together."""

    def __init__(
        self,
        client: BulletClient,
        sim: SimConfig,
        rigid: list[RigidRef],
        shapes: list[ShapeSpec],
        tissue: list[TissueSpec],
        *,
        substeps: int = 1,
    ) -> None:
        if not (isinstance(substeps, int) and substeps >= 1):
            raise ValueError(f"World substeps must be an int >= 1, got {substeps!r}")
        self.client = client
        self.sim = sim
        self.substeps = substeps
        """World steps of sim.dt / substeps per step(): tissue and pybullet each take them (pybullet's
        fixedTimeStep must be set to match by the caller)."""
        self._h = sim.dt / substeps
        self.rigid = list(rigid)
        self.shapes = list(shapes)
        nr = len(self.rigid)
        for k, s in enumerate(self.shapes):
            if not -1 <= s.rigid < nr:
                raise ValueError(f"shape {k} refers to rigid slot {s.rigid}, but there are {nr} slots")
        inv_m, inv_i = read_mass_properties(client, self.rigid)
        self._free_base = np.array([r.free_base for r in self.rigid], dtype=np.bool_)
        self._reader = StateReader(client, self.rigid)
        self._impulses = ImpulseApplier(client, self.rigid, free=self._free_base)
        self._colliders = Colliders(
            rigid_x=np.zeros((nr, 3)),
            rigid_q=np.tile([0.0, 0.0, 0.0, 1.0], (nr, 1)),
            rigid_v=np.zeros((nr, 3)),
            rigid_w=np.zeros((nr, 3)),
            rigid_inv_mass=inv_m,
            rigid_inv_inertia=inv_i,
            rigid_gravity=np.array([r.gravity for r in self.rigid], dtype=np.bool_),
            rigid_in_solve=np.array(
                [r.in_solve or (r.core and sim.coupling == "consistent") for r in self.rigid], dtype=np.bool_
            ),
            shape_kind=np.array([SHAPE_CODES[s.kind] for s in self.shapes], dtype=np.int32),
            shape_params=_params_table(self.shapes),
            shape_rigid=np.array([s.rigid for s in self.shapes], dtype=np.int32),
            shape_local_x=np.array([s.local_x for s in self.shapes], dtype=np.float64).reshape(-1, 3),
            shape_local_q=np.array([s.local_q for s in self.shapes], dtype=np.float64).reshape(-1, 4),
        )
        self._joints = _SlidingCores(client, self.rigid, self._colliders.rigid_in_solve)
        self._stale = False
        """The rigid states in ``_colliders`` are older than pybullet's: a world without tissue reads
        them when they are asked for (``colliders``), not after every step (per physics step only
        what the physics needs)."""
        self.model: TissueModel | None = None
        self.solver: TissueSolver | None = None
        self.state: TissueState | None = None
        self.last_output: StepOutput | None = None
        self._core_rigid: np.ndarray | None = None  # each tissue body's core's rigid slot
        self.refresh()
        if tissue:
            for t in tissue:
                if not 0 <= t.core_shape < len(self.shapes) or self.shapes[t.core_shape].rigid < 0:
                    raise ValueError(f"tissue core_shape {t.core_shape} must be a shape on a rigid slot")
            model = concatenate([with_core_shapes(t.model, np.array([t.core_shape])) for t in tissue])
            self.model = model
            self._core_rigid = np.array([self.shapes[int(k)].rigid for k in model.body_core_shape], dtype=np.intp)
            # The compliant material needs steps short enough for itself and for its pull on the
            # cores (compliant.world_substeps): a World asked for fewer would ring or go unstable.
            core_mass = np.array([_mass(inv_m[self.shapes[t.core_shape].rigid]) for t in tissue])
            need = world_substeps(model, core_mass, sim.dt, sim.material_solve)
            if substeps < need:
                raise ValueError(
                    f"World(substeps={substeps}) at dt={sim.dt:g} s: this tissue needs at least {need} world steps per "
                    f"step (compliant.world_substeps: its material's stiffness and its pull on cores of "
                    f"{', '.join(f'{m:g}' for m in core_mass)} kg); pass substeps={need} and pybullet's fixedTimeStep "
                    f"dt / {need}")  # fmt: skip
            self.solver = TissueSolver(model, replace(sim, dt=self._h) if substeps > 1 else sim)
            cores = [self.shapes[t.core_shape].rigid for t in tissue]
            self.state = state_at_rest(model, self.colliders.rigid_x[cores], self.colliders.rigid_q[cores])
            self._sync()
        self.step_count = 0

    # --- the step ----------------------------------------------------------------------------------

    def step(self) -> None:
        """Advance the world by ``sim.dt`` (in ``substeps`` world steps)."""
        if self.solver is None:
            # Rigid bodies only: nothing here needs their states between steps; ``colliders`` reads
            # them once when asked (the same numbers the eager read after the last step gave).
            for _ in range(self.substeps):
                self.client.stepSimulation()
            self._stale = True
            self.step_count += 1
            return
        col = self._colliders
        for _ in range(self.substeps):
            out = self.solver.step(self.state, col)
            self.last_output = out
            # A NaN impulse would poison pybullet's bodies (and its broadphase) for good: the applier
            # hands nothing over then, and we stop here so the caller can end the episode and rebuild.
            if not self._impulses.apply(col.rigid_x, col.rigid_q, col.rigid_v, col.rigid_w, col.rigid_inv_mass,
                                        col.rigid_inv_inertia, out.rigid_impulse, out.rigid_angular_impulse,
                                        self._h):  # fmt: skip
                raise SimulationDiverged(f"non-finite tissue impulse at step {self.step_count}")
            self.client.stepSimulation()
            self.refresh()
            self._sync()
        self.step_count += 1

    @property
    def colliders(self) -> Colliders:
        """The rigid bodies as the tissue sees them, read from pybullet after the last step."""
        if self._stale:
            self.refresh()
        return self._colliders

    def refresh(self) -> None:
        """Re-read every rigid slot's pose and velocity from pybullet (after a step or a reset)."""
        c = self._colliders
        self._reader.read(c.rigid_x, c.rigid_q, c.rigid_v, c.rigid_w)
        self._joints.read(c.rigid_q, c.rigid_axis, c.rigid_force)
        self._stale = False

    def position(self, slot: int) -> tuple[float, float, float] | np.ndarray:
        """Slot ``slot``'s centre of mass now [m]: one pybullet query where the rigid states are not
        read yet (a world without tissue between steps), else the row already read. The same
        numbers either way (the query ``refresh`` makes for that slot)."""
        if not self._stale:
            return self._colliders.rigid_x[slot]
        return self._reader.position(slot)

    def set_mass_properties(self, slot: int) -> None:
        """Read slot ``slot``'s mass and inertia from pybullet again, after a changeDynamics."""
        inv_m, inv_i = read_mass_properties(self.client, [self.rigid[slot]])
        self._colliders.rigid_inv_mass[slot] = inv_m[0]
        self._colliders.rigid_inv_inertia[slot] = inv_i[0]

    def _sync(self) -> None:
        m, s, c = self.model, self.state, self._colliders
        sync_attached(m.particle_rest_x, m.particle_rest_q, m.particle_attached, m.particle_body, m.body_core_shape,
                      c.shape_rigid, c.rigid_x, c.rigid_q, c.rigid_v, c.rigid_w, s.particle_x, s.particle_v,
                      s.particle_q, s.particle_omega)  # fmt: skip

    # --- queries ------------------------------------------------------------------------------------

    def penetration(self) -> tuple[float, float]:
        """(deepest tissue overlap with other rigid shapes, deepest intrusion into own core) [m]."""
        if self.solver is None:
            return 0.0, 0.0
        return self.solver.penetration(self.state, self.colliders)

    def tissue_deviation(self) -> float:
        """Largest distance of a particle from its rest spot carried rigidly by its core [m]: how far
        the tissue is deformed (or torn away) anywhere; 0 without tissue."""
        if self.state is None:
            return 0.0
        m, c = self.model, self.colliders
        return _largest_deviation(self.state.particle_x, m.particle_rest_x, m.body_particle_offsets, self._core_rigid,
                                  c.rigid_x, c.rigid_q)  # fmt: skip

    def is_finite(self) -> bool:
        c = self.colliders
        ok = bool(np.isfinite(c.rigid_x).all() and np.isfinite(c.rigid_v).all())
        return ok and (self.state is None or self.state.is_finite())

    # --- save / restore -----------------------------------------------------------------------------

    def save(self) -> tuple[int, TissueState | None, int]:
        """Snapshot of the whole world (pybullet bodies and tissue)."""
        sid = self.client.saveState()
        return sid, (None if self.state is None else self.state.copy()), self.step_count

    def restore(self, snap: tuple[int, TissueState | None, int]) -> None:
        sid, tissue, steps = snap
        self.client.restoreState(stateId=sid)
        if tissue is not None:
            self.state.assign(tissue)
        self.step_count = steps
        self.refresh()


@nb.njit(cache=True)
def _largest_deviation(x, rest_x, offsets, core_rigid, rigid_x, rigid_q):
    """World.tissue_deviation's loop, compiled (it runs once per env step, for the divergence
    check): each particle's distance from its rest spot carried by its body's core; inf if any
    is not finite (NaN would slip through a max)."""
    worst = 0.0
    for b in range(offsets.shape[0] - 1):
        r = core_rigid[b]
        qx, qy, qz, qw = rigid_q[r, 0], rigid_q[r, 1], rigid_q[r, 2], rigid_q[r, 3]
        r00, r01, r02 = 1.0 - 2.0 * (qy * qy + qz * qz), 2.0 * (qx * qy - qz * qw), 2.0 * (qx * qz + qy * qw)
        r10, r11, r12 = 2.0 * (qx * qy + qz * qw), 1.0 - 2.0 * (qx * qx + qz * qz), 2.0 * (qy * qz - qx * qw)
        r20, r21, r22 = 2.0 * (qx * qz - qy * qw), 2.0 * (qy * qz + qx * qw), 1.0 - 2.0 * (qx * qx + qy * qy)
        for i in range(offsets[b], offsets[b + 1]):
            a0, a1, a2 = rest_x[i, 0], rest_x[i, 1], rest_x[i, 2]
            d0 = x[i, 0] - (r00 * a0 + r01 * a1 + r02 * a2 + rigid_x[r, 0])
            d1 = x[i, 1] - (r10 * a0 + r11 * a1 + r12 * a2 + rigid_x[r, 1])
            d2 = x[i, 2] - (r20 * a0 + r21 * a1 + r22 * a2 + rigid_x[r, 2])
            d = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            if not math.isfinite(d):
                return math.inf
            worst = max(worst, d)
    return worst
