"""Where each method fails: the scripted grasp over grids of settings, every finger kind, same
scene, same policy, same seed, on the v3 physics (``SoftGraspEasy-v3``).

    PYTHONPATH=. python benchmarks/stability_map.py [--quick | --tiny] [--methods rigid,tissue,...]
        [--maps physics | v3 | all | name,name,...] [--name stability_map_v3]

The physics maps (the default, rows x columns; docs/results/stability_map.csv was made with them
on the physics of release 0.6.0's v1 ids, before the compliant material and the smooth arm; run
again, they map the v3 physics):
1. ``wedge_yaw``: jaw wedge (angle between the finger faces) x gripper yaw, lateral offset 5 mm;
2. ``offset_friction``: lateral offset along the finger face, up to past its end (the face is 4 cm
   long) x friction scale (tissue, rigid finger and ground coefficients together), no wedge;
3. ``dt_force``: physics time step (1/1000 to 1/60 s) x finger force;
4. ``mass_radius``: cylinder mass x cylinder radius.

The v3 maps (``--maps v3``; docs/results/stability_map_v3.csv): where the torsional peer
('rigid_torsion') might fail and the tissue hold. Every cell is aligned (yaw 0.05 rad, 5 mm start
offset, no wedge) unless the map says otherwise:
5. ``wedge_yaw_wide``: the jaw wedge over the whole range the scene accepts (+-pi/6, both signs)
   x yaw up to pi/4 (SceneConfig's limits);
6. ``aim_offset_wedge``: where along the face the grasp lands (the policy aims ``aim_offset``
   along the faces off the cylinder's axis: the start's lateral offset does not do this, the
   scripted policy centres the grip on the cylinder whatever the start) up to past the face's end
   (2 cm half face + 3 cm radius) x jaw wedge;
7. ``aim_offset_yaw``: the same offsets x yaw;
8. ``aim_height_wedge``: the grasp's height above the cylinder's centre (the policy aims there) x
   jaw wedge: a two-point grasp off the centre of mass needs torsion to keep the cylinder upright;
9. ``force_wedge``: finger force (down to 0.5 N) x jaw wedge, on the default cylinder;
10. ``radius_force``: small cylinders (down to 5 mm, the smallest radius SceneConfig takes) x
   finger force (down to 0.5 N);
11. ``radius_wedge``: small cylinders x jaw wedge at 3 N;
12. ``mass_friction``: heavier cylinders x friction scale, aligned;
13. ``mass_friction_wedge``: the same at a 0.15 rad wedge (the reach task's edge);
14. ``carry_wedge_freq``: the v3 carry test (``carry=True``, 1.5 s of sway from 3.5 s, success:
    held at every step and in-hand slide <= 5 mm) with the sway fixed by reset options - peak
    acceleration 1 m/s^2 across the jaw - x frequency (1.2-3.0 Hz, the v3 band) x jaw wedge;
15. ``carry_wedge_dir``: the carry at 1.9 Hz (the two-point pendulum), 1 m/s^2, x its direction
    (0 across the jaw, pi/2 along the closing axis) x jaw wedge;
16. ``carry_mass_wedge``: the carry at 1.9 Hz, 1 m/s^2, across, x cylinder mass x jaw wedge;
17. ``carry_aim_height``: the carry at 1.9 Hz, 1 m/s^2, across, x the grasp's height x jaw wedge;
18. ``carry_accel_wedge``: the carry's peak acceleration (0.5-1.4 m/s^2: the sway ramps in ~5 %
    above its steady peak, and the arm takes at most 1.5) x jaw wedge;
19.-22. ``carry_force_wedge``, ``carry_friction_wedge``, ``carry_radius_wedge``,
    ``carry_mass_force``: the carry at 1.9 Hz, 1 m/s^2, across, x finger force, friction scale,
    cylinder radius, each x jaw wedge, and cylinder mass x finger force.
The object is a cylinder: a tapered object (a cone's slanted side) is not modelled, and no map
pretends to test one (the jaw wedge tilts the faces against a straight side instead, which is the
same contact geometry up to the taper's angle).

A cell is one 5 s episode of SoftGraspEnv (``SoftGraspEasy-v3``, the gentle start: the open
fingers around the cylinder's top, so each cell tests the grasp, not the approach) with
softgrasp_env.policies.ScriptedGraspPolicy (``for_env``; below 1 N per finger its grip threshold is
half the finger force, ``policy_for``): 2 = held (lifted and held at the end; carry maps:
the v3 success, held through the whole carry with slide <= 5 mm), 1 = slipped (lifted, then lost;
carry maps: lifted, then lost or slid more than 5 mm in the carry), 0 = dropped (never lifted),
-1 = diverged, -2 = refused (gym.make or reset raises a ValueError: the setting is outside what the
method or the scene accepts, e.g. the consistent coupling's squeeze impulse limit, config.py).
Methods: the finger kinds of softgrasp_env.fingers.FINGERS, ours with both couplings and on the
v4 tissue ("tissue, v4": registration.TISSUE_V4, SoftGraspEasy-v4's physics) (the v3
maps leave out 'fem', V3_SKIP, unless --methods names it). Writes benchmarks/out/<name>.csv and
.png (one heatmap per method and map; ``--name``, default stability_map) and prints the grids;
the CSV's ``lift_mm``, ``tilt_deg`` and ``slide_mm`` are the last step's lift, the largest tilt
of the cylinder and (carry maps) the largest in-hand slide during the carry.
"""

