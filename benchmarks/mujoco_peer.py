"""MuJoCo peer: our scripted grasp built in MuJoCo (4.x) with ``flexcomp`` soft pads, to set its speed
and accuracy beside our tissue's. Same scene, same material, same script, same figures.

    PYTHONPATH=. python benchmarks/mujoco_peer.py [--levels 30,100,570,3800] [--dofs full,trilinear]
        [--rows rig,grasp,bound,dt,condim] [--dt 1/240] [--budget 100] [--out benchmarks/out]

The scene (SI units; every size is read from SceneConfig / TissueConfig, so it stays ours):

- ground plane at z = 0; cylinder radius 0.03 m, height 0.10 m, 0.1 kg, upright at the origin (a free
  body), ground friction 0.5;
- palm: box half extents PALM_HALF_EXTENTS, 0.5 kg, on a slide joint along z, driven by a stiff position
  servo (25 Hz on the rigid gripper: kp 14,800 N/m, kv 188 N s/m, critically damped; ``ARM_PUSH`` = 40 N
  force limit) whose setpoint is our own arm path (softgrasp_env.scene.gripper.PalmPath, same speed and
  acceleration limits) fed by the same targets as accuracy.run_grasp; the servo is fed the path's
  velocity too, so it follows without lag.
  The rigid gripper's weight is compensated (``gravcomp``), as our arm does (``arm_force`` = weight + 40 N);
- two finger cores, boxes half extents (0.008, 0.02, 0.03) m, 0.05 kg each, on slide joints along x
  under the palm, open so their inner faces are ``finger_stroke`` (60 mm) from the centre, travel limited
  to where the pads meet; a joint equality keeps their travels equal (our gripper's gear);
- each core pushed by a velocity servo that closes at up to ``finger_speed`` (0.1 m/s) toward the
  commanded travel with a ``forcerange`` of +-3 N: our force-limited position motors, commanded past
  contact, so the squeeze is the force limit, 3 N per finger;
- pads: an 8 mm (``TissueConfig.extrude``, the finite-element reference's thickness) ``flexcomp`` grid,
  ``dim=3``, on each core's inner face, covering it (40 x 60 mm), nodes on the core's face pinned to the
  core. Elasticity ``young`` = 2 G (1 + nu) = 8,000 Pa from G = 4,000 Pa, ``poisson`` = 0, mass
  1000 kg/m^3 x the pad's volume, 19.2 g a pad. flexcomp gives every grid point an equal share and drops
  the pinned ones', so full pads move (nx - 1) / nx of it (9.6 g at 2 layers, 12.8 g at 3); trilinear
  ones lump all 19.2 g on their free nodes (measured on the built models).
  Resolution ``nx x ny x nz`` grid points (through thickness x across width x along height); the levels
  30 (2x3x5), 100 (2x5x10), 570 (3x10x19), 3800 (5x20x38) nodes a pad match our tissue's 60 / 200 /
  1,140 / 7,600 particles over both pads. ``dof="full"``: every free grid point is a body with three
  slide joints. ``dof="trilinear"``: the grid points are only the collision mesh; the degrees of freedom
  are the nodes of a background grid of ``cellcount`` cells, by default one cell per grid gap, so the
  level's node count is the trilinear flex's node count too (``cells`` sets a coarser grid).

Options, and why (MuJoCo 4.0.1):

- ``integrator="discrete"``: MuJoCo 4 refuses 2-D / 3-D flex elasticity under ``implicit`` and
  ``implicitfast`` ("flex elasticity is no longer integrated implicitly", an engine error at the first
  step); ``Euler`` integrates it explicitly and blew up within 0.1 s at dt 1/480 and 1/960 (100-node
  pad). ``discrete`` folds the flex stiffness into the solver's metric (implicit in position), so the
  pads are stable at every dt tried, 1/240 s included.
- ``solver="Newton"`` (the default; under ``discrete`` it supports flex nodes attached to jointed bodies),
  ``iterations`` 100, ``tolerance`` 1e-8 (defaults).
- ``noslip_iterations`` 0: MuJoCo rejects the noslip post-pass with flex elasticity under ``discrete``
  ("discrete integrator: PGS and noslip not yet supported with flex"). What noslip would remove, friction
  creep of the soft contacts, is kept small by ``impratio`` and the contact settings below.
- ``cone="elliptic"``: Coulomb's circular cone per contact, as ours. ``impratio`` 10 (MuJoCo's gripper
  examples' value): friction rows 10x harder than the normal ones. Soft friction rows let a loaded contact
  creep: over the 2 s hold of 0.1 kg (30-node trilinear pads) the cylinder crept 0.76 mm at impratio 1,
  0.08 at 10 and 0.012 at 100; at 0.47 kg 0.4-0.55 mm at 10 and 0.07 at 100. 100 moved the hold bound by
  1.4 % (0.475 -> 0.482 kg) but halved the full 100-node grasp's speed (260-278 -> 138-145 steps/s,
  interleaved runs), so 10 it is (``--impratio`` to change it).
- ``condim`` 3 on the pads (sliding friction only, as our tissue's contacts); ``--condim 4`` / ``6`` add
  MuJoCo's default torsional (0.005 m) and rolling (0.0001 m) coefficients (row ``condim``).
- ``solref`` = (2 dt, 1) on every contact: the stiffest time constant MuJoCo's guidance gives for the step,
  critically damped. Measured on the 100-node trilinear grasp at dt 1/480: stiffer than the step resolves
  (0.002 s, which ``refsafe`` replaces) the hold crept 3.6 mm in 2 s; 0.005 s crept 0.11 mm with 0.29 mm
  of contact overlap; 0.02 s (the default) crept 0.06 mm but overlapped 0.9 mm.
  ``solimp`` (0.99, 0.9999, 0.1 mm): impedance near 1 so the soft contact's own give stays small next to
  the pad's deformation (MuJoCo's default (0.9, 0.95, 1 mm) with 0.02 s overlapped 3.3 mm and crept 1.8 mm).
- flex ``radius`` 0 (allowed in 3-D) and ``margin`` 0: the contact surface is the tetrahedra's own, so
  "first touch" of the undeformed pad is at the core's face + 8 mm. With a radius r > 0 it is at
  8 mm + r (+ margin); the rig measures from ``face + pad + radius + margin`` to handle either (at 1 N,
  30-node pads: r = 0 / 0.5 / 1 mm read 1.137 / 1.134 / 1.130 mm trilinear, 0.920 / 0.920 / 0.918 full).
  ``selfcollide="none"``: the pads never fold onto themselves here.
- elasticity ``damping`` 0.004 s (Rayleigh, stiffness-proportional): the pad's first mode (the layer's
  shear, (pi / 2) sqrt(G / rho) / h = 390 rad/s) then decays at beta omega^2 / 2 = 300 /s, our tissue's
  damping (SimConfig.damping).
- contact filtering (contype / conaffinity): pads touch the cylinder only (not their own core, the palm or
  the ground); cores and palm touch the cylinder and the ground. Pad friction 0.9 (TissueConfig), core
  and palm 0.9, cylinder and ground 0.5; MuJoCo takes the larger of two, so pad-cylinder is 0.9 and
  cylinder-ground 0.5.

Three MuJoCo limits shape what the figures mean (all measured here, see the docs and changelog of 4.0):

- ``dof="full"`` pads are Saint Venant-Kirchhoff: with nu = 0 a uniaxial nominal stress peaks at
  E / (3 sqrt 3) = 0.19 E (1,540 Pa) at 42 % compression and then falls, so the whole 40 x 60 mm face
  carries at most 3.7 N before it collapses and a cylinder's line contact much less: the coarse pads
  bottom out between 2 and 3 N in the rig, and at the grasp's 3 N they are crushed to the core (the
  cylinder then rests on the pinned layer and the cores). Crushed, the 100-node pads wrap the cylinder
  and pinch it across the face: they held 1.5 kg (three times Coulomb's bound), their contacts' normal
  forces summing to 17.6 N against the 6 N squeeze, none of them vertical. ``dof="trilinear"`` pads stay
  linear (a single cell's compression grows in proportion to the load) and do not collapse up to 6 N.
- ``dof="trilinear"`` pads whose parent body has a joint (our fingers): MuJoCo applies the pad's elastic
  reaction to the finger through the pinned nodes, but not the opposite share through the free nodes,
  which are the finger's children; the finger felt the pad's force twice and squeezed the cylinder with
  1.5 N instead of 3. ``hoist`` (default for trilinear) moves the free node bodies to the world body after
  the first compile (same places, same joints), so only the pinned nodes tie the pad to the finger: the
  squeeze is then 3.0 N. ``dof="full"`` pads balance as they are (the finger's generalized passive
  force is 0) and are left under the finger.
- trilinear (interpolated) flexes keep at most ``mjMAXCONPAIR`` = 50 contacts against one geom (MuJoCo
  4.0 changelog); a pad whose contact strip holds more surface elements than that loses the rest and the
  cylinder sinks between them: the 570-node trilinear pad let it 1.2 / 5.3 / 7.3 mm into its surface at
  1 / 3 / 6 N in the rig and dropped it in the grasp (the full 570-node pad had 123 contacts at 1 N).

Rows (``--rows``):

- ``rig``: one pad, its core fixed, gravity off, a frictionless (condim 1) rigid cylinder (radius 0.03 m,
  80 mm long, its axis along the face's height) on a slide joint along x, pushed into the pad by 1, 3 and
  6 N (ramped over 0.2 s, held 0.5 s, joint damping 20 N s/m so it comes to rest). Compression = the
  cylinder's travel from first touching the undeformed pad (PadRig in spatial_convergence.py), against
  the plane-strain finite-element reference at nu = 0 (pad_reference.py): 1.344 / 2.865 / 4.603 mm.
  The load the contacts put on the cylinder at rest is read back (load balance) with the deepest overlap.
- ``grasp``: accuracy.GraspPlan's defaults (approach 0.5 s, squeeze 0.6 s, lift 0.05 m in 1 s minimum
  jerk, hold 2 s): held (lifted >= 80 % at the end and through the hold, tilt <= 45 deg: GraspRecord.held),
  in-hand motion (largest distance of the cylinder's centre in the palm's frame from the start of the
  lift to the end), slip through the hold, largest tilt, deepest contact overlap of pads or cores with the
  cylinder (includes the flat facets' chord depth against the curved cylinder), the pad compression at the
  end of the squeeze (pad - gap between core face and cylinder), the squeeze (closing-direction force) each pad and
  core puts on the cylinder then, and speed: simulated seconds per wall second and physics steps per second, timing
  mj_step alone (one thread: MuJoCo steps a model single-threaded). A grasp whose projected wall time
  exceeds ``--budget`` seconds is stopped after 0.05 s simulated and reports its speed only; so is the rig
  after its first 0.1 s (the cylinder on the pad by then).
- ``bound``: the heaviest cylinder the grasp holds (held, and slipping < 1 mm through the hold, as
  GraspRecord.holds_without_slip), geometric bisection over 0.05-1.5 kg to 2 % (accuracy.find_hold_bound),
  over Coulomb's 2 mu F / (g + a), a the palm's peak acceleration during lift and hold (its velocity change
  over 0.02 s, while it carries the cylinder; grasp_checks.hold_bound takes it over the whole episode).
  Only where one grasp takes less than ``--bound-budget`` seconds.
- ``dt``: the grasp at dt 1/240, 1/480, 1/960, 1/1920 s; prints the largest at which it held.
- ``condim``: the grasp with condim 3, 4 and 6 on the pads.

Printed: a table, one row per dof x level (and one per dt / condim in those rows); CSV to
``--out``/mujoco_peer.csv (and mujoco_peer_dt.csv, mujoco_peer_condim.csv).
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import platform
import re
import tempfile
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field, replace
from fractions import Fraction
from pathlib import Path

import numpy as np

from softgrasp_env.accuracy import GraspPlan, _min_jerk, _min_jerk_rate, find_hold_bound  # the lift's profile, ours
from softgrasp_env.config import SimConfig, TissueConfig
from softgrasp_env.scene import FINGER_DROP, PALM_HALF_EXTENTS, GripperControl, SceneConfig
from softgrasp_env.scene.config import ARM_PUSH
from softgrasp_env.scene.gripper import PalmPath

OUT = Path(__file__).resolve().parent / "out"
SCENE = SceneConfig()
TISSUE = TissueConfig()
GRAVITY = SimConfig().gravity
PAD = TISSUE.extrude
"""The pad's thickness [m]: 8 mm, the finite-element reference's layer."""
POISSON = 0.0
YOUNG = 2.0 * TISSUE.shear_modulus * (1.0 + POISSON)
"""Young's modulus of the pads [Pa]: 8,000 from G = 4,000 Pa, nu = 0."""
MU = TISSUE.friction_static
LEVELS: dict[str, tuple[int, int, int]] = {"30": (2, 3, 5), "100": (2, 5, 10), "570": (3, 10, 19), "3800": (5, 20, 38)}
"""Grid points a pad (through thickness x across width x along height), named by their count."""
TISSUE_PARTICLES = {"30": 60, "100": 200, "570": 1140, "3800": 7600}
"""Our tissue's particles over both pads at the matching density."""
REFERENCE_MM = {1.0: 1.344, 3.0: 2.865, 6.0: 4.603}
"""Plane-strain finite-element compression of the pad at nu = 0 [mm] (benchmarks/pad_reference.py)."""
LOADS = (1.0, 3.0, 6.0)
DTS = (1 / 240, 1 / 480, 1 / 960, 1 / 1920)
DEFAULT_DT = 1 / 240
"""The largest dt tried: the grasp held at it with 30- and 100-node pads of both dofs (row ``dt``) and
with 570-node full ones."""
ARM_OMEGA = 2.0 * math.pi * 25.0
"""Natural frequency of the palm's servo [rad/s]: stiff next to the lift (its peak 0.3 m/s^2 lags by
microns), soft enough to leave the cylinder's load visible."""
FINGER_GAIN = 24.0
"""The finger servos' speed per metre of travel error [1/s]: pybullet's position motor's default gain
(0.1 of the error per step at 1/240 s), capped at ``finger_speed``."""
FINGER_KV = 60.0
"""Velocity servo gain of a finger [N s/m]: 0.1 m/s short of its command it pushes 6 N, so against the
cylinder it sits at the 3 N limit."""
RIG_DAMPING = 20.0
"""Joint damping of the rig's cylinder [N s/m], about critical on the pad (it does not change the rest)."""
SLIP = 1e-3
ACCEL_WINDOW = 0.02
"""The palm's acceleration is its velocity change over this long [s] (5 steps at 1/240 s, as
grasp_checks' cylinder_peak_acceleration): a contact's step-to-step jitter is not a load."""
"""The bound's slip limit through the hold [m] (GraspRecord.holds_without_slip)."""
CONTYPE = {"ground": (1, 1), "cylinder": (3, 3), "pad": (2, 0), "rigid": (4, 1)}
"""(contype, conaffinity) per kind of collider: pads meet the cylinder only."""


