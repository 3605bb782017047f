"""Accuracy measured against analytic physics, the same way for every finger kind and setting.
The demo, the benchmarks and the tests all measure through this module.

- The scripted grasp and the figures taken from it: penetration (every step), in-hand slip and
  turn during the hold, tilt. Coulomb's law gives the reference: two fingers squeezing with
  normal force F hold a cylinder of mass m without slipping iff 2 mu_s F >= m g, so the heaviest
  cylinder held is m* = 2 mu_s F / g (found by bisection, find_hold_bound), and below it the
  cylinder should not move in the fingers at all.
- The tissue alone: a pad on a slowly tilted ramp breaks loose at tan theta = mu_s, slides down
  a steeper one at g (sin theta - mu_k cos theta), and launched at v0 on level ground stops
  after v0^2 / (2 mu_k g); a free body keeps its momentum, angular momentum and energy.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from .config import SimConfig, TissueConfig, kinetic_friction
from .scene import GraspScene
from .tissue.builder import build_free_block
from .tissue.collision import SHAPE_CODES
from .tissue.compliant import substeps_for
from .tissue.model import TissueModel
from .tissue.rigid import Colliders
from .tissue.rotation import quat_to_matrix
from .tissue.solver import TissueSolver
from .tissue.state import TissueState, state_at_rest


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
    """Deepest overlap of a finger (tissue, or pybullet's own contacts) with the cylinder or the
    ground, checked after every step [m] (GraspScene.penetration)."""
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
    in_hand_motion: float
    """Largest distance of the cylinder centre, in the palm's frame, from where it was when the
    lift began, over lift and hold [m]: what the hand let it move by, sag of the fingers plus slip
    (ideal 0 while the bound is met)."""
    steps: int
    seconds: float
    """Wall time of the physics steps alone [s]."""
    finite: bool
    """False if the run diverged (GraspScene.diverged: non-finite, or far past any physical speed)."""
    trace: np.ndarray | None = None
    """With ``run_grasp(..., trace=True)``: (steps, 8) rows [t, cylinder x, y, z, qx, qy, qz, qw]
    after every step, for comparing runs (pose_error)."""

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


def _min_jerk_rate(u: float) -> float:
    """d/du of the minimum-jerk profile: 30 u^2 (1 - u)^2."""
    u = min(max(u, 0.0), 1.0)
    return 30.0 * u * u * (1.0 - u) * (1.0 - u)


def _relative_pose(scene: GraspScene) -> tuple[np.ndarray, np.ndarray]:
    """Cylinder pose in the palm's frame (position [m], quaternion [x, y, z, w])."""
    c = scene.client
    pp, pq = c.getBasePositionAndOrientation(scene.gripper.body)
    cp, cq = c.getBasePositionAndOrientation(scene.cylinder)
    ip, iq = c.invertTransform(pp, pq)
    rp, rq = c.multiplyTransforms(ip, iq, cp, cq)
    return np.asarray(rp), np.asarray(rq)


def _angle_between(q0: np.ndarray, q1: np.ndarray) -> float:
    d = abs(float(np.dot(q0, q1)))
    return 2.0 * math.acos(min(1.0, d))


def run_grasp(
    scene: GraspScene, plan: GraspPlan | None = None, *, on_step: Callable[[str], None] | None = None,
    trace: bool = False,
) -> GraspRecord:
    """Drive ``scene`` through approach, squeeze, lift and hold (fingers commanded past contact: the
    motors' force limit sets the squeeze) and measure it; ``on_step(phase)`` runs after every step;
    ``trace`` records the cylinder's pose after every step."""
    plan = plan or GraspPlan()
    dt = scene.config.sim.dt
    world = scene.world
    start = scene.palm_target.copy()
    control = scene.control
    grasp = start.copy()
    grasp[2] = scene.grasp_height + scene.palm_offset
    close_to = scene.config.finger_stroke

    def n_steps(duration: float) -> int:
        return int(round(duration / dt))

    phases = [("approach", n_steps(plan.approach)), ("squeeze", n_steps(plan.squeeze)),
              ("lift", n_steps(plan.lift)), ("hold", n_steps(plan.hold))]  # fmt: skip
    max_pen = max_intr = max_tilt = 0.0
    min_hold = math.inf
    lift_slip = hold_slip = hold_turn = in_hand = 0.0
    rel0 = hold0 = None
    finite = True
    seconds = 0.0
    rows: list[tuple[float, ...]] = []
    for phase, n in phases:
        if phase == "lift":
            rel0 = _relative_pose(scene)
        if phase == "hold":
            hold0 = _relative_pose(scene)
            lift_slip = float(np.linalg.norm(hold0[0] - rel0[0]))
        for k in range(n):
            if phase == "approach":
                # reach the grasp height at 80 % of the phase, then settle (the path's own velocity
                # goes with it, so the arm follows without lag)
                u = (k / n) * 1.25
                velocity = (grasp - start) * (1.25 / (n * dt)) if u < 1.0 else np.zeros(3)
                control = replace(control, palm_target=start + (grasp - start) * min(1.0, u), palm_velocity=velocity)
            elif phase == "squeeze":
                control = replace(control, finger_closing=close_to, palm_velocity=None)
            elif phase == "lift":
                target = grasp.copy()
                target[2] += plan.lift_distance * _min_jerk((k + 1) / n)
                velocity = np.array([0.0, 0.0, plan.lift_distance * _min_jerk_rate((k + 1) / n) / (n * dt)])
                control = replace(control, palm_target=target, palm_velocity=velocity)
            elif phase == "hold" and control.palm_velocity is not None:
                control = replace(control, palm_velocity=None)
            tic = time.perf_counter()
            scene.step(control)
            seconds += time.perf_counter() - tic
            if scene.diverged():
                finite = False
                break
            pen, intr = scene.penetration()
            max_pen = max(max_pen, pen)
            if trace:
                cp, cq = scene.cylinder_pose()
                rows.append((world.step_count * dt, *cp, *cq))
            max_intr = max(max_intr, intr)
            if phase in ("lift", "hold"):
                max_tilt = max(max_tilt, scene.cylinder_tilt())
                in_hand = max(in_hand, float(np.linalg.norm(_relative_pose(scene)[0] - rel0[0])))
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
        in_hand_motion=in_hand,
        steps=world.step_count,
        seconds=seconds,
        finite=finite,
        trace=np.array(rows) if trace else None,
    )


