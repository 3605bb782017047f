"""Accuracy of a grasp, measured the same way for every finger kind: the scripted grasp and the
figures taken from it (penetration every step, in-hand slip, tilt), and the hold bound found by
bisection. The demo, the benchmarks and the tests all measure through this module.

Coulomb's law gives the reference: two fingers squeezing with normal force F hold a cylinder of
mass m without slipping iff 2 mu_s F >= m g (the load split evenly over both contact patches);
so the heaviest cylinder held is m* = 2 mu_s F / g, and below it the cylinder should not move in
the fingers at all.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .scene import GraspScene


@dataclass(frozen=True)
class GraspPlan:
    """Phases of the scripted grasp [s]. The lift follows a minimum-jerk profile (Flash & Hogan
    1985: s = 10 u^3 - 15 u^4 + 6 u^5), whose peak acceleration 5.77 d / T^2 adds ~3 % of g to the
    load for 5 cm in 1 s: the hold then tests the static bound, not a jerk at the start of the lift."""

    approach: float = 0.5
    squeeze: float = 0.6
    lift: float = 1.0
    hold: float = 2.0
    lift_distance: float = 0.05

    def __post_init__(self) -> None:
        for name in ("approach", "squeeze", "lift", "hold"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0.0):
                raise ValueError(f"GraspPlan.{name} must be a finite duration >= 0 s, got {v!r}")
        if not (isinstance(self.lift_distance, (int, float)) and 0.0 < self.lift_distance <= 0.15):
            raise ValueError(f"GraspPlan.lift_distance must be in (0, 0.15] m, got {self.lift_distance!r}")


@dataclass
class GraspRecord:
    """What one scripted grasp did. Lengths in m, angles in rad."""

    lift_height: float
    """Cylinder centre above its resting height at the end [m]."""
    min_lift_during_hold: float
    max_penetration: float
    """Deepest tissue overlap with any other rigid shape, checked after every step [m]."""
    max_core_intrusion: float
    """Deepest intrusion of an outer particle's centre into its own core, every step [m]."""
    max_tilt: float
    """Largest tilt of the cylinder's axis from the vertical during lift and hold [rad]."""
    tilt: float
    """Tilt at the end [rad]."""
    lift_slip: float
    """How far the cylinder centre moved in the palm's frame from the end of the squeeze to the
    end of the lift [m]: elastic sag of the tissue under the load plus any slip."""
    hold_slip: float
    """Largest distance of the cylinder centre, in the palm's frame, from where it was when the
    hold began [m]: slip in the hand (0 for a grasp that holds)."""
    hold_turn: float
    """Largest rotation of the cylinder relative to the palm since the hold began [rad]."""
    steps: int
    seconds: float
    """Wall time of the physics steps alone [s]."""
    finite: bool

    @property
    def steps_per_second(self) -> float:
        return self.steps / self.seconds if self.seconds > 0 else float("nan")

    def held(self, plan: GraspPlan, *, max_tilt: float = math.pi / 4) -> bool:
        """Lifted to at least 80 % of the commanded height, kept there through the hold, and never
        tilted beyond ``max_tilt`` (the env's success threshold): a cylinder that rotates out of
        the fingers is dropped, wherever its centre is."""
        need = 0.8 * plan.lift_distance
        return (
            self.finite and self.lift_height >= need and self.min_lift_during_hold >= need
            and self.max_tilt <= max_tilt
        )  # fmt: skip


    def holds_without_slip(self, plan: GraspPlan, *, max_slip: float = 1e-3, max_tilt: float = math.pi / 4) -> bool:
        """The hold bound's criterion: off the ground (at least half the commanded lift, whatever
        the tissue sagged under the load) and, once the load is static, not moving in the fingers:
        less than ``max_slip`` of slip through the hold. Above Coulomb's bound the cylinder slides
        all through the hold (mu_k < mu_s: once it slides, it keeps sliding)."""
        return (
            self.finite and self.min_lift_during_hold >= 0.5 * plan.lift_distance
            and self.hold_slip < max_slip and self.max_tilt <= max_tilt
        )  # fmt: skip


def _min_jerk(u: float) -> float:
    u = min(max(u, 0.0), 1.0)
    return u * u * u * (10.0 + u * (-15.0 + 6.0 * u))


def _relative_pose(scene: GraspScene) -> tuple[np.ndarray, np.ndarray]:
    """Cylinder pose in the palm's frame (position [m], quaternion [x, y, z, w])."""
    c = scene.client
    pp, pq = c.getBasePositionAndOrientation(scene.gripper)
    cp, cq = c.getBasePositionAndOrientation(scene.cylinder)
    ip, iq = c.invertTransform(pp, pq)
    rp, rq = c.multiplyTransforms(ip, iq, cp, cq)
    return np.asarray(rp), np.asarray(rq)