def parse_dt(text: str) -> float:
    """'1/480' or '0.002' [s]."""
    return float(Fraction(text)) if "/" in text else float(text)


def level_counts(level: str) -> tuple[int, int, int]:
    """Grid points of a named level ('30', '100', '570', '3800') or 'NXxNYxNZ' (e.g. '3x6x9')."""
    if level in LEVELS:
        return LEVELS[level]
    m = re.fullmatch(r"(\d+)x(\d+)x(\d+)", level)
    if not m or min(int(v) for v in m.groups()) < 2:
        raise ValueError(f"level must be one of {', '.join(LEVELS)} or NXxNYxNZ with each >= 2, got {level!r}")
    return tuple(int(v) for v in m.groups())  # type: ignore[return-value]


@dataclass(frozen=True)
class PeerConfig:
    """One MuJoCo build of the scene (SI units)."""

    counts: tuple[int, int, int] = LEVELS["30"]
    """Grid points a pad: through the thickness (x), across the width (y), along the height (z)."""
    dof: str = "full"
    """flexcomp ``dof``: 'full' or 'trilinear'."""
    cells: tuple[int, int, int] | None = None
    """Trilinear only: ``cellcount``; None, one cell per grid gap (nodes = grid points)."""
    dt: float = DEFAULT_DT
    condim: int = 3
    impratio: float = 10.0
    timeconst: float | None = None
    """Contact solref time constant [s]; None: 2 dt."""
    solimp: tuple[float, ...] = (0.99, 0.9999, 0.0001, 0.5, 2.0)
    radius: float = 0.0
    """Flex element radius [m]: inflates the pad's contact surface."""
    margin: float = 0.0
    damping: float = 0.004
    """Rayleigh damping of the elasticity [s]."""
    cylinder_mass: float = SCENE.cylinder_mass
    iterations: int = 100
    tolerance: float = 1e-8
    noslip_iterations: int = 0
    hoist: bool = True
    """Trilinear pads on a jointed finger: move their free nodes to the world body (see the docstring)."""

    def __post_init__(self) -> None:
        if self.dof not in ("full", "trilinear"):
            raise ValueError(f"dof must be 'full' or 'trilinear', got {self.dof!r}")
        if self.condim not in (1, 3, 4, 6):
            raise ValueError(f"condim must be 1, 3, 4 or 6, got {self.condim!r}")
        if len(self.counts) != 3 or min(self.counts) < 2:
            raise ValueError(f"counts needs 3 entries >= 2, got {self.counts!r}")

    @property
    def solref(self) -> tuple[float, float]:
        return (2.0 * self.dt if self.timeconst is None else self.timeconst, 1.0)

    @property
    def cellcount(self) -> tuple[int, int, int]:
        return self.cells or tuple(n - 1 for n in self.counts)  # type: ignore[return-value]

    @property
    def nodes_per_pad(self) -> int:
        """The pad's nodes, pinned ones included: grid points (full) or interpolation nodes (trilinear)."""
        if self.dof == "full":
            return int(np.prod(self.counts))
        return int(np.prod([c + 1 for c in self.cellcount]))