from __future__ import annotations

import argparse
import csv
import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from agents.scripted import ScriptedGraspPolicy
from softgrasp_env.config import SimConfig
from softgrasp_env.fingers import FINGERS
from softgrasp_env.observation import CARRY_OBS_NAMES, OBS_NAMES
from softgrasp_env.registration import TISSUE_V4
from softgrasp_env.registration import make_as as make_env

OUT = Path(__file__).resolve().parent / "out"
LABELS = {2: "held", 1: "slipped", 0: "dropped", -1: "diverged", -2: "refused"}


TINY_SKIP = ("fem",)
"""Finger kinds the --tiny map leaves out: pybullet's FEM pads run at ~10 world steps/s (8
substeps of explicit elasticity, FemConfig.substeps), and the tiny map's two 5 s episodes
would add about 5 minutes to CI; tests/fingers/test_fem.py runs the fem grasp (marked slow)."""
V3_SKIP = ("fem",)
"""Finger kinds the v3 maps leave out unless --methods names them: the FEM pads' ~10 steps/s
would make the v3 maps' ~1,000 cells per method take hours."""


def methods(*, tiny: bool = False, skip: tuple[str, ...] = ()) -> dict[str, dict]:
    """Every method: env arguments (without TINY_SKIP's kinds if ``tiny``, nor ``skip``'s)."""
    out = {}
    for kind in FINGERS:
        if (tiny and kind in TINY_SKIP) or kind in skip:
            continue
        if kind == "tissue":
            out["tissue, thesis"] = dict(fingers="tissue")
            out["tissue, consistent"] = dict(fingers="tissue", sim=SimConfig(coupling="consistent"))
            out["tissue, v4"] = dict(fingers="tissue", **TISSUE_V4)
        else:
            out[kind] = dict(fingers=kind)
    return out


class AimedPolicy:
    """The scripted policy aiming ``along`` [m] along the finger faces and ``up`` [m] above the
    cylinder's centre instead of at it: it sees the cylinder where it would be if the grip were
    there, so the grasp lands off-centre by that much (the policy itself is unchanged; once it
    grips, it only lifts)."""

    def __init__(self, policy: ScriptedGraspPolicy, *, yaw: float, along: float, up: float, names: tuple[str, ...]) -> None:
        self.policy = policy
        k = names.index("cyl_rel_x")
        self.rel = slice(k, k + 3)
        self.shift = np.array([-math.sin(yaw) * along, math.cos(yaw) * along, up])

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        obs = np.array(obs, dtype=np.float64)
        obs[self.rel] += self.shift
        return self.policy(obs)


POLICY_ARGS = ("aim_offset", "aim_height")
"""Grid parameters of the policy (AimedPolicy), not of the env."""