@dataclass
class ShearRecord:
    """What :func:`shear_under_load` measured, one row per sample (lengths in m, forces in N)."""

    load: np.ndarray
    """(S,) the tangential load the two pads carry: the cylinder's weight plus the pull [N]."""
    traction: np.ndarray
    """(S,) the same read off the taxels: minus the pads' vertical traction, summed over both [N]."""
    shear: np.ndarray
    """(S,) the pads' mean downward shear over their loaded taxels (pressure-weighted), mean of the
    two pads [m]."""
    slide: np.ndarray
    """(S,) how far the cylinder has slid down in the grip since the pull began [m]."""
    slip_load: float
    """The load at which it first slid more than ``slip`` (inf if it never did) [N]."""
    fields: np.ndarray
    """(S, 2, rows, cols, channels) the taxels at each sample (fingers/tactile.py)."""


def shear_under_load(scene: GraspScene, *, rate: float = 2.0, slip: float = 1e-3, max_load: float = 12.0,
                     every: int = 4, rows: int = 4, cols: int = 3) -> ShearRecord:  # fmt: skip
    """The scripted grasp (a short hold), then the cylinder made heavier at ``rate`` [N/s of
    weight] until it slips ``slip`` on the pads (or its weight reaches ``max_load``): how the pads
    shear under a tangential load up to slip, read through the taxels
    (:mod:`softgrasp_env.fingers.tactile`) every ``every`` physics steps. Slip is the cylinder's slide in the grip
    less the pads' own shear (an elastic pad carries the cylinder down with its surface)."""
    plan = GraspPlan(hold=0.5)
    run_grasp(scene, plan)
    kind = scene.fingers
    grid = kind.taxel_grid(rows, cols)
    g = scene.config.sim.gravity
    m0 = scene.config.cylinder_mass
    control = scene.control
    rel0 = _relative_pose(scene)[0]
    dt = scene.config.sim.dt
    out: dict[str, list] = {"load": [], "traction": [], "shear": [], "slide": [], "fields": []}
    slip_load = math.inf
    shear0 = None
    k = 0
    while True:
        load = m0 * g + rate * k * dt
        if load > max_load:
            break
        scene.set_cylinder_mass(load / g)
        scene.step(control)
        k += 1
        if k % every:
            continue
        slide = float(rel0[2] - _relative_pose(scene)[0][2])
        tac = kind.tactile(grid)
        pressure = tac[..., 0]
        shear = [float(-(pressure[f] * tac[f, ..., 4]).sum() / pressure[f].sum()) if pressure[f].sum() > 0 else 0.0
                 for f in range(2)]  # fmt: skip
        out["load"].append(load)
        out["traction"].append(float(-tac[..., 2].sum() * grid.area))
        out["shear"].append(0.5 * (shear[0] + shear[1]))
        out["slide"].append(slide)
        out["fields"].append(tac)
        if shear0 is None:
            shear0 = out["shear"][0]
        if slide - (out["shear"][-1] - shear0) > slip:
            slip_load = load
            break
    return ShearRecord(**{key: np.array(v) for key, v in out.items()}, slip_load=slip_load)