def _vec(v) -> str:
    return " ".join(f"{float(x):.10g}" for x in v)


def pad_xml(cfg: PeerConfig, name: str, side: int, *, condim: int | None = None, friction: float = MU) -> str:
    """A pad on a core's face: ``side`` +1 covers the core's +x face, -1 its -x face; the grid layer on
    the core's face is pinned to the core."""
    nx, ny, nz = cfg.counts
    hx, hy, hz = SCENE.finger_half_extents
    spacing = (PAD / (nx - 1), 2.0 * hy / (ny - 1), 2.0 * hz / (nz - 1))
    if cfg.dof == "trilinear":
        cx, cy, cz = cfg.cellcount
        i = 0 if side > 0 else cx  # the node layer on the core's face
        extra = f'cellcount="{cx} {cy} {cz}"'
        pin = f'<pin gridrange="{i} 0 0 {i} {cy} {cz}"/>'
    else:
        i = 0 if side > 0 else nx - 1
        extra = ""
        pin = f'<pin gridrange="{i} 0 0 {i} {ny - 1} {nz - 1}"/>'
    mass = TISSUE.mass_density * PAD * 4.0 * hy * hz
    contype, conaffinity = CONTYPE["pad"]
    return (
        f'<flexcomp name="{name}" type="grid" dim="3" dof="{cfg.dof}" {extra} count="{nx} {ny} {nz}" '
        f'spacing="{_vec(spacing)}" pos="{side * (hx + 0.5 * PAD):.10g} 0 0" radius="{cfg.radius:.10g}" '
        f'mass="{mass:.10g}">'
        f'<elasticity young="{YOUNG:.10g}" poisson="{POISSON:g}" damping="{cfg.damping:.10g}"/>'
        f'<contact selfcollide="none" contype="{contype}" conaffinity="{conaffinity}" '
        f'condim="{cfg.condim if condim is None else condim}" friction="{friction:g} 0.005 0.0001" '
        f'solref="{_vec(cfg.solref)}" solimp="{_vec(cfg.solimp)}" margin="{cfg.margin:.10g}"/>'
        f"{pin}</flexcomp>"
    )  # fmt: skip