@dataclass(frozen=True)
class Cell:
    """One episode's result."""

    outcome: int
    lift_mm: float = float("nan")
    tilt_deg: float = float("nan")
    slide_mm: float = float("nan")


def episode(env, options: dict, policy) -> Cell:
    """One 5 s episode: held / slipped / dropped / diverged (module docstring)."""
    aim = {k: options.pop(k) for k in POLICY_ARGS if k in options}
    try:
        obs, _ = env.reset(seed=0, options=options)
    except ValueError:  # outside what the scene accepts (SceneConfig's limits)
        return Cell(-2)
    if aim:
        names = CARRY_OBS_NAMES if len(obs) == len(CARRY_OBS_NAMES) else OBS_NAMES
        policy = AimedPolicy(policy, yaw=env.unwrapped.scene.config.yaw, along=aim.get("aim_offset", 0.0),
                             up=aim.get("aim_height", 0.0), names=names)  # fmt: skip
    axis_z = OBS_NAMES.index("cyl_axis_z")
    ever, tilt = False, 0.0
    for _ in range(100):
        obs, _, term, trunc, info = env.step(policy(obs))
        ever |= info["held"]
        tilt = max(tilt, math.degrees(math.acos(float(np.clip(obs[axis_z], -1.0, 1.0)))))
        if info["diverged"]:
            return Cell(-1)
        if term or trunc:
            break
    slide = getattr(env.unwrapped.task, "slide", None)
    extra = dict(lift_mm=1000.0 * float(info["lift_height"]), tilt_deg=tilt,
                 slide_mm=float("nan") if slide is None else 1000.0 * slide)  # fmt: skip
    if info["is_success"]:
        return Cell(2, **extra)
    return Cell(1 if ever else 0, **extra)


GRIP_FORCE = 0.5
"""The scripted policy's default grip threshold [N]: it lifts once both fingers press this hard."""


def policy_for(env) -> ScriptedGraspPolicy:
    """The env's scripted policy, its grip threshold at most half the finger force: at 0.5 N per
    finger the default threshold (0.5 N) is the motor's whole force, the contact force dips below
    it and the policy never lifts, or lifts by chance (the consistent coupling once "held" 0.1 kg
    at 0.5 N, below Coulomb's 0.55 N, with it; every method agrees with Coulomb at 0.25 N)."""
    force = env.unwrapped.args.control.finger_force
    return ScriptedGraspPolicy.for_env(env, grip_force=min(GRIP_FORCE, 0.5 * force))


MAKE_ARGS = ("finger_force", "dt")
"""Grid parameters that are env arguments (a new env per cell), not reset options."""


def grid(make: dict, rows: tuple[str, list[float]], cols: tuple[str, list[float]], fixed: dict,
         env_id: str = "SoftGraspEasy-v3") -> list[list[Cell]]:  # fmt: skip
    out = [[Cell(-2)] * len(cols[1]) for _ in rows[1]]
    env, key = None, None
    for i, rv in enumerate(rows[1]):
        for j, cv in enumerate(cols[1]):
            cell = {**fixed, rows[0]: rv, cols[0]: cv}
            kwargs = dict(make)
            for name in MAKE_ARGS:
                if name in cell:
                    value = cell.pop(name)
                    if name == "dt":
                        kwargs["sim"] = replace(kwargs.get("sim", SimConfig()), dt=value)
                    else:
                        kwargs[name] = value
            if env is None or repr(kwargs) != key:
                if env is not None:
                    env.close()
                key = repr(kwargs)
                try:  # the physics map: fingers start around the cylinder
                    env = make_env(env_id, **kwargs)
                except ValueError:  # outside what this method accepts
                    env = None
            out[i][j] = Cell(-2) if env is None else episode(env, cell, policy_for(env))
    if env is not None:
        env.close()
    return out


