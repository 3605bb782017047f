"""The lift task both starts share: pick the cylinder up to the success height and hold it.

Reward terms (Gymnasium v5 style, each in ``info["reward_terms"]``): ``lift`` = clip(lift height /
success height, 0, 1), the task itself (1 once the cylinder is 5 cm up), and ``reach`` =
-reach_weight * min(d, 0.1 m) / 0.1 m with d the grip point's distance to the cylinder centre
(small shaping). ``reward_type="dense"`` pays ``lift + reach``; ``"sparse"`` pays 1 on steps where
the cylinder is held, else 0. Held: lifted to the success height, both fingers pressing with at
least MIN_GRIP_FORCE, tilted no more than ``max_tilt``. The episode terminates when the cylinder
is knocked over (tilted past ``max_tilt``) or leaves the workspace.

The start is drawn per episode around ``base`` over :class:`StartRanges`; the reach and the easy
task (reach.py, easy.py) differ in where the gripper starts.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ..scene.config import scale_friction
from ..scene.gripper import WORKSPACE_HALF_WIDTH
from ..validation import check_range, is_real
from .base import Outcome, Task

if TYPE_CHECKING:
    from ..observation import Reading
    from ..scene import GraspScene, SceneConfig

MIN_GRIP_FORCE = 0.05
"""Each finger presses at least this hard on a held cylinder [N]."""
REACH_SCALE = 0.1
"""The reach term is -reach_weight from this distance on [m]."""
LOWEST = -0.01
"""A cylinder centre below this height has left the workspace through the ground [m]."""
HIGHEST = 0.5
"""A cylinder centre above this height has left the workspace [m]."""

RESET_OPTIONS = ("cylinder_xy", "lateral_offset", "yaw", "jaw_wedge", "friction_scale", "cylinder_radius",
                 "cylinder_mass", "gripper_xy", "object_scale")  # fmt: skip
"""Keys ``reset(options=...)`` accepts: each fixes a quantity that is otherwise randomised."""


@dataclass(frozen=True)
class StartRanges:
    """Half widths of the start's randomisation (each drawn uniformly, per episode)."""

    cylinder_position: float
    """Cylinder centre in x and y: U(+-cylinder_position) [m]."""
    lateral_offset: float
    """Palm offset along y (the faces' long direction): U(+-lateral_offset) [m]."""
    yaw: float
    """Palm yaw: U(+-yaw) [rad]."""
    jaw_wedge: float
    """Angle between the finger faces: U(+-jaw_wedge) [rad]."""
    friction: float
    """Every friction coefficient scaled by U(1 +- friction) [-]."""
    cylinder_radius: float
    """Cylinder radius: base +- U(cylinder_radius) [m]."""
    cylinder_mass: float
    """Cylinder mass: base x U(1 +- cylinder_mass) [-]."""
    objects: tuple = ()
    """The objects (scene.objects.ObjectShape) an episode's object is drawn from, each as likely,
    after the draws above; () keeps the base scene's."""
    object_scale: float = 0.0
    """The object's size (every dimension) scaled by U(1 +- object_scale) [-], a draw of its own
    after the object's (none when 0, so a start without it draws as before)."""

    def __post_init__(self) -> None:
        # each named by its gym.make keyword (``yaw_range``), the only place these come from
        for name, hi in (("cylinder_position", 0.08), ("lateral_offset", 0.05), ("yaw", math.pi / 4),
                         ("jaw_wedge", math.pi / 6), ("friction", 0.9), ("cylinder_radius", 0.02),
                         ("cylinder_mass", 0.9), ("object_scale", 0.5)):  # fmt: skip
            check_range(f"{name}_range", getattr(self, name), 0.0, hi)


def check_option(name: str, value: Any):
    """A reset option as the scene takes it: ``cylinder_xy`` / ``gripper_xy`` two finite numbers
    (a tuple), every other option one finite number; else a TypeError / ValueError naming it."""
    if name in ("cylinder_xy", "gripper_xy"):
        if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__len__") or len(value) != 2 \
                or not all(is_real(x) for x in value):  # fmt: skip
            raise TypeError(f"reset option {name!r} must be two numbers (x, y) in m, got {value!r}")
        out = tuple(float(x) for x in value)
        if not all(math.isfinite(x) for x in out):
            raise ValueError(f"reset option {name!r} must be finite, got {value!r}")
        return out
    if not is_real(value):
        raise TypeError(f"reset option {name!r} must be a number, got {type(value).__name__}: {value!r}")
    if not math.isfinite(float(value)):
        raise ValueError(f"reset option {name!r} must be finite, got {value!r}")
    return float(value)