def _option(cfg: PeerConfig, gravity: float) -> str:
    return (f'<option timestep="{cfg.dt:.17g}" integrator="discrete" solver="Newton" cone="elliptic" '
            f'impratio="{cfg.impratio:g}" iterations="{cfg.iterations}" tolerance="{cfg.tolerance:g}" '
            f'noslip_iterations="{cfg.noslip_iterations}" gravity="0 0 {-gravity:g}"/>'
            f'<default><geom solref="{_vec(cfg.solref)}" solimp="{_vec(cfg.solimp)}"/></default>')  # fmt: skip


def start_palm_z() -> float:
    """The palm's centre at the start [m]: the grip point start_height above the cylinder's middle."""
    return 0.5 * SCENE.cylinder_height + palm_offset() + SCENE.start_height


def palm_offset() -> float:
    """Height of the palm's centre above the finger cores' centres [m] (Gripper.palm_offset_of)."""
    return PALM_HALF_EXTENTS[2] + FINGER_DROP + SCENE.finger_half_extents[2]


def arm_gains() -> tuple[float, float]:
    """(kp [N/m], kv [N s/m]) of the palm's servo: ``ARM_OMEGA`` on the rigid gripper, critically damped."""
    m = SCENE.palm_mass + 2.0 * SCENE.finger_mass
    return m * ARM_OMEGA**2, 2.0 * m * ARM_OMEGA


def scene_xml(cfg: PeerConfig) -> str:
    """The grasp scene's MJCF."""
    hx, hy, hz = SCENE.finger_half_extents
    r, h = SCENE.cylinder_radius, SCENE.cylinder_height
    open_x = SCENE.finger_stroke + hx  # a core's centre when fully open
    travel = SCENE.finger_stroke - PAD  # closing stops where the pads meet (SceneConfig.finger_stop "pads")
    kp, kv = arm_gains()
    c = {k: f'contype="{a}" conaffinity="{b}"' for k, (a, b) in CONTYPE.items()}
    g_mu = SCENE.ground_friction
    f = SCENE.finger_force
    core = (f'<geom name="{{n}}core" type="box" size="{_vec((hx, hy, hz))}" mass="{SCENE.finger_mass:g}" '
            f'{c["rigid"]} friction="{MU:g} 0.005 0.0001"/>')  # fmt: skip
    return f"""<mujoco model="mujoco_peer">
{_option(cfg, GRAVITY)}
<worldbody>
  <geom name="ground" type="plane" size="1 1 0.1" {c["ground"]} friction="{g_mu:g} 0.005 0.0001"/>
  <body name="cylinder" pos="0 0 {0.5 * h:g}"><freejoint/>
    <geom name="cylinder" type="cylinder" size="{r:g} {0.5 * h:g}" mass="{cfg.cylinder_mass:.10g}" {c["cylinder"]}
          friction="{g_mu:g} 0.005 0.0001"/></body>
  <body name="palm" pos="0 0 {start_palm_z():.10g}" gravcomp="1">
    <joint name="arm" type="slide" axis="0 0 1"/>
    <geom name="palm" type="box" size="{_vec(PALM_HALF_EXTENTS)}" mass="{SCENE.palm_mass:g}" {c["rigid"]}
          friction="{MU:g} 0.005 0.0001"/>
    <body name="left" pos="{-open_x:.10g} 0 {-palm_offset():.10g}" gravcomp="1">
      <joint name="left" type="slide" axis="1 0 0" range="0 {travel:.10g}"/>
      {core.format(n="left_")}{pad_xml(cfg, "lpad", +1)}</body>
    <body name="right" pos="{open_x:.10g} 0 {-palm_offset():.10g}" gravcomp="1">
      <joint name="right" type="slide" axis="-1 0 0" range="0 {travel:.10g}"/>
      {core.format(n="right_")}{pad_xml(cfg, "rpad", -1)}</body>
  </body>
</worldbody>
<equality><joint joint1="left" joint2="right"/></equality>
<actuator>
  <position name="arm" joint="arm" kp="{kp:.10g}" kv="{kv:.10g}" forcelimited="true"
            forcerange="{-ARM_PUSH:g} {ARM_PUSH:g}"/>
  <velocity name="left" joint="left" kv="{FINGER_KV:g}" forcelimited="true" forcerange="{-f:g} {f:g}"/>
  <velocity name="right" joint="right" kv="{FINGER_KV:g}" forcelimited="true" forcerange="{-f:g} {f:g}"/>
</actuator>
</mujoco>"""  # fmt: skip


def rig_touch_x(cfg: PeerConfig) -> float:
    """The rig's cylinder centre when it first touches the undeformed pad [m]: core face + pad + the
    flex radius and margin (they inflate the pad's contact surface) + the cylinder's radius."""
    return SCENE.finger_half_extents[0] + PAD + cfg.radius + cfg.margin + SCENE.cylinder_radius


def rig_xml(cfg: PeerConfig) -> str:
    """The pad rig's MJCF: one pad on a fixed core, a frictionless cylinder on a slide joint along x."""
    hx, hy, hz = SCENE.finger_half_extents
    a, b = CONTYPE["cylinder"]
    return f"""<mujoco model="mujoco_peer_rig">
{_option(cfg, 0.0)}
<worldbody>
  <body name="core"><geom name="core" type="box" size="{_vec((hx, hy, hz))}" contype="4" conaffinity="0"/>
    {pad_xml(cfg, "pad", +1, condim=1, friction=0.0)}</body>
  <body name="cylinder" pos="{rig_touch_x(cfg) + 5e-4:.10g} 0 0">
    <joint name="push" type="slide" axis="1 0 0" damping="{RIG_DAMPING:g}"/>
    <geom name="cylinder" type="cylinder" size="{SCENE.cylinder_radius:g} {hz + 0.01:g}" mass="{SCENE.cylinder_mass:g}"
          contype="{a}" conaffinity="{b}" condim="1" friction="0 0 0"/></body>
</worldbody>
</mujoco>"""  # fmt: skip


def _hoisted(xml: str) -> str:
    """``xml`` with the pads' free node bodies moved from their finger to the world body, where they sit
    at the same place with the same three slide joints (see the module docstring: trilinear pads under
    a jointed body push their finger twice)."""
    import mujoco

    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "peer.xml")
        mujoco.mj_saveLastXML(path, model)
        root = ET.parse(path).getroot()
    world = root.find("worldbody")
    parent = {child: p for p in root.iter() for child in p}
    for body in list(root.iter("body")):
        name = body.get("name") or ""
        if re.fullmatch(r"[lr]pad_\d+_\d+_\d+", name):
            parent[body].remove(body)
            body.set("pos", _vec(data.xpos[model.body(name).id]))
            world.append(body)
    return ET.tostring(root, encoding="unicode")