@dataclass(frozen=True)
class Map:
    """A grid: ``rows`` x ``cols`` (parameter name, values; ``quick_*`` the coarser grid), the
    other settings ``fixed`` (reset options, MAKE_ARGS, POLICY_ARGS) and env arguments ``make``
    every method's are joined with (``carry=True`` for the carry maps)."""

    name: str
    rows: tuple[str, list[float]]
    cols: tuple[str, list[float]]
    fixed: dict
    quick_rows: list[float] | None = None
    quick_cols: list[float] | None = None
    make: dict = field(default_factory=dict)

    def grid(self, quick: bool) -> tuple[tuple[str, list[float]], tuple[str, list[float]]]:
        rows = (self.rows[0], self.quick_rows if quick and self.quick_rows is not None else self.rows[1])
        cols = (self.cols[0], self.quick_cols if quick and self.quick_cols is not None else self.cols[1])
        return rows, cols


CENTRED = {"cylinder_xy": (0.0, 0.0)}
ALIGNED = {"yaw": 0.05, "lateral_offset": 0.005, "jaw_wedge": 0.0, **CENTRED}
"""The aligned start (the physics maps' fixed settings)."""
WEDGE_MAX = math.pi / 6
"""The largest jaw wedge SceneConfig takes [rad]."""
YAW_MAX = math.pi / 4
"""The largest yaw SceneConfig takes [rad]."""
CARRY = {"carry": True}
SWAY = {"carry_frequency": 1.9, "carry_acceleration": 1.0, "carry_direction": 0.0}
"""The carry maps' sway unless a map varies it: at the two-point grasp's pendulum frequency, the v3
range's largest peak acceleration, across the jaw (where a two-point grasp swings)."""

PHYSICS_MAPS = (
    Map("wedge_yaw", ("jaw_wedge", [0.0, 0.025, 0.05, 0.1, 0.2, 0.3, 0.45]), ("yaw", [0.0, 0.1, 0.2, 0.3]),
        {"lateral_offset": 0.005, **CENTRED}, [0.0, 0.05, 0.2, 0.45], [0.0, 0.2]),
    Map("offset_friction", ("lateral_offset", [0.0, 0.01, 0.02, 0.025, 0.03]),
        ("friction_scale", [0.2, 0.3, 0.5, 0.75, 1.0]), {"yaw": 0.0, "jaw_wedge": 0.0, **CENTRED},
        [0.0, 0.02, 0.03], [0.3, 1.0]),
    Map("dt_force", ("dt", [1 / 1000, 1 / 480, 1 / 240, 1 / 120, 1 / 60]), ("finger_force", [1.0, 3.0, 6.0, 10.0, 20.0]),
        {"yaw": 0.05, "lateral_offset": 0.005, "jaw_wedge": 0.0, **CENTRED}, [1 / 1000, 1 / 240, 1 / 60], [1.0, 10.0]),
    Map("mass_radius", ("cylinder_mass", [0.05, 0.1, 0.2, 0.4, 0.6]), ("cylinder_radius", [0.015, 0.02, 0.03, 0.04]),
        {"yaw": 0.05, "lateral_offset": 0.005, "jaw_wedge": 0.0, **CENTRED}, [0.05, 0.4], [0.02, 0.04]),
)  # fmt: skip

WEDGES = [-WEDGE_MAX, -0.45, -0.3, -0.15, -0.05, 0.0, 0.05, 0.15, 0.3, 0.45, WEDGE_MAX]
"""Both signs: a positive wedge opens the gap at the top (the faces touch with their lower edges)."""
WEDGES_QUICK = [-WEDGE_MAX, -0.15, 0.0, 0.15, WEDGE_MAX]
OFFSETS = [0.0, 0.01, 0.02, 0.025, 0.03, 0.035, 0.04, 0.045]
"""Along the face (2 cm half length): past its end from 2 cm; the 3 cm cylinder still reaches it up to 5 cm."""
HEIGHTS = [-0.005, 0.0, 0.01, 0.02, 0.03, 0.04]
"""The grasp's height above the cylinder's centre [m]: the open fingertips (3 cm half height, the
pad below) reach the ground from about 1 cm below the centre; at 4 cm the faces' lower half still
touches the 10 cm cylinder."""
HEIGHTS_QUICK = [-0.005, 0.02, 0.04]
FORCES = [0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 6.0]
"""Per finger [N]: Coulomb's bound for the 0.1 kg cylinder, m g / 2 mu, is 0.55 N."""

