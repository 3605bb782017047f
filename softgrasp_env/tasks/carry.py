"""The carry test, a composition over the reach task: for the episode's last ``duration`` the
arm, not the policy, sways the palm, and success needs the cylinder held through it.

The sway is ``A sin(2 pi f t)`` about where the arm had the palm when the carry began, horizontal.
The policy's finger command still acts, its arm command is ignored meanwhile. The observation
gains the time since reset: the carry comes at a fixed time, and a policy that cannot see the
clock would face a task that is not Markov.

Every episode draws its sway: the frequency f from a band from below to above the two-point
grasp's pendulum frequency (about 1.9 Hz with the cylinder's own inertia), the peak acceleration
a = A (2 pi f)^2 from a range (the amplitude follows), and the direction, any horizontal one
(across the jaw, where a two-point grasp swings about the line through its contacts, along the
closing axis, or between). The sway ramps in over its first period (``A (t f) sin(2 pi f t)``: it
starts at rest, as the arm's path must) and keeps within the arm's speed and acceleration (checked
when the env is made). Success needs the cylinder held at every env step of the carry and its
in-hand slide (the cylinder's move relative to the grip point since the carry began) at most
``slide_limit``, not only at the last step: a grasp that swings out and back, or ratchets, has not
held. ``reset(options=...)`` fixes ``carry_frequency``, ``carry_acceleration`` and
``carry_direction`` (rad from across the jaw) for one episode.

The carry runs from 3.5 s (step 70 of the 100 at 20 Hz) for 1.5 s.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ..scene.gripper import GripperControl, Workspace
from .base import Outcome, Task, TaskWrapper

if TYPE_CHECKING:
    from ..observation import Reading
    from ..scene import GraspScene, SceneConfig

CARRY_START = 3.5
"""The carry begins this long after reset [s]."""
CARRY_DURATION = 1.5
"""How long the arm carries [s]."""
CARRY_FREQUENCY_BAND = (1.2, 3.0)
"""The sway's frequency band [Hz]: 0.6 to 1.6 times the two-point pendulum's ~1.9 Hz."""
CARRY_ACCELERATION_RANGE = (0.5, 1.0)
"""The sway's peak acceleration [m/s^2]: at 1.2 Hz 1.0 m/s^2 is 0.13 m/s at most, within the
arm's 0.15 m/s; the arm's 1.5 m/s^2 leaves room for the path's corrections."""
CARRY_SLIDE_LIMIT = 0.005
"""The success's largest in-hand slide during the carry [m]: the soft grasp slides 0.14 mm, aligned
rigid fingers 0.2-0.5 mm, a rigid two-point grasp swinging 5-37 deg 3-18 mm (scripted, 1 m/s^2 at
1.2-3 Hz)."""
CARRY_OPTIONS = ("carry_frequency", "carry_acceleration", "carry_direction")
"""Reset options that fix the sway for one episode."""
RAMP_ACCELERATION_FACTOR = math.sqrt(1.0 + 1.0 / math.pi**2)
"""The sway's peak acceleration while it ramps in, over its steady peak (sway_limits_error)."""
RAMP_SPEED_FACTOR = math.sqrt(1.0 + 1.0 / (4.0 * math.pi**2))
"""The sway's peak speed while it ramps in, over its steady peak (sway_limits_error)."""
_EPS = 1e-9
"""Slack on the carry's time window [s]: physics steps land on its ends up to rounding."""


def sway_limits_error(frequency: float, *, amplitude: float | None = None, acceleration: float | None = None,
                      speed: float, arm_acceleration: float) -> str | None:  # fmt: skip
    """What is wrong with a sway the arm cannot follow (None: it can): its peak speed or
    acceleration above the arm's ``speed`` / ``arm_acceleration``, the ramp over the first period
    included (:meth:`CarryTest.steer`: x = A (f t) sin(w t), w = 2 pi f, so x'' = A w (2 f cos -
    f t w sin) peaks at up to A w^2 sqrt(1 + 1/pi^2), 4.9 % above the steady A w^2, and x' at up
    to A w sqrt(1 + 1/(4 pi^2)), 1.3 % above A w). Otherwise the arm's path would clip the sway
    without a word."""
    omega = 2.0 * math.pi * frequency
    steady = acceleration if acceleration is not None else amplitude * omega * omega
    a = steady * RAMP_ACCELERATION_FACTOR
    v = steady / omega * RAMP_SPEED_FACTOR
    if a > arm_acceleration * (1 + 1e-12):
        return (f"peaks at {a:.3g} m/s^2 ({steady:.3g} steady, more while it ramps in), above the arm's "
                f"arm_acceleration={arm_acceleration:g} m/s^2")  # fmt: skip
    if v > speed * (1 + 1e-12):
        return (f"peaks at {v:.3g} m/s ({steady / omega:.3g} steady, more while it ramps in), above the arm's "
                f"arm_speed={speed:g} m/s")  # fmt: skip
    return None