def build(xml: str, cfg: PeerConfig, *, jointed: bool):
    """Compile ``xml``; trilinear pads on ``jointed`` cores are hoisted first (``cfg.hoist``). The saved
    XML rounds numbers to 6 digits: the time step is set back exactly."""
    import mujoco

    if cfg.dof == "trilinear" and jointed and cfg.hoist:
        xml = _hoisted(xml)
    model = mujoco.MjModel.from_xml_string(xml)
    model.opt.timestep = cfg.dt
    return model


def cpu_name() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def _contact_forces(model, data, cylinder_geom: int) -> tuple[np.ndarray, float]:
    """(force the contacts put on the cylinder, world frame [N], deepest overlap of a pad or core
    with it [m])."""
    import mujoco

    total = np.zeros(3)
    deepest = 0.0
    f6 = np.zeros(6)
    for i in range(data.ncon):
        con = data.contact[i]
        if cylinder_geom not in (con.geom[0], con.geom[1]):
            continue
        other = con.geom[1] if con.geom[0] == cylinder_geom else con.geom[0]
        mujoco.mj_contactForce(model, data, i, f6)
        frame = con.frame.reshape(3, 3)
        world = frame.T @ f6[:3]  # on geom/flex 2 (frame's normal points from 1 to 2)
        total += world if con.geom[1] == cylinder_geom else -world
        if other < 0 or model.geom_bodyid[other] != 0:  # a pad (flex) or a core, not the ground
            deepest = max(deepest, -float(con.dist))
    return total, deepest


# --- the rig -------------------------------------------------------------------------------------


@dataclass
class RigResult:
    """The pad under each load. Lengths in m, forces in N."""

    loads: tuple[float, ...]
    compression: list[float]
    read_load: list[float]
    """The normal load the contacts put on the cylinder at rest (mean of the hold's last fifth)."""
    overlap: list[float]
    """Deepest contact overlap at the end of each hold."""
    speed: list[float]
    """The cylinder's speed at the end of each hold [m/s]."""
    contacts: list[int]
    steps_per_second: float
    nodes: int
    nv: int
    completed: bool = True
    """False if stopped for the wall-time budget (only the speed is then measured)."""


