"""Accuracy at the default settings against analytic physics, every figure in one run.

    PYTHONPATH=. python benchmarks/accuracy_defaults.py [--quick]

Rows (softgrasp_env/accuracy.py measures each):
- pad on a slowly tilted ramp: breakaway tan theta vs mu_s, for mu_s 0.3 / 0.6 / 0.9 (mu_k = 7/9 mu_s)
- sliding acceleration down a steeper ramp vs g (sin theta - mu_k cos theta)
- slide-to-stop distance from 0.25 / 0.5 / 1 m/s vs v^2 / (2 mu_k g)
- free body, 1,000 steps: relative change of momentum and angular momentum, largest energy rise
- scripted grasp at the defaults: deepest penetration (every step), core intrusion, per coupling
- hold: scripted grasp then 60 s of holding: tilt and slip in the hand, per finger kind
- hold bound: heaviest cylinder held at 3 N per finger (bisection, 4 s lift) vs 2 mu_s F / g

Takes about 3 minutes on 2 cores of an AMD EPYC (--quick: no 60 s soak, coarser bisection).
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace

import numpy as np

from softgrasp_env import accuracy, presets
from softgrasp_env.accuracy import GraspPlan, coulomb_hold_bound, find_hold_bound, run_grasp
from softgrasp_env.config import COMPLIANT_DAMPING, SimConfig, TissueConfig, kinetic_friction
from softgrasp_env.scene import GraspScene, SceneConfig
from softgrasp_env.tissue.builder import build_free_block
from softgrasp_env.tissue.rigid import empty_colliders
from softgrasp_env.tissue.solver import TissueSolver
from softgrasp_env.tissue.state import state_at_rest


def kinds(preset: str) -> dict[str, SceneConfig]:
    base = presets.scene_config(preset)
    return {
        "soft, thesis coupling": base,
        "soft, consistent coupling": replace(base, sim=replace(base.sim, coupling="consistent")),
        "rigid-only fingers": replace(base, fingers="rigid"),
    }


def pct(value: float, reference: float) -> str:
    return f"{100.0 * (value / reference - 1.0):+.2f} %"


def friction_rows() -> None:
    sim = SimConfig()
    t = TissueConfig()
    damping = sim.damping if sim.damping is not None else COMPLIANT_DAMPING
    print(f"pad on a ramp (defaults: {sim.iterations} iterations, dt 1/{round(1 / sim.dt)} s, {t.group_energy} energy, "
          f"shear modulus {t.shear_modulus:g} Pa, damping {damping:g} /s)")
    for mu_s in (0.3, 0.6, 0.9):
        tissue = TissueConfig(friction_static=mu_s, friction_kinetic=mu_s * 7.0 / 9.0)
        tan = accuracy.ramp_breakaway(tissue, sim)
        theta = math.atan(mu_s + 0.15)
        a = accuracy.slide_acceleration(theta, tissue, sim)
        a_ref = sim.gravity * (math.sin(theta) - kinetic_friction(tissue) * math.cos(theta))
        print(f"  mu_s {mu_s}: breaks loose at tan {tan:.4f} ({pct(tan, mu_s)}); "
              f"slides at {a:.4f} m/s^2 vs {a_ref:.4f} ({pct(a, a_ref)})")  # fmt: skip
    tissue = TissueConfig()
    for v0 in (0.25, 0.5, 1.0):
        d = accuracy.stop_distance(v0, tissue, sim)
        ref = v0 * v0 / (2.0 * kinetic_friction(tissue) * sim.gravity)
        print(f"  stops from {v0} m/s after {d * 1000:.2f} mm vs {ref * 1000:.2f} mm ({pct(d, ref)})")


def conservation_rows() -> None:
    print("free 125-particle block, zero gravity, 1,000 steps at the default damping")
    for kind in ("random velocities", "rigid spin"):
        model = build_free_block((0.02, 0.02, 0.02), TissueConfig(), spacing=0.008)
        state = state_at_rest(model, np.zeros((1, 3)), np.array([[0.0, 0.0, 0.0, 1.0]]))
        if kind == "random velocities":
            state.particle_v[:] = np.random.default_rng(7).normal(scale=0.01, size=state.particle_v.shape)
        else:
            omega = np.array([0.3, -0.2, 1.0])
            state.particle_v[:] = np.cross(omega, state.particle_x) + [0.01, 0.0, 0.0]
            state.particle_omega[:] = omega
        solver = TissueSolver(model, SimConfig(gravity=0.0))
        p0, l0, e0 = accuracy.momenta(model, state)
        rise = 0.0
        for _ in range(1000):
            solver.step(state, empty_colliders())
            rise = max(rise, accuracy.momenta(model, state)[2] / e0 - 1.0)
        p1, l1, _ = accuracy.momenta(model, state)
        print(f"  {kind}: momentum {np.linalg.norm(p1 - p0) / np.linalg.norm(p0):.1e}, angular momentum "
              f"{np.linalg.norm(l1 - l0) / np.linalg.norm(l0):.1e} (relative); energy at most {rise:+.1e} above the start")  # fmt: skip


def grasp_rows(soak: float, preset: str) -> None:
    print(f"scripted grasp, preset {preset!r}, then {soak:g} s of holding")
    for name, cfg in kinds(preset).items():
        scene = GraspScene(cfg)
        try:
            r = run_grasp(scene, GraspPlan(hold=soak))
        finally:
            scene.close()
        print(f"  {name}: penetration {r.max_penetration * 1000:.3f} mm, core intrusion "
              f"{r.max_core_intrusion * 1000:.3f} mm; over the hold: slip {r.hold_slip * 1000:.3f} mm, turn "
              f"{math.degrees(r.hold_turn):.3f} deg; tilt at most {math.degrees(r.max_tilt):.3f} deg; "
              f"{'held' if r.held(GraspPlan(hold=soak)) else 'NOT HELD'}")  # fmt: skip


def bound_rows(rel_tol: float, preset: str) -> None:
    plan = GraspPlan(lift=4.0, hold=3.0)
    base = presets.scene_config(preset)
    ref = coulomb_hold_bound(base.tissue.friction_static, base.finger_force, base.sim.gravity)
    print(f"hold bound at {base.finger_force:g} N per finger (4 s lift, 3 s hold): Coulomb 2 mu_s F / g = {ref:.4f} kg")
    for name, cfg in kinds(preset).items():

        def held(mass: float, cfg=cfg) -> bool:
            scene = GraspScene(replace(cfg, cylinder_mass=mass))
            try:
                return run_grasp(scene, plan).holds_without_slip(plan)
            finally:
                scene.close()

        tic = time.perf_counter()
        bound, trials = find_hold_bound(held, lo=0.5 * ref, hi=1.5 * ref, rel_tol=rel_tol)
        print(f"  {name}: {bound:.4f} kg ({pct(bound, ref)}), {len(trials)} trials, {time.perf_counter() - tic:.0f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="hold 5 s instead of 60 s, bisect to 2 %%")
    parser.add_argument("--preset", default="default", choices=tuple(presets.PRESETS), help="scene preset of the grasp rows")
    parser.add_argument("--grasp-only", action="store_true", help="only the grasp and hold-bound rows")
    args = parser.parse_args()
    if not args.grasp_only:
        friction_rows()
        conservation_rows()
    grasp_rows(5.0 if args.quick else 60.0, args.preset)
    bound_rows(0.02 if args.quick else 0.005, args.preset)


if __name__ == "__main__":
    main()