def _value(option: str, value: float, lo: float, hi: float) -> float:
    if not lo <= value <= hi:
        raise ValueError(f"reset option {option!r} must be in [{lo:g}, {hi:g}], got {value!r}")
    return value


class CarryTest(TaskWrapper):
    """``task`` with the carry test after it (see the module docstring), from ``start_time`` for
    ``duration`` [s] after reset. ``frequency`` [Hz] and ``acceleration`` [m/s^2, peak] are a value or a
    (low, high) band drawn per episode, the direction any horizontal one, drawn; success needs the
    cylinder held at every step of the carry and its in-hand slide at most ``slide_limit`` [m].
    ``arm_speed`` [m/s] and ``arm_acceleration`` [m/s^2] are the arm's limits a reset option's sway
    is checked against (EnvArguments checks the bands against them when the env is made)."""

    def __init__(self, task: Task, *, dt: float, workspace: Workspace, start_time: float = CARRY_START,
                 duration: float = CARRY_DURATION,
                 frequency: float | tuple[float, float] = CARRY_FREQUENCY_BAND,
                 acceleration: float | tuple[float, float] = CARRY_ACCELERATION_RANGE,
                 slide_limit: float = CARRY_SLIDE_LIMIT, arm_speed: float = math.inf,
                 arm_acceleration: float = math.inf) -> None:  # fmt: skip
        super().__init__(task)
        self.observation_extras = task.observation_extras + ("time",)
        self.reset_options = task.reset_options + CARRY_OPTIONS
        self.dt = float(dt)
        self.workspace = workspace
        self.start_time, self.duration = float(start_time), float(duration)
        self.frequency_band = frequency
        self.acceleration_band = acceleration
        self.slide_limit = float(slide_limit)
        self.arm_speed, self.arm_acceleration = float(arm_speed), float(arm_acceleration)
        # this episode's sway (draw() sets it)
        self.frequency = float(frequency) if not isinstance(frequency, tuple) else float(np.mean(frequency))
        self.amplitude = 0.0
        self.angle = 0.0
        """The sway's direction from across the jaw toward the closing axis [rad]."""
        self._anchor: np.ndarray | None = None
        self._direction = np.zeros(3)  # the sway's, in the world (set with the anchor)
        self._rel0: np.ndarray | None = None
        self.slide = 0.0
        """The largest in-hand slide of this episode's carry so far [m]."""
        self.failed = False
        """The cylinder was not held at some step of this episode's carry, or slid too far."""
        # The physics steps whose end lies in the carry's window, exactly as phase() says (t grows
        # with the step, so the window is a range): found near the estimate, then checked step by
        # step, so that steer() needs no float arithmetic outside the window.
        first = max(0, math.floor((self.start_time - _EPS) / self.dt) - 2)
        while first <= math.floor((self.start_time - _EPS) / self.dt) + 3 and self.phase(first) is None:
            first += 1
        last = math.floor((self.start_time + self.duration + _EPS) / self.dt) + 2
        while last >= first and self.phase(last) is None:
            last -= 1
        self._first, self._last = first, last

    def draw(self, rng: np.random.Generator, options: Mapping[str, Any], base: SceneConfig) -> SceneConfig:
        """The wrapped task's draw, then this episode's sway: frequency and peak acceleration, each
        drawn only if it is a band, then the direction; a reset option replaces the drawn value."""
        mine = {k: options[k] for k in CARRY_OPTIONS if k in options}
        cfg = self.task.draw(rng, {k: v for k, v in options.items() if k not in mine}, base)
        f = self.frequency_band
        f = float(rng.uniform(*f)) if isinstance(f, tuple) else float(f)
        a = self.acceleration_band
        a = float(rng.uniform(*a)) if isinstance(a, tuple) else float(a)
        angle = float(rng.uniform(0.0, math.pi))
        if "carry_frequency" in mine:
            f = _value("carry_frequency", mine["carry_frequency"], 0.05, 10.0)
        if "carry_acceleration" in mine:
            a = _value("carry_acceleration", mine["carry_acceleration"], 0.0, 50.0)
        if "carry_direction" in mine:
            angle = _value("carry_direction", mine["carry_direction"], -math.pi, math.pi)
        omega = 2.0 * math.pi * f
        amplitude = a / (omega * omega)
        if mine:
            problem = sway_limits_error(f, amplitude=amplitude, speed=self.arm_speed,
                                        arm_acceleration=self.arm_acceleration)  # fmt: skip
            if problem:
                raise ValueError(f"reset options {mine}: the sway {problem}")
        self.frequency, self.amplitude, self.angle = f, float(amplitude), angle
        return cfg

    def begin(self, scene: GraspScene, rng: np.random.Generator) -> None:
        self.task.begin(scene, rng)
        self._anchor = None
        self._rel0 = None
        self.slide, self.failed = 0.0, False

    # --- the carry -------------------------------------------------------------------------------

    def phase(self, steps: int) -> float | None:
        """Seconds into the carry at the end of physics step ``steps`` (counted from reset), or
        None outside it."""
        t = steps * self.dt - self.start_time
        return t if -_EPS < t <= self.duration + _EPS else None

    def over(self, steps: int) -> bool:
        return steps * self.dt >= self.start_time + self.duration - _EPS

    def carrying(self, steps: int) -> bool:
        return self.phase(steps) is not None and not self.over(steps)

    def steer(self, scene: GraspScene, control: GripperControl) -> GripperControl:
        """During the carry the palm follows the sway about where the arm had it when the carry
        began; the finger command (closing and force) is the policy's."""
        n = scene.steps + 1  # the physics step about to run
        if n < self._first or n > self._last:
            return control
        t = self.phase(n)
        omega = 2.0 * math.pi * self.frequency
        if self._anchor is None:  # where the arm has the palm when the carry begins
            self._anchor = scene.palm_setpoint
            yaw = scene.config.yaw
            across = np.array([-math.sin(yaw), math.cos(yaw), 0.0])
            c, s = math.cos(self.angle), math.sin(self.angle)
            self._direction = across * c + np.array([math.cos(yaw), math.sin(yaw), 0.0]) * s
        direction = self._direction
        # ramped in over the first period: position and velocity start at 0 (the path starts at rest)
        ramp, ramp_rate = (t * self.frequency, self.frequency) if t * self.frequency < 1.0 else (1.0, 0.0)
        sin, cos = math.sin(omega * t), math.cos(omega * t)
        target = self._anchor + direction * (self.amplitude * ramp * sin)
        velocity = direction * (self.amplitude * (ramp_rate * sin + ramp * omega * cos))  # the sway's own: no lag
        # the policy's control keeps the workspace (palm_box): the arm brakes before its walls
        return GripperControl(target, control.finger_closing, palm_velocity=velocity, palm_box=control.palm_box,
                              finger_force=control.finger_force)  # fmt: skip

    def evaluate(self, reading: Reading, scene: GraspScene) -> Outcome:
        out = self.task.evaluate(reading, scene)
        steps = scene.steps
        over = self.over(steps)
        if self.phase(steps) is not None:  # held at every step of the carry, its ends included
            if self._rel0 is None:
                self._rel0 = np.array(reading.cyl_rel, dtype=np.float64)
            self.slide = max(self.slide, float(np.linalg.norm(reading.cyl_rel - self._rel0)))
            if not out.held or self.slide > self.slide_limit:
                self.failed = True
        success = over and out.held and self._rel0 is not None and not self.failed
        return replace(out, success=success, carrying=self.carrying(steps))


__all__ = ["CARRY_ACCELERATION_RANGE", "CARRY_DURATION", "CARRY_FREQUENCY_BAND", "CARRY_OPTIONS", "CARRY_SLIDE_LIMIT", "CARRY_START", "CarryTest", "sway_limits_error"]