def run_rig(cfg: PeerConfig, loads=LOADS, *, ramp: float = 0.2, hold: float = 0.5,
            budget: float | None = None) -> RigResult:  # fmt: skip
    """Push the rig's cylinder into the pad with each load in turn (ramped over ``ramp`` from the last,
    held ``hold``) [N, s]. ``budget`` [s of wall time]: stop once the cylinder has reached the pad (its
    contacts cost the most) if the whole run would take longer."""
    import mujoco

    model = build(rig_xml(cfg), cfg, jointed=False)
    data = mujoco.MjData(model)
    dof = model.joint("push").dofadr[0]
    body = model.body("cylinder").id
    geom = model.geom("cylinder").id
    touch = rig_touch_x(cfg)
    out = RigResult(tuple(loads), [], [], [], [], [], math.nan, cfg.nodes_per_pad, model.nv)
    last, seconds, steps = 0.0, 0.0, 0
    total = len(loads) * round((ramp + hold) / cfg.dt)
    for load in loads:
        n_ramp, n_hold = round(ramp / cfg.dt), round(hold / cfg.dt)
        reads = []
        for k in range(n_ramp + n_hold):
            u = min(1.0, (k + 1) / n_ramp)
            data.qfrc_applied[dof] = -(last + (load - last) * u)  # toward the pad, along -x
            tic = time.perf_counter()
            mujoco.mj_step(model, data)
            seconds += time.perf_counter() - tic
            steps += 1
            if k >= n_ramp + n_hold - max(1, n_hold // 5):
                reads.append(_contact_forces(model, data, geom)[0][0])
            if budget is not None and steps == round(0.1 / cfg.dt) and seconds * total / steps > budget:
                out.steps_per_second, out.completed = steps / seconds, False
                return out
        force, deepest = _contact_forces(model, data, geom)
        out.compression.append(touch - float(data.xpos[body, 0]))
        out.read_load.append(float(np.mean(reads)))
        out.overlap.append(deepest)
        out.speed.append(abs(float(data.qvel[dof])))
        out.contacts.append(int(data.ncon))
        last = load
    out.steps_per_second = steps / seconds
    return out


# --- the grasp -----------------------------------------------------------------------------------


@dataclass
class GraspResult:
    """What one scripted grasp did. Lengths in m, angles in rad, forces in N."""

    completed: bool = True
    """False if stopped for the wall-time budget (only the speed is then measured)."""
    finite: bool = True
    lift_height: float = math.nan
    min_lift_during_hold: float = math.nan
    in_hand_motion: float = math.nan
    hold_slip: float = math.nan
    max_tilt: float = math.nan
    max_penetration: float = math.nan
    compression: float = math.nan
    """Pad compression at the end of the squeeze: the pad less the gap from core face to cylinder."""
    press: dict = field(default_factory=dict)
    """Squeeze on the cylinder at the end of the squeeze (closing-direction component of the contact
    force) from each pad and each core [N]."""
    palm_peak_acceleration: float = math.nan
    """Largest |dv/dt| of the palm during lift and hold, dv over ``ACCEL_WINDOW`` [m/s^2]."""
    steps: int = 0
    seconds: float = 0.0
    """Wall time of mj_step alone [s]."""
    dt: float = math.nan
    nv: int = 0

    @property
    def steps_per_second(self) -> float:
        return self.steps / self.seconds if self.seconds > 0 else math.nan

    @property
    def realtime(self) -> float:
        """Simulated seconds per wall second."""
        return self.steps_per_second * self.dt

    def held(self, plan: GraspPlan, *, max_tilt: float = math.pi / 4) -> bool:
        """GraspRecord.held: lifted >= 80 % at the end and all through the hold, tilt <= ``max_tilt``."""
        need = 0.8 * plan.lift_distance
        return (self.completed and self.finite and self.lift_height >= need and self.min_lift_during_hold >= need
                and self.max_tilt <= max_tilt)  # fmt: skip

    def holds_without_slip(self, plan: GraspPlan, *, max_slip: float = SLIP) -> bool:
        """Held, and slipping less than ``max_slip`` through the hold (the bound's criterion)."""
        return self.held(plan) and self.hold_slip < max_slip


def _tilt(xmat: np.ndarray) -> float:
    return math.acos(min(1.0, abs(float(xmat.reshape(3, 3)[2, 2]))))


def run_grasp(cfg: PeerConfig, plan: GraspPlan | None = None, *, budget: float | None = None,
              inspect=None) -> GraspResult:  # fmt: skip
    """accuracy.run_grasp's script in MuJoCo: the same palm targets through our arm path (PalmPath), the
    fingers commanded to ``finger_stroke`` (past contact) for the squeeze. ``budget`` [s of wall time]:
    stop after 0.05 s simulated if the whole grasp would take longer. ``inspect(model, data)`` runs at
    the end (diagnostics)."""
    import mujoco

    plan = plan or GraspPlan()
    model = build(scene_xml(cfg), cfg, jointed=True)
    data = mujoco.MjData(model)
    dt = cfg.dt
    kp, kv = arm_gains()
    z0 = start_palm_z()
    cyl, palm, left = model.body("cylinder").id, model.body("palm").id, model.body("left").id
    cyl_geom = model.geom("cylinder").id
    arm_dof, left_q = model.joint("arm").dofadr[0], model.joint("left").qposadr[0]
    rest_z = 0.5 * SCENE.cylinder_height
    start = np.array([0.0, 0.0, z0])
    grasp = np.array([0.0, 0.0, rest_z + palm_offset()])
    path = PalmPath(start, v_max=SCENE.arm_speed, a_max=SCENE.arm_acceleration, dt=dt)
    control = GripperControl(start.copy(), 0.0)
    phases = [("approach", plan.approach), ("squeeze", plan.squeeze), ("lift", plan.lift), ("hold", plan.hold)]
    total = sum(round(t / dt) for _, t in phases)
    r = GraspResult(dt=dt, nv=model.nv, max_tilt=0.0, max_penetration=0.0, in_hand_motion=0.0, hold_slip=0.0,
                    palm_peak_acceleration=0.0, min_lift_during_hold=math.inf)  # fmt: skip
    rel0 = hold0 = None
    window = max(1, round(ACCEL_WINDOW / dt))
    palm_v: list[float] = []
    for phase, duration in phases:
        n = round(duration / dt)
        if phase == "lift":
            rel0 = data.xpos[cyl] - data.xpos[palm]
            r.compression = PAD - (float(data.xpos[cyl, 0]) - SCENE.cylinder_radius
                                   - (float(data.xpos[left, 0]) + SCENE.finger_half_extents[0]))  # fmt: skip
            r.press = _press(model, data, cyl_geom)
        for k in range(n):
            if phase == "approach":
                u = (k / n) * 1.25  # at the grasp height at 80 % of the phase, as accuracy.run_grasp
                velocity = (grasp - start) * (1.25 / (n * dt)) if u < 1.0 else np.zeros(3)
                control = replace(control, palm_target=start + (grasp - start) * min(1.0, u), palm_velocity=velocity)
            elif phase == "squeeze":
                control = replace(control, finger_closing=SCENE.finger_stroke, palm_velocity=None)
            elif phase == "lift":
                target = grasp.copy()
                target[2] += plan.lift_distance * _min_jerk((k + 1) / n)
                velocity = np.array([0.0, 0.0, plan.lift_distance * _min_jerk_rate((k + 1) / n) / (n * dt)])
                control = replace(control, palm_target=target, palm_velocity=velocity)
            elif control.palm_velocity is not None:
                control = replace(control, palm_velocity=None)
            path.step(control, data.xpos[palm])
            data.ctrl[0] = (path.x[2] - z0) + kv / kp * path.v[2]  # the servo's setpoint, fed its velocity
            speed = float(np.clip(FINGER_GAIN * (control.finger_closing - data.qpos[left_q]),
                                  -SCENE.finger_speed, SCENE.finger_speed))  # fmt: skip
            data.ctrl[1] = data.ctrl[2] = speed
            tic = time.perf_counter()
            mujoco.mj_step(model, data)
            r.seconds += time.perf_counter() - tic
            r.steps += 1
            if not (np.isfinite(data.qpos).all() and np.abs(data.qvel).max() < 1e3):
                r.finite = False
                break
            r.max_penetration = max(r.max_penetration, _contact_forces(model, data, cyl_geom)[1])
            palm_v.append(float(data.qvel[arm_dof]))
            if phase in ("lift", "hold"):
                if len(palm_v) > window:
                    a = abs(palm_v[-1] - palm_v[-1 - window]) / (window * dt)
                    r.palm_peak_acceleration = max(r.palm_peak_acceleration, a)
                r.max_tilt = max(r.max_tilt, _tilt(data.xmat[cyl]))
                r.in_hand_motion = max(r.in_hand_motion, float(np.linalg.norm(data.xpos[cyl] - data.xpos[palm] - rel0)))
            if phase == "hold":
                if hold0 is None:
                    hold0 = data.xpos[cyl] - data.xpos[palm]
                r.hold_slip = max(r.hold_slip, float(np.linalg.norm(data.xpos[cyl] - data.xpos[palm] - hold0)))
                r.min_lift_during_hold = min(r.min_lift_during_hold, float(data.xpos[cyl, 2]) - rest_z)
            if budget is not None and r.steps == max(1, round(0.05 / dt)) and r.seconds * total / r.steps > budget:
                r.completed = False
                return r
        if not r.finite:
            break
    if r.finite:
        r.lift_height = float(data.xpos[cyl, 2]) - rest_z
    if inspect is not None:
        inspect(model, data)
    return r


def _press(model, data, cylinder_geom: int) -> dict:
    """The squeeze on the cylinder at the end of the squeeze: the x-component (the closing direction) of
    the contact force each pad and each core puts on it, pressing inward [N]."""
    import mujoco

    out = {"left pad": 0.0, "right pad": 0.0, "left core": 0.0, "right core": 0.0}
    f6 = np.zeros(6)
    names = {model.geom("left_core").id: "left core", model.geom("right_core").id: "right core"}
    for i in range(data.ncon):
        con = data.contact[i]
        if cylinder_geom not in (con.geom[0], con.geom[1]):
            continue
        mujoco.mj_contactForce(model, data, i, f6)
        world = con.frame.reshape(3, 3).T @ f6[:3]
        fx = float(world[0] if con.geom[1] == cylinder_geom else -world[0])
        flex = con.flex[0] if con.flex[0] >= 0 else con.flex[1]
        if flex >= 0:
            key = "left pad" if flex == 0 else "right pad"
        else:
            key = names.get(con.geom[1] if con.geom[0] == cylinder_geom else con.geom[0])
            if key is None:
                continue
        out[key] += fx if key.startswith("left") else -fx  # the left finger pushes along +x
    return out


def hold_bound(cfg: PeerConfig, plan: GraspPlan | None = None, *, lo: float = 0.05, hi: float = 1.5,
               rel_tol: float = 0.02, report=None) -> dict:  # fmt: skip
    """The heaviest cylinder the grasp holds without slipping (bisection, accuracy.find_hold_bound) and
    Coulomb's 2 mu F / (g + a), a the palm's peak acceleration during lift and hold in the heaviest
    run that held; NaN when [lo, hi] does not bracket it."""
    plan = plan or GraspPlan()
    accel: dict[float, float] = {}

    def held(mass: float) -> bool:
        r = run_grasp(replace(cfg, cylinder_mass=mass), plan)
        ok = r.holds_without_slip(plan)
        accel[mass] = r.palm_peak_acceleration
        if report is not None:
            report(f"    {mass:.4f} kg: {'held' if ok else 'not held'} (lift {r.lift_height * 1e3:.1f} mm, hold slip "
                   f"{r.hold_slip * 1e3:.2f} mm, in hand {r.in_hand_motion * 1e3:.2f} mm)")  # fmt: skip
        return ok

    try:
        mass, trials = find_hold_bound(held, lo=lo, hi=hi, rel_tol=rel_tol)
    except ValueError as e:
        return {"mass": math.nan, "coulomb": math.nan, "ratio": math.nan, "accel": math.nan, "note": str(e)}
    a = accel[max(m for m, ok in trials if ok)]
    coulomb = 2.0 * MU * SCENE.finger_force / (GRAVITY + a)
    return {"mass": mass, "coulomb": coulomb, "ratio": mass / coulomb, "accel": a, "trials": len(trials)}


# --- the command line ----------------------------------------------------------------------------


def _config(level: str, dof: str, ns: argparse.Namespace, **kw) -> PeerConfig:
    cells = tuple(int(v) for v in ns.cells.split(",")) if (ns.cells and dof == "trilinear") else None
    return PeerConfig(counts=level_counts(level), dof=dof, cells=cells, dt=ns.dt, condim=ns.condim,
                      impratio=ns.impratio, **kw)  # fmt: skip


def _fmt(v: float, scale: float = 1.0, digits: int = 3) -> str:
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v * scale:.{digits}f}"