def pose_error(trace: np.ndarray, reference: np.ndarray) -> tuple[float, float]:
    """RMS difference of two runs' cylinder poses over time: (position [m], orientation [rad]),
    ``reference`` interpolated (positions linearly, orientations by nearest sample) at ``trace``'s
    times within the span both cover. Runs at different time steps compare this way."""
    t = trace[:, 0]
    keep = (t >= reference[0, 0]) & (t <= reference[-1, 0])
    t = t[keep]
    pos = np.stack([np.interp(t, reference[:, 0], reference[:, 1 + a]) for a in range(3)], axis=1)
    idx = np.clip(np.searchsorted(reference[:, 0], t), 0, len(reference) - 1)
    dq = np.abs((trace[keep, 4:8] * reference[idx, 4:8]).sum(axis=1))
    ang = 2.0 * np.arccos(np.clip(dq, -1.0, 1.0))
    return float(np.sqrt(((trace[keep, 1:4] - pos) ** 2).sum(axis=1).mean())), float(np.sqrt((ang**2).mean()))


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


# --- the tissue alone against Coulomb's law: a pad on a ramp and on the ground ------------------------

PAD_HALF_EXTENTS = (0.016, 0.016, 0.008)
"""The test pad: a free two-layer tissue block 32 x 32 x 16 mm at 8 mm spacing (75 particles)."""


class _Pad:
    """A pad resting on a plane tilted by ``theta`` about x (through the origin), stepped as the
    world steps tissue (sim/world.py): in steps of dt / n short enough for its material
    (compliant.substeps_for). The plane sits on a kinematic rigid slot (no mass: nothing the
    tissue does moves it) that turns at ``rate`` [rad/s] within every step, as a body would: turned
    in one jump per dt, a pad in shorter steps met each jump in its first one and slipped in the
    next, 1.5 % early on the ramp."""

    def __init__(self, theta: float, tissue: TissueConfig, sim: SimConfig, *, rate: float = 0.0) -> None:
        self.model = build_free_block(PAD_HALF_EXTENTS, tissue, spacing=0.008)
        self.n = substeps_for(self.model, sim.dt)
        self.h = sim.dt / self.n
        self.theta, self.rate = theta, rate
        q = np.array([math.sin(theta / 2), 0.0, 0.0, math.cos(theta / 2)])
        self.col = Colliders(
            rigid_x=np.zeros((1, 3)), rigid_q=q[None].copy(), rigid_v=np.zeros((1, 3)), rigid_w=np.zeros((1, 3)),
            rigid_inv_mass=np.zeros(1), rigid_inv_inertia=np.zeros((1, 3)), rigid_gravity=np.zeros(1, dtype=np.bool_),
            rigid_in_solve=np.zeros(1, dtype=np.bool_), shape_kind=np.array([SHAPE_CODES["plane"]], dtype=np.int32),
            shape_params=np.zeros((1, 3)), shape_rigid=np.zeros(1, dtype=np.int32), shape_local_x=np.zeros((1, 3)),
            shape_local_q=np.array([[0.0, 0.0, 0.0, 1.0]]),
        )  # fmt: skip
        rot = quat_to_matrix(q)
        self.state = state_at_rest(self.model, (rot[:, 2] * PAD_HALF_EXTENTS[2])[None], q[None])
        self.solver = TissueSolver(self.model, replace(sim, dt=self.h) if self.n > 1 else sim)
        self.down = -rot[:, 1]
        self._pose()

    def _pose(self) -> None:
        self.col.rigid_q[0] = (math.sin(self.theta / 2), 0.0, 0.0, math.cos(self.theta / 2))
        self.col.rigid_w[0] = (self.rate, 0.0, 0.0)

    def step(self) -> None:
        """One step of sim.dt."""
        for _ in range(self.n):
            self.solver.step(self.state, self.col)
            self.theta += self.rate * self.h
            self._pose()

    def on_ramp(self) -> np.ndarray:
        """The pad's centre in the ramp's frame [m]."""
        return quat_to_matrix(self.col.rigid_q[0]).T @ self.state.particle_x.mean(axis=0)


