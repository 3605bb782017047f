"""The grip-force task, a composition over the carry test: hold and carry the cylinder
with the least squeeze.

The cylinder's mass and friction are drawn per episode and not observed (the ids' ranges make the
force that holds it vary 18-fold); the action's last entry sets the squeeze (``finger_action=
"force"``). The reward pays the lift and charges the squeeze: ``squeeze = -squeeze_weight *
mean(force_left, force_right) / reference`` is added to the wrapped task's reward (its own term
in ``info["reward_terms"]``), so a policy that holds harder than it must pays for it at every step.
The reference is the finger's full force (``squeeze_reference="finger_force"``: a newton costs the
same on every cylinder) or the episode's static least force m g / (2 mu_s) (``"least"``: a margin
over the least costs the same on every cylinder, and over constant grips the tissue's expected
return is highest at 1.2-1.5 times the least; the package's documentation, Results: where the grip
reward peaks).

Success is the carry test's (held at every env step of the carry, its in-hand slide within the
limit) and the carry's mean squeeze - the mean over its env steps of the two fingers' mean normal
force - at most ``squeeze_factor`` times the least force that holds this cylinder through this
carry, from Coulomb's law with the accelerations the cylinder had:

    F_least = m max_t |(a(t) + g) minus its component along the jaw axis| / (2 mu_s)

Two fingers pressing with F each give at most 2 mu_s F of friction; friction must carry what the
cylinder's weight and acceleration ask for across the jaw axis (along it, the normal forces carry
it). ``a(t)`` is the cylinder's acceleration over each env step of the carry, the difference of its
velocities at the step's two ends (20 Hz: a 3 Hz sway's peak reads sin(x)/x = 0.96 of itself, its
share of |a + g| being 10 % at most). The measure is point Coulomb: a soft pad that wraps the
cylinder holds with less (its normals tilt around the curve and sum to more than the squeeze;
the package's documentation, Results: tactile pads and the grip-force task, measures how much),
which counts as success too.

``info`` carries ``carry_squeeze`` (the carry's mean squeeze so far) and ``least_squeeze`` (F_least
so far) [N], both 0 before the carry (not NaN: Gymnasium's checker and users compare infos by
equality).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from .base import Outcome, TaskWrapper
from .carry import CarryTest

if TYPE_CHECKING:
    from ..observation import Reading
    from ..scene import GraspScene

GRAVITY = np.array([0.0, 0.0, -9.81])
"""pybullet's gravity in every scene [m/s^2] (scene/scene.py sets it)."""
GRIP_INFO = ("carry_squeeze", "least_squeeze")
"""The entries the grip-force task adds to ``info`` [N]."""
SQUEEZE_REFERENCES = ("finger_force", "least")
"""What the squeeze charge divides the squeeze by (:class:`GripForceTask`): the finger's full force,
or the episode's static least force m g / (2 mu_s)."""
SQUEEZE_CHARGE_STEPS = ("all", "carry")
"""Which env steps the squeeze is charged on (:class:`GripForceTask`): every one, or only the
carry's (the task's least force is the carry's, so only the squeeze held through it is judged;
closing and lifting cost nothing)."""


def least_squeeze(mass: float, mu_s: float, accelerations: np.ndarray, jaw_axis: np.ndarray) -> float:
    """The least normal force per finger [N] with which two fingers on either side of a body of
    ``mass`` [kg], with friction ``mu_s``, hold it through ``accelerations`` ((n, 3) [m/s^2]) with
    their normals along the unit ``jaw_axis`` (n, 3) or (3,): Coulomb, 2 mu_s F >= m |a - g| off
    the axis at every instant (module docstring)."""
    need = np.asarray(accelerations, dtype=np.float64) - GRAVITY  # what the fingers must supply, per kg
    axis = np.asarray(jaw_axis, dtype=np.float64)
    along = np.sum(need * axis, axis=-1, keepdims=True) * axis
    across = np.linalg.norm(need - along, axis=-1)
    return float(mass * across.max() / (2.0 * mu_s)) if across.size else 0.0


