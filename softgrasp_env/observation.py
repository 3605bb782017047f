"""The observation: what the env reads off the scene once per env step, every entry by name.

:func:`read` takes a :class:`Reading` of a scene; ``Reading.vector(names)`` is the observation
vector in the order of ``names`` (``OBS_NAMES``, or ``CARRY_OBS_NAMES`` with the carry test's
clock). Tasks read the same :class:`Reading` by name: nothing indexes the observation by number.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .fingers.tactile import TAXEL_CHANNELS, TaxelGrid
from .scene.objects import OBJECT_KINDS

if TYPE_CHECKING:
    from .scene import GraspScene, SceneConfig

OBS_GROUPS: dict[str, tuple[str, ...]] = {
    "grip": ("grip_x", "grip_y", "grip_z"),
    "grip_v": ("grip_vx", "grip_vy", "grip_vz"),
    "finger_gap": ("finger_gap",),
    "cyl_rel": ("cyl_rel_x", "cyl_rel_y", "cyl_rel_z"),
    "cyl_axis": ("cyl_axis_x", "cyl_axis_y", "cyl_axis_z"),
    "cyl_v": ("cyl_vx", "cyl_vy", "cyl_vz"),
    "cyl_w": ("cyl_wx", "cyl_wy", "cyl_wz"),
    "force": ("force_left", "force_right"),
    "lift": ("lift",),
    "gripper_yaw": ("gripper_yaw",),
    "time": ("time",),
    "shape_kind": tuple(f"shape_{k}" for k in OBJECT_KINDS),
    "shape_extent": ("shape_extent_x", "shape_extent_y", "shape_extent_z"),
}
"""Each field of a :class:`Reading` and the observation entries it fills, in observation order."""

SHAPE_GROUPS: tuple[str, ...] = ("shape_kind", "shape_extent")
"""The groups that describe the grasped object's shape (``observe_shape``, on when the env is made with
``object=``): its kind one-hot (softgrasp_env.scene.objects.OBJECT_KINDS) and its half extents at rest."""
SHAPE_OBS_NAMES: tuple[str, ...] = tuple(n for g in SHAPE_GROUPS for n in OBS_GROUPS[g])
"""The shape description's entries: they follow the clock (if any) and precede the taxels."""
OBS_NAMES: tuple[str, ...] = tuple(n for g, names in OBS_GROUPS.items() if g != "time" and g not in SHAPE_GROUPS
                                   for n in names)  # fmt: skip
"""Names of the observation entries, in order (the env card documents each)."""
CARRY_OBS_NAMES: tuple[str, ...] = OBS_NAMES + ("time",)
"""With the carry test (``carry=True``) the observation ends with the time since
reset [s]: the carry comes at a fixed time, and a policy that cannot see the clock would face a
task that is not Markov."""


OBJECT_GROUPS: tuple[str, ...] = ("cyl_rel", "cyl_axis", "cyl_v", "cyl_w", "lift")
"""The groups that observe the cylinder itself, its pose and motion: ``observe_object=False`` (the
grip-force ids) leaves them out, keeping what a gripper's own sensors give - its pose and velocity,
its fingers' gap and forces, the clock, the taxels."""


_OBJECT_NAMES: tuple[str, ...] = tuple(n for g in OBJECT_GROUPS for n in OBS_GROUPS[g])
PRIVILEGED_NAMES: tuple[str, ...] = (*_OBJECT_NAMES,
                                     "object_qx", "object_qy", "object_qz", "object_qw",
                                     "object_mass", "friction_static", "friction_kinetic")  # fmt: skip
"""What :func:`privileged` returns, in order: the object's own state (the entries of
:data:`OBJECT_GROUPS`: its centre from the grip point [m], its up axis, velocities [m/s, rad/s], lift
[m]), its orientation quaternion (x, y, z, w), its mass [kg] and the finger surface's friction
coefficients mu_s, mu_k as this episode drew them. A simulator knows them; a gripper's own sensors
do not: an asymmetric critic reads them in training, the actor never
(``softgrasp_env.wrappers.PrivilegedObservation``)."""


def privileged(reading: Reading, config: SceneConfig) -> np.ndarray:
    """The :data:`PRIVILEGED_NAMES` entries of ``reading`` and the scene's ``config``, float64."""
    mu_s = config.tissue.friction_static
    mu_k = mu_s if config.tissue.friction_kinetic is None else config.tissue.friction_kinetic
    return np.concatenate((reading.vector(_OBJECT_NAMES), reading.object_q,
                           (config.cylinder_mass, mu_s, mu_k)))  # fmt: skip


def without_object(names: tuple[str, ...]) -> tuple[str, ...]:
    """``names`` without the entries of :data:`OBJECT_GROUPS`."""
    return tuple(n for n in names if n not in _OBJECT_NAMES)


