"""Main job: a scripted grasp, headless. ``python -m softgrasp_env.demo --help``

Approach (descend around the cylinder), squeeze (force-limited fingers), lift 5 cm, hold 2 s (or
``--hold`` seconds); prints the lift height, the deepest tissue penetration over every step, the
slip in the hand, the tilt and the physics steps per second, and exits non-zero if the cylinder
was not held (lifted to 80 % and never tilted past 45 degrees, the env's success threshold).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time

import numpy as np

from .accuracy import GraspPlan, run_grasp
from .config import SimConfig, TissueConfig
from .presets import v4_tissue
from .scene import GraspScene, SceneConfig

_OLD_FLAGS = {"particle_density": "--density", "mass_density": "--tissue-density"}
"""Flags of 0.2, before TissueConfig's fields were renamed: both spellings work, the old one
with a note on stderr."""


class _Deprecated(argparse.Action):
    def __call__(self, parser, namespace, values, option_string=None):
        if option_string in _OLD_FLAGS.values():
            new = "--" + self.dest.replace("_", "-")
            print(f"note: {option_string} is deprecated, use {new}", file=sys.stderr)
        setattr(namespace, self.dest, values)


_NUMBERS = {"float": float, "int": int, "float | None": float, "int | None": int}
"""Field annotations (strings: the config modules use postponed annotations) that get a flag."""


def _add_dataclass_flags(parser: argparse.ArgumentParser, cls: type, prefix: str = "") -> None:
    for f in dataclasses.fields(cls):
        if f.type in _NUMBERS:
            kind = _NUMBERS[f.type]
            flags = [f"--{prefix}{f.name.replace('_', '-')}"] + ([_OLD_FLAGS[f.name]] if f.name in _OLD_FLAGS else [])
            parser.add_argument(*flags, dest=prefix + f.name, type=kind, default=None, action=_Deprecated,
                                help=f"{cls.__name__}.{f.name} (default {f.default})")  # fmt: skip


def _collect(ns: argparse.Namespace, cls: type, prefix: str = "") -> dict:
    out = {}
    for f in dataclasses.fields(cls):
        key = (prefix + f.name).replace("-", "_")
        if getattr(ns, key, None) is not None:
            out[f.name] = getattr(ns, key)
    return out


def main(argv: list[str] | None = None) -> int:
    # no abbreviations: a retired flag (--material) must not be read as a prefix of a live one
    parser = argparse.ArgumentParser(prog="python -m softgrasp_env.demo", description=__doc__, allow_abbrev=False,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    parser.add_argument("--rigid", action="store_true", help="rigid-only fingers (no tissue)")
    parser.add_argument("--tissue", choices=["v5", "v4", "v3"], default="v5",
                        help="the tissue of the soft ids of that version: v5 the v4 tissue solved globally "
                             "(--material-solve global, the default), v4 the continuum energy with Coulomb's law per "
                             "contact (presets.v4_tissue) swept group by group, v3 the thesis' shape matching with "
                             "its patch law")  # fmt: skip
    parser.add_argument("--coupling", choices=["thesis", "consistent"], default=None, help="core-tissue coupling")
    parser.add_argument("--material-solve", choices=["groups", "global"], default=None,
                        help="how the tissue's material is solved each pass (SimConfig.material_solve; default: "
                             "--tissue's, global for v5, groups for v4 and v3)")  # fmt: skip
    parser.add_argument("--gui", action="store_true", help="open the pybullet GUI (needs a display)")
    parser.add_argument("--hold", type=float, default=GraspPlan().hold, help="seconds to hold the lifted cylinder")
    _add_dataclass_flags(parser, TissueConfig)
    _add_dataclass_flags(parser, SimConfig)
    for name in ("cylinder_radius", "cylinder_height", "cylinder_mass", "finger_force", "lateral_offset", "yaw"):
        parser.add_argument(f"--{name.replace('_', '-')}", type=float, default=None)
    ns = parser.parse_args(argv)
    try:
        tissue_kw = _collect(ns, TissueConfig)
        tissue = TissueConfig(**tissue_kw) if ns.tissue == "v3" else v4_tissue(**tissue_kw)
        sim_kw = _collect(ns, SimConfig)
        if ns.tissue == "v5" and not ns.rigid:  # the soft ids' v5: the v4 tissue, solved globally
            sim_kw.setdefault("material_solve", "global")
        if ns.coupling:
            sim_kw["coupling"] = ns.coupling
        if ns.material_solve:
            sim_kw["material_solve"] = ns.material_solve
        sim = SimConfig(**sim_kw)
        scene_kw = {k: getattr(ns, k) for k in ("cylinder_radius", "cylinder_height", "cylinder_mass",
                                                 "finger_force", "lateral_offset", "yaw") if getattr(ns, k) is not None}  # fmt: skip
        cfg = SceneConfig(fingers="rigid" if ns.rigid else "tissue", tissue=tissue, sim=sim, **scene_kw)
    except ValueError as exc:
        parser.error(str(exc))
    plan = GraspPlan(hold=ns.hold)
    print("building the scene (the first run on a machine compiles the solver: about a minute)...", flush=True)
    tic = time.perf_counter()
    scene = GraspScene(cfg, gui=ns.gui)
    try:
        scene.step()  # the first step loads (or compiles) every kernel; not timed below
        print(f"ready in {time.perf_counter() - tic:.1f} s; grasping...", flush=True)
        res = run_grasp(scene, plan)
        n_particles = 0 if scene.world.model is None else scene.world.model.particle_count
    finally:
        scene.close()
    kind = "rigid-only" if ns.rigid else f"soft, {ns.tissue} tissue"
    print(f"fingers:            {kind} ({n_particles} tissue particles)")
    print(f"lift height:        {res.lift_height * 100:.2f} cm (min during hold {res.min_lift_during_hold * 100:.2f} cm)")
    print(f"max penetration:    {res.max_penetration * 1000:.3f} mm (tissue into rigid shapes, every step)")
    print(f"max core intrusion: {res.max_core_intrusion * 1000:.3f} mm (outer particles into own core)")
    print(f"slip in the hand:   {res.hold_slip * 1000:.3f} mm, turn {np.degrees(res.hold_turn):.2f} deg (over the hold)")
    print(f"cylinder tilt:      {np.degrees(res.max_tilt):.2f} deg (largest, lift and hold)")
    print(f"physics steps/s:    {res.steps_per_second:.0f} ({res.steps} steps in {res.seconds:.2f} s of stepping)")
    ok = res.held(plan)
    print("result:             " + ("HELD" if ok else "NOT HELD"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