class GripForceTask(TaskWrapper):
    """``carry`` (a :class:`CarryTest`) judged as the grip-force task (module docstring):
    ``squeeze_weight`` charges the squeeze in the reward, per env step, ``squeeze_weight * F /
    reference`` with F the fingers' mean normal force and the reference ``squeeze_reference``:
    ``"finger_force"`` (``finger_force`` [N], the squeeze at full action) or ``"least"`` (the
    episode's static least force m g / (2 mu_s), so the charge is in least forces and the same
    grip margin costs the same on every cylinder); ``squeeze_factor`` (None: the carry's success
    alone) bounds the carry's mean squeeze by that many times the least that holds.
    ``squeeze_charge_steps`` ("all" or "carry") is which env steps pay the charge: every one, or
    only the carry's; ``squeeze_free`` is the part of the squeeze, in references, that costs
    nothing: the charge is ``squeeze_weight * max(0, F / reference - squeeze_free)`` (with the
    least force as the reference, 1 charges only the margin over it)."""

    def __init__(self, carry: CarryTest, *, squeeze_weight: float, squeeze_factor: float | None,
                 finger_force: float, squeeze_reference: str = "finger_force",
                 squeeze_charge_steps: str = "all", squeeze_free: float = 0.0) -> None:  # fmt: skip
        if not isinstance(carry, CarryTest):
            raise TypeError(f"GripForceTask wraps a CarryTest (its accelerations judge the squeeze), got {carry!r}")
        if squeeze_reference not in SQUEEZE_REFERENCES:
            raise ValueError(f"squeeze_reference must be one of {SQUEEZE_REFERENCES}, got {squeeze_reference!r}")
        if squeeze_charge_steps not in SQUEEZE_CHARGE_STEPS:
            raise ValueError(f"squeeze_charge_steps must be one of {SQUEEZE_CHARGE_STEPS}, got {squeeze_charge_steps!r}")
        self.squeeze_reference = squeeze_reference
        self.squeeze_charge_steps = squeeze_charge_steps
        if not (math.isfinite(squeeze_free) and squeeze_free >= 0.0):
            raise ValueError(f"squeeze_free must be a finite number >= 0, got {squeeze_free!r}")
        self.squeeze_free = float(squeeze_free)
        super().__init__(carry)
        self.reward_terms = carry.reward_terms + ("squeeze",)
        self.info_keys = carry.info_keys + GRIP_INFO
        self.squeeze_weight = float(squeeze_weight)
        self.squeeze_factor = None if squeeze_factor is None else float(squeeze_factor)
        self.finger_force = float(finger_force)
        self._begun(None)

    def _begun(self, scene: GraspScene | None) -> None:
        self.mass = math.nan if scene is None else float(scene.config.cylinder_mass)
        self.mu_s = math.nan if scene is None else float(scene.config.tissue.friction_static)
        # the charge's unit of squeeze [N]
        self.reference = (self.finger_force if self.squeeze_reference == "finger_force"
                          else self.mass * -GRAVITY[2] / (2.0 * self.mu_s))  # fmt: skip
        self._prev: tuple[float, np.ndarray] | None = None  # (time, cylinder velocity) of the last reading
        self.least = 0.0
        """The least squeeze that holds through the carry so far [N] (0 before it): the largest of
        each carry step's least."""
        self._squeeze_sum, self._squeeze_n = 0.0, 0

    def begin(self, scene: GraspScene, rng: np.random.Generator) -> None:
        self.task.begin(scene, rng)
        self._begun(scene)

    @property
    def carry_squeeze(self) -> float:
        """The carry's mean squeeze so far [N] (0 before it)."""
        return self._squeeze_sum / self._squeeze_n if self._squeeze_n else 0.0

    def evaluate(self, reading: Reading, scene: GraspScene) -> Outcome:
        out = self.task.evaluate(reading, scene)
        squeeze = float(np.mean(reading.force))
        steps = scene.steps
        in_carry = self.task.phase(steps) is not None
        if self._prev is not None and in_carry and reading.time > self._prev[0]:
            acceleration = (reading.cyl_v - self._prev[1]) / (reading.time - self._prev[0])
            yaw = reading.gripper_yaw
            axis = np.array([math.cos(yaw), math.sin(yaw), 0.0])  # the closing axis
            self.least = max(self.least, least_squeeze(self.mass, self.mu_s, acceleration[None], axis))
            self._squeeze_sum += squeeze
            self._squeeze_n += 1
        self._prev = (reading.time, reading.cyl_v.copy())
        charged = in_carry or self.squeeze_charge_steps == "all"
        term = -self.squeeze_weight * max(0.0, squeeze / self.reference - self.squeeze_free) if charged else 0.0
        success = out.success
        least, mean = self.least, self.carry_squeeze
        if success and self.squeeze_factor is not None:
            success = bool(mean <= self.squeeze_factor * least)
        return replace(out, reward=out.reward + term, terms={**out.terms, "squeeze": term}, success=success,
                       info={**out.info, "carry_squeeze": mean, "least_squeeze": least})  # fmt: skip


def __getattr__(name: str):
    if name == "LeastSqueeze":  # the class's name before 0.7
        from ..validation import deprecated

        deprecated("softgrasp_env.tasks.grip.LeastSqueeze", "GripForceTask", stacklevel=3)
        return GripForceTask
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["GRIP_INFO", "SQUEEZE_CHARGE_STEPS", "SQUEEZE_REFERENCES", "GripForceTask", "least_squeeze"]