TACTILE_PREFIX = "tactile_"
"""Every tactile entry's name starts with it (``tactile=(rows, cols)``: :func:`tactile_names`)."""


def tactile_names(rows: int, cols: int, frames: int = 1) -> tuple[str, ...]:
    """The names of a tactile observation's entries, ``tactile_<left|right>_r<row>_c<col>_<channel>``,
    in the order of the reading's (2, rows, cols, channels) array flattened (C order):
    fingers/tactile.py says what each channel is. With ``frames`` > 1 (``tactile_history``) the
    frames of the env steps before follow, ``tactile_past<d>_...`` d steps back, d = 1 .. frames - 1."""
    return tuple(f"{TACTILE_PREFIX}{'' if d == 0 else f'past{d}_'}{side}_r{r}_c{c}_{ch}" for d in range(frames)
                 for side in ("left", "right") for r in range(rows) for c in range(cols)
                 for ch in TAXEL_CHANNELS)  # fmt: skip


@functools.lru_cache(maxsize=64)
def _tactile_layout(names: tuple[str, ...]) -> tuple[int, int, int, int]:
    """(start, frames, rows, cols) of the taxel entries of an observation of ``names``."""
    start = next((k for k, n in enumerate(names) if n.startswith(TACTILE_PREFIX)), None)
    if start is None:
        raise ValueError("the observation has no tactile entries (make the env with tactile=(rows, cols))")
    last = f"{TACTILE_PREFIX}right_r"
    end = max(k for k, n in enumerate(names) if n.startswith(last))  # the current frame's last entry
    parts = names[end][len(last) - 1 :].split("_")  # r<R-1>, c<C-1>, <channel...>
    rows, cols = int(parts[0][1:]) + 1, int(parts[1][1:]) + 1
    per_frame = 2 * rows * cols * len(TAXEL_CHANNELS)
    frames = sum(1 for n in names if n.startswith(TACTILE_PREFIX)) // per_frame
    return start, frames, rows, cols