V3_MAPS = (
    Map("wedge_yaw_wide", ("jaw_wedge", WEDGES), ("yaw", [0.0, 0.2, 0.4, 0.6, YAW_MAX]),
        {"lateral_offset": 0.005, **CENTRED}, WEDGES_QUICK, [0.0, YAW_MAX]),
    Map("aim_offset_wedge", ("aim_offset", OFFSETS), ("jaw_wedge", [-0.3, -0.15, 0.0, 0.15, 0.3]),
        {**ALIGNED}, [0.0, 0.02, 0.03, 0.04], [-0.15, 0.0, 0.15]),
    Map("aim_offset_yaw", ("aim_offset", OFFSETS), ("yaw", [0.0, 0.2, 0.4, YAW_MAX]),
        {**ALIGNED}, [0.0, 0.02, 0.03, 0.04], [0.0, YAW_MAX]),
    Map("aim_height_wedge", ("aim_height", HEIGHTS), ("jaw_wedge", [-WEDGE_MAX, -0.3, -0.15, 0.0, 0.15, 0.3, WEDGE_MAX]),
        {**ALIGNED}, HEIGHTS_QUICK, [-0.3, 0.0, 0.3]),
    Map("force_wedge", ("finger_force", FORCES), ("jaw_wedge", [-WEDGE_MAX, -0.3, -0.15, 0.0, 0.15, 0.3, WEDGE_MAX]),
        {**ALIGNED}, [0.75, 1.0, 3.0], [-0.3, 0.0, 0.3]),
    Map("radius_force", ("cylinder_radius", [0.005, 0.0075, 0.01, 0.015, 0.02, 0.03]),
        ("finger_force", [0.5, 0.75, 1.0, 1.5, 2.0, 3.0]), {**ALIGNED}, [0.005, 0.01, 0.03], [0.5, 1.0, 3.0]),
    Map("radius_wedge", ("cylinder_radius", [0.005, 0.0075, 0.01, 0.015, 0.02, 0.03]),
        ("jaw_wedge", [-0.3, -0.15, -0.05, 0.0, 0.05, 0.15, 0.3]), {**ALIGNED}, [0.005, 0.01, 0.03], [-0.15, 0.0, 0.15]),
    Map("mass_friction", ("cylinder_mass", [0.1, 0.2, 0.3, 0.4, 0.5]), ("friction_scale", [0.3, 0.4, 0.5, 0.75, 1.0]),
        {**ALIGNED}, [0.1, 0.3, 0.5], [0.3, 1.0]),
    Map("mass_friction_wedge", ("cylinder_mass", [0.1, 0.2, 0.3, 0.4, 0.5]),
        ("friction_scale", [0.3, 0.4, 0.5, 0.75, 1.0]), {**ALIGNED, "jaw_wedge": 0.15}, [0.1, 0.3, 0.5], [0.3, 1.0]),
    Map("carry_wedge_freq", ("jaw_wedge", WEDGES), ("carry_frequency", [1.2, 1.5, 1.9, 2.4, 3.0]),
        {**ALIGNED, **SWAY}, WEDGES_QUICK, [1.2, 1.9, 3.0], CARRY),
    Map("carry_wedge_dir", ("jaw_wedge", WEDGES), ("carry_direction", [0.0, math.pi / 4, math.pi / 2]),
        {**ALIGNED, **SWAY}, WEDGES_QUICK, [0.0, math.pi / 2], CARRY),
    Map("carry_mass_wedge", ("cylinder_mass", [0.1, 0.2, 0.3, 0.4]), ("jaw_wedge", [-0.3, -0.15, 0.0, 0.15, 0.3]),
        {**ALIGNED, **SWAY}, [0.1, 0.3], [-0.15, 0.0, 0.15], CARRY),
    Map("carry_aim_height", ("aim_height", HEIGHTS), ("jaw_wedge", [-WEDGE_MAX, -0.3, -0.15, 0.0, 0.15, 0.3, WEDGE_MAX]),
        {**ALIGNED, **SWAY}, HEIGHTS_QUICK, [-0.3, 0.0, 0.3], CARRY),
    Map("carry_accel_wedge", ("carry_acceleration", [0.5, 0.75, 1.0, 1.25, 1.4]), ("jaw_wedge", WEDGES),
        {**ALIGNED, **SWAY}, [0.5, 1.4], WEDGES_QUICK, CARRY),
    Map("carry_force_wedge", ("finger_force", FORCES), ("jaw_wedge", [-WEDGE_MAX, -0.3, -0.15, 0.0, 0.15, 0.3, WEDGE_MAX]),
        {**ALIGNED, **SWAY}, [0.75, 1.0, 3.0], [-0.3, 0.0, 0.3], CARRY),
    Map("carry_friction_wedge", ("friction_scale", [0.25, 0.3, 0.4, 0.5, 0.75, 1.0]),
        ("jaw_wedge", [-WEDGE_MAX, -0.3, -0.15, 0.0, 0.15, 0.3, WEDGE_MAX]), {**ALIGNED, **SWAY}, [0.3, 1.0],
        [-0.3, 0.0, 0.3], CARRY),
    Map("carry_radius_wedge", ("cylinder_radius", [0.005, 0.0075, 0.01, 0.015, 0.02, 0.03]),
        ("jaw_wedge", [-WEDGE_MAX, -0.3, -0.15, 0.0, 0.15, 0.3, WEDGE_MAX]), {**ALIGNED, **SWAY}, [0.005, 0.03],
        [-0.3, 0.0, 0.3], CARRY),
    Map("carry_mass_force", ("cylinder_mass", [0.05, 0.1, 0.2, 0.3, 0.4]), ("finger_force", FORCES),
        {**ALIGNED, **SWAY, "jaw_wedge": 0.3}, [0.1, 0.3], [1.0, 3.0], CARRY),
)  # fmt: skip