def _angle_between(q0: np.ndarray, q1: np.ndarray) -> float:
    d = abs(float(np.dot(q0, q1)))
    return 2.0 * math.acos(min(1.0, d))


def run_grasp(scene: GraspScene, plan: GraspPlan | None = None, *, on_step: Callable[[str], None] | None = None) -> GraspRecord:
    """Drive ``scene`` through approach, squeeze, lift and hold (fingers commanded past contact: the
    motors' force limit sets the squeeze) and measure it; ``on_step(phase)`` runs after every step."""
    plan = plan or GraspPlan()
    dt = scene.config.sim.dt
    world = scene.world
    start = scene.palm_target.copy()
    grasp = start.copy()
    grasp[2] = scene.grasp_height + scene.palm_offset
    close_to = scene.config.finger_max_opening

    def n_steps(duration: float) -> int:
        return int(round(duration / dt))

    phases = [("approach", n_steps(plan.approach)), ("squeeze", n_steps(plan.squeeze)),
              ("lift", n_steps(plan.lift)), ("hold", n_steps(plan.hold))]  # fmt: skip
    max_pen = max_intr = max_tilt = 0.0
    min_hold = math.inf
    lift_slip = hold_slip = hold_turn = 0.0
    rel0 = hold0 = None
    finite = True
    seconds = 0.0
    for phase, n in phases:
        if phase == "lift":
            rel0 = _relative_pose(scene)
        if phase == "hold":
            hold0 = _relative_pose(scene)
            lift_slip = float(np.linalg.norm(hold0[0] - rel0[0]))
        for k in range(n):
            if phase == "approach":
                # reach the grasp height at 80 % of the phase, then settle
                scene.set_palm_target(start + (grasp - start) * min(1.0, (k / n) * 1.25))
            elif phase == "squeeze":
                if scene.finger_target != close_to:
                    scene.set_finger_target(close_to)
            elif phase == "lift":
                target = grasp.copy()
                target[2] += plan.lift_distance * _min_jerk((k + 1) / n)
                scene.set_palm_target(target)
            tic = time.perf_counter()
            world.step()
            seconds += time.perf_counter() - tic
            if not world.is_finite():
                finite = False
                break
            pen, intr = world.penetration()
            max_pen = max(max_pen, pen)
            max_intr = max(max_intr, intr)
            if phase in ("lift", "hold"):
                max_tilt = max(max_tilt, scene.cylinder_tilt())
            if phase == "hold":
                min_hold = min(min_hold, scene.lift_height())
                pos, q = _relative_pose(scene)
                hold_slip = max(hold_slip, float(np.linalg.norm(pos - hold0[0])))
                hold_turn = max(hold_turn, _angle_between(q, hold0[1]))
            if on_step is not None:
                on_step(phase)
        if not finite:
            break
    return GraspRecord(
        lift_height=scene.lift_height() if finite else math.nan,
        min_lift_during_hold=float(min_hold) if finite else math.nan,
        max_penetration=max_pen,
        max_core_intrusion=max_intr,
        max_tilt=max_tilt,
        tilt=scene.cylinder_tilt() if finite else math.nan,
        lift_slip=lift_slip,
        hold_slip=hold_slip,
        hold_turn=hold_turn,
        steps=world.step_count,
        seconds=seconds,
        finite=finite,
    )


def coulomb_hold_bound(mu_s: float, finger_force: float, gravity: float) -> float:
    """Heaviest cylinder two fingers pressing with ``finger_force`` each can hold: 2 mu_s F / g [kg]."""
    return 2.0 * mu_s * finger_force / gravity


def find_hold_bound(
    held: Callable[[float], bool], *, lo: float, hi: float, rel_tol: float = 0.01, max_trials: int = 30
) -> tuple[float, list[tuple[float, bool]]]:
    """Heaviest mass for which ``held(mass)`` is true, by bisection between ``lo`` (must hold) and
    ``hi`` (must not); returns (the midpoint of the final bracket, every trial). Raises ValueError
    if the bracket does not bracket."""
    trials: list[tuple[float, bool]] = []
    for m, want in ((lo, True), (hi, False)):
        ok = held(m)
        trials.append((m, ok))
        if ok != want:
            raise ValueError(f"hold bound not bracketed: held({m:g} kg) is {ok}, expected {want}")
    while hi - lo > rel_tol * lo and len(trials) < max_trials:
        mid = math.sqrt(lo * hi)  # geometric: the bound's relative error is what counts
        ok = held(mid)
        trials.append((mid, ok))
        if ok:
            lo = mid
        else:
            hi = mid
    return math.sqrt(lo * hi), trials
