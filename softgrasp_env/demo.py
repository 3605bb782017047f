"""Main job: a scripted grasp, headless. ``python -m softgrasp_env.demo --help``

Approach (descend around the cylinder), squeeze (force-limited fingers), lift 5 cm, hold 2 s;
prints the lift height, the deepest tissue penetration and the physics steps per second, and exits
non-zero if the cylinder was not held.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from dataclasses import dataclass

import numpy as np

from .config import SceneConfig, SimConfig, TissueConfig
from .scene import GraspScene


@dataclass(frozen=True)
class ScriptTimes:
    """Durations of the scripted phases [s]."""

    approach: float = 0.5
    squeeze: float = 0.6
    lift: float = 1.0
    hold: float = 2.0
    lift_distance: float = 0.05


@dataclass
class GraspResult:
    lift_height: float
    """Cylinder centre above its resting height at the end of the hold [m]."""
    min_lift_during_hold: float
    max_penetration: float
    """Deepest tissue overlap with a rigid shape, over the whole run [m]."""
    max_core_intrusion: float
    """Deepest intrusion of an outer particle's centre into its own core [m]."""
    steps: int
    seconds: float
    finite: bool
    tilt: float
    """Cylinder tilt at the end [rad]."""

    @property
    def steps_per_second(self) -> float:
        return self.steps / self.seconds if self.seconds > 0 else float("nan")

    def held(self, times: ScriptTimes) -> bool:
        """Lifted to at least 80 % of the commanded height and kept there through the hold."""
        need = 0.8 * times.lift_distance
        return self.finite and self.lift_height >= need and self.min_lift_during_hold >= need


def run_scripted_grasp(scene: GraspScene, times: ScriptTimes | None = None) -> GraspResult:
    """Drive ``scene`` through approach, squeeze, lift and hold; returns what happened."""
    t = times or ScriptTimes()
    dt = scene.config.sim.dt
    world = scene.world
    start = scene.palm_target.copy()
    grasp = start.copy()
    grasp[2] = scene.grasp_height + scene.palm_offset
    max_pen = 0.0
    max_intr = 0.0
    min_hold = np.inf
    finite = True
    close_to = scene.config.finger_max_opening  # beyond contact: the force limit sets the squeeze

    def steps(duration: float) -> int:
        return int(round(duration / dt))

    plan = []
    n = steps(t.approach)
    plan += [("approach", k / n) for k in range(n)]
    plan += [("squeeze", 0.0)] * steps(t.squeeze)
    n = steps(t.lift)
    plan += [("lift", (k + 1) / n) for k in range(n)]
    plan += [("hold", 1.0)] * steps(t.hold)

    tic = time.perf_counter()
    for phase, s in plan:
        if phase == "approach":
            scene.set_palm_target(start + (grasp - start) * min(1.0, s * 1.25))
        elif phase == "squeeze":
            if scene.finger_target != close_to:
                scene.set_finger_target(close_to)
        else:
            target = grasp.copy()
            target[2] += t.lift_distance * s
            scene.set_palm_target(target)
        world.step()
        if world.solver is not None and world.step_count % 10 == 0:
            pen, intr = world.penetration()
            max_pen = max(max_pen, pen)
            max_intr = max(max_intr, intr)
        if phase == "hold":
            min_hold = min(min_hold, scene.lift_height())
        if not world.is_finite():
            finite = False
            break
    seconds = time.perf_counter() - tic
    return GraspResult(
        lift_height=scene.lift_height(),
        min_lift_during_hold=float(min_hold),
        max_penetration=max_pen,
        max_core_intrusion=max_intr,
        steps=world.step_count,
        seconds=seconds,
        finite=finite,
        tilt=scene.cylinder_tilt(),
    )


def _add_dataclass_flags(parser: argparse.ArgumentParser, cls: type, prefix: str = "") -> None:
    for f in dataclasses.fields(cls):
        if f.type in ("float", "int", float, int):
            kind = float if f.type in ("float", float) else int
            parser.add_argument(f"--{prefix}{f.name.replace('_', '-')}", type=kind, default=None,
                                help=f"{cls.__name__}.{f.name} (default {f.default})")  # fmt: skip


def _collect(ns: argparse.Namespace, cls: type, prefix: str = "") -> dict:
    out = {}
    for f in dataclasses.fields(cls):
        key = (prefix + f.name).replace("-", "_")
        if getattr(ns, key, None) is not None:
            out[f.name] = getattr(ns, key)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m softgrasp_env.demo", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    parser.add_argument("--rigid", action="store_true", help="rigid-only fingers (no tissue)")
    parser.add_argument("--coupling", choices=["thesis", "consistent"], default=None, help="core-tissue coupling")
    parser.add_argument("--orientation", choices=["reaction", "goal"], default=None, help="particle orientation update")
    parser.add_argument("--gui", action="store_true", help="open the pybullet GUI (needs a display)")
    _add_dataclass_flags(parser, TissueConfig)
    _add_dataclass_flags(parser, SimConfig)
    for name in ("cylinder_radius", "cylinder_height", "cylinder_mass", "finger_force", "lateral_offset", "yaw"):
        parser.add_argument(f"--{name.replace('_', '-')}", type=float, default=None)
    ns = parser.parse_args(argv)
    try:
        tissue = TissueConfig(**_collect(ns, TissueConfig))
        sim_kw = _collect(ns, SimConfig)
        if ns.coupling:
            sim_kw["coupling"] = ns.coupling
        if ns.orientation:
            sim_kw["orientation"] = ns.orientation
        sim = SimConfig(**sim_kw)
        scene_kw = {k: getattr(ns, k) for k in ("cylinder_radius", "cylinder_height", "cylinder_mass",
                                                 "finger_force", "lateral_offset", "yaw") if getattr(ns, k) is not None}  # fmt: skip
        cfg = SceneConfig(soft=not ns.rigid, tissue=tissue, sim=sim, **scene_kw)
    except ValueError as exc:
        parser.error(str(exc))
    scene = GraspScene(cfg, gui=ns.gui)
    try:
        times = ScriptTimes()
        res = run_scripted_grasp(scene, times)
    finally:
        scene.close()
    n_particles = 0 if scene.world.model is None else scene.world.model.particle_count
    print(f"fingers:            {'rigid-only' if ns.rigid else 'soft'} ({n_particles} tissue particles)")
    print(f"lift height:        {res.lift_height * 100:.2f} cm (min during hold {res.min_lift_during_hold * 100:.2f} cm)")
    print(f"max penetration:    {res.max_penetration * 1000:.3f} mm (tissue into rigid shapes)")
    print(f"max core intrusion: {res.max_core_intrusion * 1000:.3f} mm (outer particles into own core)")
    print(f"cylinder tilt:      {np.degrees(res.tilt):.1f} deg")
    print(f"physics steps/s:    {res.steps_per_second:.0f} ({res.steps} steps in {res.seconds:.2f} s)")
    ok = res.held(times)
    print("result:             " + ("HELD" if ok else "NOT HELD"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