def grasp_row(r: GraspResult, plan: GraspPlan) -> dict:
    """A grasp's CSV fields (mm, deg, N)."""
    if not r.completed:
        return {"held": "not run (budget)", "steps_per_s": r.steps_per_second, "sim_s_per_wall_s": r.realtime}
    return {"held": r.held(plan), "lift_mm": r.lift_height * 1e3, "in_hand_mm": r.in_hand_motion * 1e3,
            "hold_slip_mm": r.hold_slip * 1e3, "max_tilt_deg": math.degrees(r.max_tilt),
            "penetration_mm": r.max_penetration * 1e3, "squeeze_compression_mm": r.compression * 1e3,
            "pad_press_N": 0.5 * (r.press.get("left pad", 0.0) + r.press.get("right pad", 0.0)),
            "core_press_N": 0.5 * (r.press.get("left core", 0.0) + r.press.get("right core", 0.0)),
            "palm_peak_accel": r.palm_peak_acceleration, "steps_per_s": r.steps_per_second,
            "sim_s_per_wall_s": r.realtime}  # fmt: skip


def _write(path: Path, rows: list[dict]) -> None:
    keys: list[str] = []
    for row in rows:
        keys += [k for k in row if k not in keys]
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        for row in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in row.items()})
    print(f"wrote {path}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--levels", default="30,100,570,3800", help="comma list: 30,100,570,3800 or NXxNYxNZ")
    parser.add_argument("--dofs", default="full,trilinear")
    parser.add_argument("--rows", default="rig,grasp,bound", help="comma list of rig,grasp,bound,dt,condim")
    parser.add_argument("--dt", type=parse_dt, default=DEFAULT_DT, help="time step [s], e.g. 1/480")
    parser.add_argument("--cells", default=None, help="trilinear cellcount 'cx,cy,cz' (default: one per grid gap)")
    parser.add_argument("--condim", type=int, default=3, choices=(3, 4, 6))
    parser.add_argument("--impratio", type=float, default=10.0)
    parser.add_argument("--budget", type=float, default=100.0, help="wall seconds a grasp may take, else speed only")
    parser.add_argument("--bound-budget", type=float, default=10.0, help="bound only where a grasp takes less [s]")
    parser.add_argument("--out", type=Path, default=OUT)
    ns = parser.parse_args(argv)
    import mujoco

    levels, dofs = ns.levels.split(","), ns.dofs.split(",")
    rows = set(ns.rows.split(","))
    unknown = rows - {"rig", "grasp", "bound", "dt", "condim"}
    if unknown:
        parser.error(f"unknown rows {sorted(unknown)}")
    for level in levels:
        try:
            level_counts(level)
        except ValueError as e:
            parser.error(str(e))
    plan = GraspPlan()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else math.nan
    print(f"MuJoCo {mujoco.__version__} peer, one thread, {cpu_name()} (load average {load:.2f} when started); "
          f"dt {ns.dt:.6g} s, integrator discrete, Newton, elliptic cone, impratio {ns.impratio:g}, "
          f"condim {ns.condim}; pads E {YOUNG:g} Pa, nu {POISSON:g}, {PAD * 1e3:g} mm, mu {MU:g}")  # fmt: skip
    ns.out.mkdir(parents=True, exist_ok=True)
    table: list[dict] = []
    for dof in dofs if rows & {"rig", "grasp", "bound"} else ():
        for level in levels:
            cfg = _config(level, dof, ns)
            row: dict = {"dof": dof, "level": level, "grid": "x".join(map(str, cfg.counts)),
                         "nodes_per_pad": cfg.nodes_per_pad, "grid_points_per_pad": int(np.prod(cfg.counts)),
                         "tissue_particles_per_pad": TISSUE_PARTICLES.get(level, math.nan) / 2, "dt": ns.dt,
                         "condim": ns.condim}  # fmt: skip
            if dof == "trilinear":
                row["cells"] = "x".join(map(str, cfg.cellcount))
            print(f"\n{dof}, level {level}: grid {row['grid']}, {cfg.nodes_per_pad} nodes a pad"
                  + (f" (cells {row['cells']})" if dof == "trilinear" else ""), flush=True)  # fmt: skip
            if "rig" in rows:
                tic = time.perf_counter()
                rig = run_rig(cfg, budget=ns.budget)
                row["rig_nv"] = rig.nv
                if not rig.completed:
                    print(f"  rig: not run, over the {ns.budget:g} s budget at {rig.steps_per_second:.1f} steps/s "
                          "over its first 0.1 s", flush=True)  # fmt: skip
                done = zip(rig.loads, rig.compression, rig.read_load, rig.overlap, rig.speed, strict=True)
                for ld, c, f, o, s in done if rig.completed else ():
                    err = c * 1e3 / REFERENCE_MM[ld] - 1.0
                    row[f"compression_{ld:g}N_mm"], row[f"error_{ld:g}N"] = c * 1e3, err
                    row[f"read_load_{ld:g}N"], row[f"overlap_{ld:g}N_mm"] = f, o * 1e3
                    print(f"  rig {ld:g} N: compression {c * 1e3:.3f} mm (reference {REFERENCE_MM[ld]:.3f}, "
                          f"{err:+.1%}), "
                          f"contacts carry {f:.4f} N, deepest overlap {o * 1e3:.3f} mm, cylinder at {s * 1e3:.3f} mm/s",
                          flush=True)  # fmt: skip
                row["rig_steps_per_s"] = rig.steps_per_second
                if rig.completed:
                    print(f"  rig: {rig.steps_per_second:.0f} steps/s, {time.perf_counter() - tic:.1f} s", flush=True)
            grasp_seconds = math.inf
            if "grasp" in rows or "bound" in rows:
                tic = time.perf_counter()
                r = run_grasp(cfg, plan, budget=ns.budget)
                grasp_seconds = time.perf_counter() - tic if r.completed else math.inf
                row.update(grasp_row(r, plan))
                row["grasp_nv"] = r.nv
                if r.completed:
                    print(f"  grasp: {'held' if r.held(plan) else 'NOT HELD'}, lift {r.lift_height * 1e3:.1f} mm, "
                          f"in hand "
                          f"{r.in_hand_motion * 1e3:.2f} mm, hold slip {r.hold_slip * 1e3:.3f} mm, tilt "
                          f"{math.degrees(r.max_tilt):.2f} deg, overlap {r.max_penetration * 1e3:.3f} mm, pad "
                          f"compression {r.compression * 1e3:.2f} mm, squeeze on the cylinder: pads "
                          f"{row['pad_press_N']:.2f} N, cores {row['core_press_N']:.2f} N each; "
                          f"{r.steps_per_second:.0f} steps/s, {r.realtime:.3f} sim s / wall s "
                          f"({grasp_seconds:.1f} s)", flush=True)  # fmt: skip
                else:
                    print(f"  grasp: not run, over the {ns.budget:g} s budget at {r.steps_per_second:.1f} steps/s "
                          f"({r.realtime:.4f} sim s / wall s)", flush=True)  # fmt: skip
            if "bound" in rows:
                if grasp_seconds < ns.bound_budget:
                    tic = time.perf_counter()
                    b = hold_bound(cfg, plan, report=lambda s: print(s, flush=True))
                    row.update(bound_kg=b["mass"], coulomb_kg=b["coulomb"], bound_ratio=b["ratio"],
                               bound_palm_accel=b["accel"])  # fmt: skip
                    print(f"  bound: {b['mass']:.4f} kg; Coulomb 2 mu F / (g + a) {b['coulomb']:.4f} kg (a "
                          f"{b['accel']:.3f} m/s^2): ratio {b['ratio']:.3f} ({time.perf_counter() - tic:.0f} s)"
                          + (f" [{b['note']}]" if "note" in b else ""), flush=True)  # fmt: skip
                else:
                    print(f"  bound: skipped (a grasp takes {grasp_seconds:.0f} s > {ns.bound_budget:g} s)")
            table.append(row)
    if table and rows & {"rig", "grasp", "bound"}:
        print_table(table)
        _write(ns.out / "mujoco_peer.csv", table)
    if "dt" in rows:
        sweep("dt", dofs, levels, ns, plan, [{"dt": dt} for dt in DTS])
    if "condim" in rows:
        sweep("condim", dofs, levels, ns, plan, [{"condim": c} for c in (3, 4, 6)])
    return 0