class LiftTask(Task):
    """Lift the cylinder to ``success_height`` and hold it (see the module docstring)."""

    defaults: ClassVar[dict[str, float | bool]] = {}
    """The ranges (and whether the carry test is on) a start defaults to: ``cylinder_position``,
    ``yaw``, ``jaw_wedge``, ``carry``."""
    reward_terms = ("lift", "reach")
    reset_options = RESET_OPTIONS

    def __init__(self, ranges: StartRanges, *, success_height: float, reach_weight: float, max_tilt: float,
                 reward_type: str) -> None:  # fmt: skip
        self.ranges = ranges
        self.success_height = float(success_height)
        self.reach_weight = float(reach_weight)
        self.max_tilt = float(max_tilt)
        self.reward_type = reward_type

    # --- the start -------------------------------------------------------------------------------

    def gripper_xy(self, u: tuple[float, float]) -> tuple[float, float]:
        """Where the grip starts horizontally, from two U(-1, 1) draws (drawn whether used or not)."""
        return (0.0, 0.0)

    def draw(self, rng: np.random.Generator, options: Mapping[str, Any], base: SceneConfig) -> SceneConfig:
        rg = self.ranges
        u = rng.uniform(-1.0, 1.0, size=10)
        vals = {
            "cylinder_xy": (float(u[0] * rg.cylinder_position), float(u[1] * rg.cylinder_position)),
            "lateral_offset": float(u[2] * rg.lateral_offset),
            "yaw": float(u[3] * rg.yaw),
            "jaw_wedge": float(u[4] * rg.jaw_wedge),
            "friction_scale": float(1.0 + u[5] * rg.friction),
            "cylinder_radius": float(base.cylinder_radius + u[6] * rg.cylinder_radius),
            "cylinder_mass": float(base.cylinder_mass * (1.0 + u[7] * rg.cylinder_mass)),
            "gripper_xy": self.gripper_xy((float(u[8]), float(u[9]))),
        }
        if rg.objects:  # a draw of its own, after the others: the ids without a set draw as before
            vals["object"] = rg.objects[int(rng.integers(len(rg.objects)))]
        if rg.object_scale:  # likewise, after the object's
            vals["object_scale"] = float(1.0 + rng.uniform(-1.0, 1.0) * rg.object_scale)
        vals.update(options)  # checked and converted by check_option
        fs = vals.pop("friction_scale")
        if not 0.0 < fs <= 10.0:
            raise ValueError(f"friction_scale must be in (0, 10], got {fs!r}")
        scale = vals.pop("object_scale", None)
        cfg = replace(base, **vals)
        if scale is not None:  # the episode's object (the cylinder included) at that size
            cfg = cfg.with_object(replace(cfg.object_shape, label=cfg.object_name).scaled(scale))
        return scale_friction(cfg, fs)  # the task's start height is base's

    # --- the verdict -----------------------------------------------------------------------------

    def held(self, reading: Reading) -> bool:
        """Lifted to the success height, both fingers pressing, not tilted beyond max_tilt."""
        upright = reading.tilt <= self.max_tilt
        f = reading.force
        return bool(reading.lift >= self.success_height and f[0] >= MIN_GRIP_FORCE and f[1] >= MIN_GRIP_FORCE
                    and upright)  # fmt: skip

    def knocked_over_or_gone(self, reading: Reading) -> bool:
        x = reading.cylinder_x
        if math.hypot(x[0], x[1]) > WORKSPACE_HALF_WIDTH or x[2] < LOWEST or x[2] > HIGHEST:
            return True
        return reading.tilt > self.max_tilt

    def terms(self, reading: Reading) -> dict[str, float]:
        lift = _unit_clip(reading.lift / self.success_height)
        d = float(np.linalg.norm(reading.cyl_rel))
        reach = -self.reach_weight * min(d / REACH_SCALE, 1.0)  # exactly -reach_weight from 10 cm on
        return {"lift": lift, "reach": reach}

    def evaluate(self, reading: Reading, scene: GraspScene) -> Outcome:
        terms = self.terms(reading)
        held = self.held(reading)
        reward = float(held) if self.reward_type == "sparse" else terms["lift"] + terms["reach"]
        return Outcome(held=held, success=held, terminated=self.knocked_over_or_gone(reading), reward=reward,
                       terms=terms)  # fmt: skip


def _unit_clip(v: float) -> float:
    """float(np.clip(v, 0, 1)) in Python floats (numpy on a scalar costs ~3 us); NaN stays NaN."""
    return v if v != v else (0.0 if v < 0.0 else (1.0 if v > 1.0 else float(v)))


__all__ = ["MIN_GRIP_FORCE", "RESET_OPTIONS", "LiftTask", "StartRanges", "check_option"]