TINY_MAPS = (  # CI: the wedge where rigid blocks fail and tissue holds
    Map("tiny", ("jaw_wedge", [0.0, 0.1]), ("yaw", [0.1]), {"lateral_offset": 0.005, **CENTRED}),
)
MAP_GROUPS = {"physics": PHYSICS_MAPS, "v3": V3_MAPS, "all": PHYSICS_MAPS + V3_MAPS}
ALL_MAPS = {m.name: m for m in PHYSICS_MAPS + V3_MAPS}


def choose_maps(spec: str, *, tiny: bool) -> tuple[Map, ...]:
    """``--maps``: a group (physics, v3, all) or comma-separated map names; --tiny alone: the CI map."""
    if tiny and not spec:
        return TINY_MAPS
    out: list[Map] = []
    for part in (spec or "physics").split(","):
        if part in MAP_GROUPS:
            out += MAP_GROUPS[part]
        elif part in ALL_MAPS:
            out.append(ALL_MAPS[part])
        else:
            raise ValueError(f"unknown map {part!r}; choose a group {sorted(MAP_GROUPS)} or maps {sorted(ALL_MAPS)}")
    return tuple(out)


def maps(quick: bool, tiny: bool) -> list[tuple[str, list, str, list, dict]]:
    """The physics maps (or the tiny one) as (row name, row values, column name, column values, fixed)."""
    return [(*m.grid(quick)[0], *m.grid(quick)[1], m.fixed) for m in (TINY_MAPS if tiny else PHYSICS_MAPS)]


ALIASES = {"thesis": "tissue, thesis", "consistent": "tissue, consistent", "tissue": "tissue, thesis"}
"""Short names --methods takes for ours ("tissue, thesis" has a comma of its own)."""


def split_methods(spec: str) -> list[str]:
    """--methods' names: comma-separated, where a part starting with a space continues the one
    before ("tissue, thesis,rigid" is two methods); ALIASES' short names are taken too."""
    names: list[str] = []
    for part in spec.split(","):
        if part.startswith(" ") and names:
            names[-1] += "," + part
        else:
            names.append(part)
    return [ALIASES.get(n.strip(), n.strip()) for n in names]