def tactile_view(obs: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """The tactile part of an observation ``obs`` of ``names`` (``env.obs_names``; the last axis
    of a batch of observations) as its (..., 2, rows, cols, channels) grid: this env step's taxels
    (:func:`tactile_frames` for the earlier ones of ``tactile_history``)."""
    return tactile_frames(obs, names)[..., 0, :, :, :, :]


def tactile_frames(obs: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """The taxels of an observation ``obs`` of ``names`` as (..., frames, 2, rows, cols, channels):
    frame 0 this env step's, frame d the one d env steps before (``tactile_history`` frames; a new
    episode's first observation repeats its own)."""
    start, frames, rows, cols = _tactile_layout(tuple(names))
    obs = np.asarray(obs)
    return obs[..., start : start + frames * 2 * rows * cols * len(TAXEL_CHANNELS)].reshape(
        (*obs.shape[:-1], frames, 2, rows, cols, len(TAXEL_CHANNELS)))  # fmt: skip


def obs_slice(names: tuple[str, ...], group: str) -> slice:
    """Where the entries of ``group`` (a key of OBS_GROUPS) sit in an observation of ``names``."""
    members = OBS_GROUPS[group]
    start = names.index(members[0])
    return slice(start, start + len(members))


@dataclass(frozen=True, eq=False)
class Reading:
    """The scene as the env sees it after an env step, in SI units, world frame (z up)."""

    grip: np.ndarray
    """(3,) grip point: the midpoint of the two finger cores [m]."""
    grip_v: np.ndarray
    """(3,) the palm's linear velocity [m/s]."""
    finger_gap: float
    """Distance between the finger cores' inner faces [m]."""
    cyl_rel: np.ndarray
    """(3,) cylinder centre minus grip point [m]."""
    cyl_axis: np.ndarray
    """(3,) the cylinder's axis, a unit vector (its orientation up to its symmetry)."""
    cyl_v: np.ndarray
    """(3,) the cylinder's linear velocity [m/s]."""
    cyl_w: np.ndarray
    """(3,) the cylinder's angular velocity [rad/s]."""
    force: np.ndarray
    """(2,) normal force each finger (left, right) pressed on the cylinder with, mean over the env
    step [N]."""
    lift: float
    """The cylinder centre's height above its resting height [m]."""
    gripper_yaw: float
    """The palm's yaw [rad]."""
    time: float
    """Time since reset [s]."""
    cylinder_x: np.ndarray
    """(3,) the cylinder centre [m] (not observed as such: the workspace check reads it)."""
    tactile: np.ndarray | None = None
    """(2, rows, cols, channels) the pads' taxels (fingers/tactile.py), when the env reads them
    (``tactile=(rows, cols)``)."""
    tactile_past: np.ndarray | None = None
    """(frames - 1, 2, rows, cols, channels) the taxels of the env steps before, the last first
    (``tactile_history``; the env keeps them)."""
    shape_kind: np.ndarray | None = None
    """(len(OBJECT_KINDS),) the object's kind, one-hot."""
    shape_extent: np.ndarray | None = None
    """(3,) the object's half extents at rest along x, y, z [m] (half its bounding box)."""
    object_q: np.ndarray | None = None
    """(4,) the object's orientation, a unit quaternion (x, y, z, w) from its rest frame (not
    observed: :data:`PRIVILEGED_NAMES`)."""
    object_tilt: float | None = None
    """The tilt of an object other than the cylinder (scene.GraspScene.cylinder_tilt: a sphere
    has none, a lying capsule's is its axis from the horizontal); None: the cylinder's, from
    its axis."""

    @property
    def tilt(self) -> float:
        """Angle of the cylinder's axis from the vertical [rad] (another object's own tilt:
        :attr:`object_tilt`)."""
        if self.object_tilt is not None:
            return self.object_tilt
        z = float(self.cyl_axis[2])
        # np.clip's value in Python floats (a scalar through numpy costs ~3 us, and every env
        # step reads this twice); a NaN stays NaN as np.clip leaves it
        return math.acos(z if z != z else (-1.0 if z < -1.0 else (1.0 if z > 1.0 else z)))

    def vector(self, names: tuple[str, ...]) -> np.ndarray:
        """The observation of ``names`` (whole groups of OBS_GROUPS, in their order), float64."""
        values: list[float] = []
        for g in _groups_of(tuple(names)):
            v = getattr(self, g)
            if isinstance(v, np.ndarray):
                values.extend(v.ravel().tolist())
            else:
                values.append(float(v))
        out = np.array(values, dtype=np.float64)
        if names and names[-1].startswith(TACTILE_PREFIX):  # the taxels come last, then the earlier frames
            out = np.concatenate((out, self.tactile.ravel()))
            if self.tactile_past is not None:
                out = np.concatenate((out, self.tactile_past.ravel()))
        return out


@functools.lru_cache(maxsize=64)
def _groups_of(names: tuple[str, ...]) -> tuple[str, ...]:
    """The groups of OBS_GROUPS whose entries ``names`` holds, in their order."""
    return tuple(g for g, members in OBS_GROUPS.items() if members[0] in names)


def read(scene: GraspScene, force: np.ndarray, grid: TaxelGrid | None = None) -> Reading:
    """A :class:`Reading` of ``scene`` now; ``force`` is the env step's mean finger force; with a
    ``grid``, the pads' taxels on it too."""
    grip = scene.grip_point()
    palm_x, palm_q, palm_v, _ = scene.palm_state()
    cyl_x, cyl_q, cyl_v, cyl_w = scene.cylinder_state()
    x, y, z, w = cyl_q
    object_tilt = None
    if scene.object_geometry is None:
        axis = np.array([2.0 * (x * z + y * w), 2.0 * (y * z - x * w), 1.0 - 2.0 * (x * x + y * y)])
    else:  # the object's up direction at rest, where it points now
        axis = scene.object_up(cyl_q)
        object_tilt = scene.object_tilt(cyl_q)
    px, py, pz, pw = palm_q
    yaw = math.atan2(2.0 * (pw * pz + px * py), 1.0 - 2.0 * (py * py + pz * pz))
    gap = 2.0 * scene.config.finger_stroke - float(scene.finger_closing().sum())
    kind, extent = scene.shape_description
    return Reading(grip=grip, grip_v=palm_v.copy(), finger_gap=gap, cyl_rel=cyl_x - grip, cyl_axis=axis,
                   cyl_v=cyl_v.copy(), cyl_w=cyl_w.copy(), force=np.array(force, dtype=np.float64),
                   lift=float(cyl_x[2] - scene.cylinder_rest_z), gripper_yaw=yaw,
                   time=scene.steps * scene.config.sim.dt, cylinder_x=cyl_x.copy(),
                   tactile=None if grid is None else scene.fingers.tactile(grid), shape_kind=kind,
                   shape_extent=extent, object_q=np.array(cyl_q, dtype=np.float64),
                   object_tilt=object_tilt)  # fmt: skip


__all__ = ["CARRY_OBS_NAMES", "OBJECT_GROUPS", "OBS_GROUPS", "OBS_NAMES", "PRIVILEGED_NAMES", "SHAPE_GROUPS", "SHAPE_OBS_NAMES",
           "TACTILE_PREFIX", "Reading", "obs_slice",
           "privileged", "read", "tactile_frames", "tactile_names", "tactile_view", "without_object"]  # fmt: skip