def ramp_breakaway(tissue: TissueConfig, sim: SimConfig, *, rate: float = 0.05, threshold: float = 1e-4) -> float:
    """tan of the ramp angle at which the pad breaks loose, measured as on an inclined plane: the
    ramp is tilted slowly (``rate`` rad/s) from 0.08 rad below atan mu_s until the pad's centre has
    moved ``threshold`` along the ramp. Coulomb: tan theta = mu_s. Detection lags the true onset a
    little (0.1 mm at 0.05 rad/s reads ~0.1 % high); NaN if it never slid."""
    pad = _Pad(math.atan(tissue.friction_static) - 0.08, tissue, sim)
    for _ in range(int(round(0.5 / sim.dt))):  # settle
        pad.step()
    start = pad.on_ramp()
    pad.rate = rate
    for _ in range(int(round(0.2 / rate / sim.dt))):
        pad.step()
        if np.linalg.norm(pad.on_ramp() - start) > threshold:
            return math.tan(pad.theta)
    return math.nan


def slide_acceleration(theta: float, tissue: TissueConfig, sim: SimConfig, *, t0: float = 0.5, t1: float = 1.0) -> float:
    """Acceleration of the pad's centre of mass down a ramp of angle ``theta`` steep enough to slide,
    from its velocity at t0 and t1 [m/s^2]. Coulomb: g (sin theta - mu_k cos theta)."""
    pad = _Pad(theta, tissue, sim)
    m = pad.model.particle_mass[:, None]
    speeds = {}
    n0, n1 = int(round(t0 / sim.dt)), int(round(t1 / sim.dt))
    for k in range(1, n1 + 1):
        pad.step()
        if k in (n0, n1):
            speeds[k] = float(((m * pad.state.particle_v).sum(axis=0) / m.sum()) @ pad.down)
    return (speeds[n1] - speeds[n0]) / ((n1 - n0) * sim.dt)


def stop_distance(v0: float, tissue: TissueConfig, sim: SimConfig) -> float:
    """How far the pad's centre slides on level ground after being launched at ``v0`` [m].
    Coulomb: v0^2 / (2 mu_k g)."""
    pad = _Pad(0.0, tissue, sim)
    for _ in range(int(round(0.5 / sim.dt))):  # settle onto the ground first
        pad.step()
    state = pad.state
    state.particle_v[:, 1] += v0
    y0 = state.particle_x[:, 1].mean()
    for _ in range(int(2.0 * v0 / (kinetic_friction(tissue) * sim.gravity) / sim.dt) + 240):
        pad.step()
    return float(state.particle_x[:, 1].mean() - y0)


def momenta(model: TissueModel, state: TissueState) -> tuple[np.ndarray, np.ndarray, float]:
    """(linear momentum, angular momentum about the origin with the particles' own spin, kinetic
    energy with the particles' own rotation) of a tissue state."""
    m = model.particle_mass
    lin = (m[:, None] * state.particle_v).sum(axis=0)
    ang = (m[:, None] * np.cross(state.particle_x, state.particle_v)).sum(axis=0)
    inertia = model.particle_inertia_local()
    energy = 0.5 * float((m * (state.particle_v**2).sum(axis=1)).sum())
    for i in range(model.particle_count):
        r = quat_to_matrix(state.particle_q[i])
        w_local = r.T @ state.particle_omega[i]
        ang = ang + r @ (inertia[i] * w_local)
        energy += 0.5 * float(w_local @ (inertia[i] * w_local))
    return lin, ang, energy