def _fmt(v: float) -> str:
    return f"{v:.6g}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="coarser grids")
    parser.add_argument("--tiny", action="store_true", help="the CI smoke run: one wedge row")
    parser.add_argument("--methods", default="", help="comma-separated subset of the methods (thesis, consistent: ours with each coupling)")
    parser.add_argument("--maps", default="", help="physics (default), v3, all, or comma-separated map names: "
                        + ", ".join(ALL_MAPS))  # fmt: skip
    parser.add_argument("--name", default="stability_map", help="stem of the CSV and PNG written")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    try:
        chosen_maps = choose_maps(args.maps, tiny=args.tiny)
    except ValueError as e:
        parser.error(str(e))
    v3 = any(m in V3_MAPS for m in chosen_maps)
    every = methods(tiny=args.tiny and not args.methods)  # named explicitly, fem runs even in --tiny
    if args.methods:
        names = split_methods(args.methods)
        unknown = set(names) - set(every)
        if unknown:
            parser.error(f"unknown methods {sorted(unknown)}; choose from {sorted(every)}")
        chosen = {k: every[k] for k in names}
    else:
        chosen = methods(tiny=args.tiny, skip=V3_SKIP if v3 else ())
    args.out.mkdir(parents=True, exist_ok=True)
    rows_csv, results = [], []
    t_start = time.perf_counter()
    for m in chosen_maps:
        (rname, rvals), (cname, cvals) = m.grid(args.quick)
        for name, make in chosen.items():
            t0 = time.perf_counter()
            g = grid({**make, **m.make}, (rname, rvals), (cname, cvals), m.fixed)
            codes = np.array([[c.outcome for c in line] for line in g], dtype=int)
            results.append((m.name, name, rname, rvals, cname, cvals, codes))
            print(f"\n[{m.name}] {name}: rows {rname}, columns {cname} (2 held, 1 slipped, 0 dropped, -1 diverged, "
                  f"-2 refused; {time.perf_counter() - t0:.0f} s)")  # fmt: skip
            print(" " * 10 + "".join(f"{c:>8.4g}" for c in cvals))
            for rv, line in zip(rvals, g, strict=True):
                print(f"{rv:>10.4g}" + "".join(f"{c.outcome:>8d}" for c in line), flush=True)
                rows_csv += [(m.name, name, rname, _fmt(rv), cname, _fmt(cv), c.outcome, LABELS[c.outcome],
                              f"{c.lift_mm:.1f}", f"{c.tilt_deg:.1f}", f"{c.slide_mm:.2f}")
                             for cv, c in zip(cvals, line, strict=True)]  # fmt: skip
    print(f"\n{len(rows_csv)} cells in {time.perf_counter() - t_start:.0f} s")
    with open(args.out / f"{args.name}.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["map", "method", "row_param", "row_value", "col_param", "col_value", "outcome", "label",
                    "lift_mm", "tilt_deg", "slide_mm"])  # fmt: skip
        w.writerows(rows_csv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n_maps = len(results) // len(chosen)
    fig, axes = plt.subplots(n_maps, len(chosen), figsize=(3.6 * len(chosen), 3.0 * n_maps), squeeze=False)
    for k, (mname, name, rname, rvals, cname, cvals, g) in enumerate(results):
        ax = axes[k // len(chosen), k % len(chosen)]
        cmap = plt.get_cmap("RdYlGn").copy()
        cmap.set_bad("lightgray")  # refused
        ax.imshow(np.ma.masked_less(g, -1), cmap=cmap, vmin=-1, vmax=2, origin="lower", aspect="auto")
        ax.set_xticks(range(len(cvals)), [f"{c:.3g}" for c in cvals], fontsize=7)
        ax.set_yticks(range(len(rvals)), [f"{r:.3g}" for r in rvals], fontsize=7)
        ax.set_xlabel(cname, fontsize=8)
        ax.set_ylabel(rname, fontsize=8)
        ax.set_title(f"{name} [{mname}]", fontsize=9)
    fig.suptitle("Scripted grasp: green held, yellow slipped, orange dropped, red diverged, grey refused")
    fig.tight_layout()
    fig.savefig(args.out / f"{args.name}.png", dpi=90 if n_maps <= 4 else 60)
    print(f"\nwrote {args.out / (args.name + '.csv')} and {args.out / (args.name + '.png')}")


if __name__ == "__main__":
    main()