def sweep(name: str, dofs, levels, ns: argparse.Namespace, plan: GraspPlan, settings: list[dict]) -> None:
    """The grasp at each of ``settings`` (PeerConfig fields) per dof and level."""
    print(f"\n{name} sweep: the grasp at each setting")
    out = []
    for dof in dofs:
        for level in levels:
            held_dts = []
            for s in settings:
                cfg = replace(_config(level, dof, ns), **s)
                r = run_grasp(cfg, plan, budget=ns.budget)
                row = {"dof": dof, "level": level, **{k: v for k, v in s.items()}, **grasp_row(r, plan)}
                out.append(row)
                label = f"dt 1/{round(1 / cfg.dt)}" if name == "dt" else f"condim {cfg.condim}"
                if r.completed:
                    if r.held(plan):
                        held_dts.append(cfg.dt)
                    print(f"  {dof:<9} {level:>5} {label:<12} {'held' if r.held(plan) else 'NOT HELD':<9} in hand "
                          f"{r.in_hand_motion * 1e3:6.3f} mm, hold slip {r.hold_slip * 1e3:6.3f} mm, tilt "
                          f"{math.degrees(r.max_tilt):5.2f} deg, overlap {r.max_penetration * 1e3:.3f} mm, "
                          f"compression {r.compression * 1e3:.2f} mm, {r.steps_per_second:7.0f} steps/s, "
                          f"{r.realtime:6.3f} sim s / wall s", flush=True)  # fmt: skip
                else:
                    print(f"  {dof:<9} {level:>5} {label:<12} over budget ({r.steps_per_second:.1f} steps/s)",
                          flush=True)
            if name == "dt":
                print(f"  {dof} {level}: largest dt that held: "
                      + (f"1/{round(1 / max(held_dts))} s" if held_dts else "none"), flush=True)  # fmt: skip
    _write(ns.out / f"mujoco_peer_{name}.csv", out)


def print_table(table: list[dict]) -> None:
    print(f"\n{'dof':<10}{'level':>6}{'nodes':>7}{'err 1N':>8}{'err 3N':>8}{'err 6N':>8}{'held':>6}{'in-hand':>9}"
          f"{'slip':>7}{'tilt':>6}{'overlap':>8}{'steps/s':>9}{'sim/wall':>9}{'bound':>7}{'ratio':>7}")  # fmt: skip
    print(f"{'':<10}{'':>6}{'/pad':>7}{'':>8}{'':>8}{'':>8}{'':>6}{'mm':>9}{'mm':>7}{'deg':>6}{'mm':>8}{'':>9}{'':>9}"
          f"{'kg':>7}{'':>7}")  # fmt: skip
    def pct(r: dict, key: str) -> str:
        v = r.get(key)
        return "-" if v is None else f"{v:+.1%}"

    for r in table:
        held = r.get("held", "-")
        held = "yes" if held is True else "no" if held is False else "-"
        print(f"{r['dof']:<10}{r['level']:>6}{r['nodes_per_pad']:>7}{pct(r, 'error_1N'):>8}"
              f"{pct(r, 'error_3N'):>8}"
              f"{pct(r, 'error_6N'):>8}{held:>6}{_fmt(r.get('in_hand_mm', math.nan), 1, 2):>9}"
              f"{_fmt(r.get('hold_slip_mm', math.nan), 1, 2):>7}{_fmt(r.get('max_tilt_deg', math.nan), 1, 1):>6}"
              f"{_fmt(r.get('penetration_mm', math.nan), 1, 2):>8}{_fmt(r.get('steps_per_s', math.nan), 1, 0):>9}"
              f"{_fmt(r.get('sim_s_per_wall_s', math.nan), 1, 3):>9}{_fmt(r.get('bound_kg', math.nan), 1, 3):>7}"
              f"{_fmt(r.get('bound_ratio', math.nan), 1, 3):>7}")  # fmt: skip


if __name__ == "__main__":
    raise SystemExit(main())
