"""Configuration of the tissue, the solver and the grasp scene.

All configs are frozen dataclasses with SI units stated per field. Each validates itself in
``__post_init__`` and raises :class:`ValueError` naming the field and the allowed range: a bad value
is never clamped silently.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from typing import Literal

CouplingMode = Literal["thesis", "consistent"]
COUPLING_MODES: tuple[str, ...] = ("thesis", "consistent")
FINGER_KINDS: tuple[str, ...] = ("tissue", "rigid", "segmented", "fem")
SEGMENT_SPRINGS: tuple[str, ...] = ("motor", "torque")
FEM_RESOLUTIONS: tuple[str, ...] = ("coarse", "fine")
TISSUE_FACES: tuple[str, ...] = ("all", "contact")

PALM_HALF_EXTENTS = (0.09, 0.03, 0.01)
"""Half extents of the gripper's palm box [m]."""
FINGER_DROP = 0.04
"""Gap between the palm's underside and the top of a finger core [m] (the finger's upper part is
not modelled: only the fingertip segment touches anything)."""
SEGMENT_DEPTH = 0.008
"""How far a segmented finger's segments stand in front of its core (2 mm boss + 6 mm segment,
segmented.py) [m]: the pad depth of that kind, as ``TissueConfig.extrude`` is the tissue's."""
MAX_CONSISTENT_SQUEEZE_IMPULSE = 0.125
"""Largest finger_force * dt the consistent coupling accepts [N s]: a core sliding on its joint
under the motor's force is projected against the tissue every step, and a large impulse per step
drives it through the pad. Probe of issue 12 (scripted grasps): 30 N at 1/60 s (0.5 N s) and
100 N at 1/120 s (0.83) diverged in every episode, 30 N at 1/120 s (0.25) ran; the stability map
saw 10-20 N fail at 1/60 s (0.17-0.33) on the easy task. 0.125 keeps below all of them."""
MAX_PARTICLE_RADIUS = 0.0125
"""Widest tangential particle radius (radius_scale * spacing) SceneConfig accepts on the fingers
[m]. Wider particles overhang the cores' edges (a face is 4 cm wide) and catch on the cylinder's
rim: 3.5-6.7 cm tore the tissue within 10-50 random-action steps, 2.0 cm (900 per m^2) in one of
five random-action episodes (issue 12's probe and tests/test_extremes.py); the `fast` preset's
1.2 cm (2,500 per m^2) and the default's 0.95 cm run."""
MAX_TISSUE_SAG = 0.006
"""Largest equilibrium sag g dt^2 / k of the tissue under gravity that SceneConfig accepts [m].
Issue 12's probe: 0.54-0.57 cm ran its five episodes (0.57 cm, stiffness 0.03 at 1/240 s, snagged
once in eight more: stiffness now starts at 0.1), 1.7 cm tore one in three, more tore all."""
GEOMETRY_MARGIN = 0.001
"""Clearance the start geometry must leave between the cylinder and the open fingers or palm [m]."""


def _check_range(
    owner: str, name: str, value: float, lo: float, hi: float, *, lo_open: bool = False, hi_open: bool = False
) -> None:
    """Raise ValueError unless lo <(=) value <(=) hi; the message names the field and the range."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{owner}.{name} must be a finite number, got {value!r}")
    below = value <= lo if lo_open else value < lo
    above = value >= hi if hi_open else value > hi
    if below or above:
        left = "(" if lo_open else "["
        right = ")" if hi_open else "]"
        raise ValueError(f"{owner}.{name} must be in {left}{lo}, {hi}{right}, got {value!r}")


def _check_int(owner: str, name: str, value: int, lo: int, hi: int) -> None:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ValueError(f"{owner}.{name} must be an integer, got {value!r}")
    if not lo <= value <= hi:
        raise ValueError(f"{owner}.{name} must be in [{lo}, {hi}], got {value!r}")


@dataclass(frozen=True)
class TissueConfig:
    """Soft tissue wrapped around a rigid core (thesis 5.1.1 and 5.2.1).

    The core's surface is sampled with *attached* particles; each gets one *outer* partner pushed
    out by ``extrude`` along the direction from the core's centre of mass.
    """

    density: float = 4_000.0
    """Attached particles per square metre of core surface [1/m^2]; 4,000/m^2 is ~16 mm spacing (30
    particles on a finger's inner face and tip). Chosen on the speed/accuracy chart
    (benchmarks/methods.py): against 10,000/m^2 the grasp penetrates less (0.095 mm vs 0.69 mm at
    3 iterations: bigger particles, fewer contacts to resolve) at 1.4x the steps/s, and the hold
    bound stays within 3 % of Coulomb's (10,000: -4 %)."""
    extrude: float = 0.008
    """Distance from an attached particle to its outer partner [m] (thesis 5.2.1 *extrude*)."""
    group_size: int = 8
    """Particles per implicit shape-matching group, centre included (thesis 5.2.1 *groupSize*), 4 to
    16. Larger groups span most of a pad (30 particles a face at the default density) and let it
    sag and tear: 32 diverged in every episode at 1 iteration, 64 in 1 of 5 at 2 iterations (and
    1 of 5 at 2 iterations and 1/60 s), while 16 ran every episode at 1 iteration (issue 12's
    extremes probe)."""
    tissue_density: float = 1_000.0
    """Mass density of the tissue [kg/m^3], 100 to 1e4; particle mass = density * (its share of
    the layer volume). Heavier tissue outweighs its shape matching under the arm's shoves: 3e4
    tore in 2 of 3 random-action episodes, 1e5 in every episode, scripted ones too; 1e4 ran all.
    Tissue lighter than foam (2 and 13 kg/m^3) tore in two of the fuzzed settings, and setting
    that alone back to 1,000 made both run."""
    stiffness: float = 0.5
    """Shape-matching stiffness k in [0.1, 1] per *step*; made iteration-independent (Mueller
    2007). Slacker tissue does not follow its core under the arm's shoves: at 0.001 every episode
    tore past the divergence limit by the second step, at 0.01 one of three random-action
    episodes, at 0.03 one of five (issue 12's extremes probe and tests/test_extremes.py)."""
    radius_scale: float = 0.6
    """Tangential ellipsoid radius as a fraction of the particle spacing (>0.5 closes gaps)."""
    normal_radius: float = 0.003
    """Ellipsoid radius along the surface normal [m] (flat, pebble-like particles). With ``extrude``
    it is the pad thickness that SceneConfig checks the cylinder against (0.1 m used to pass the
    check and diverge at the first step)."""
    friction_static: float = 0.9
    """Coulomb static friction coefficient mu_s of the tissue surface [-]."""
    friction_dynamic: float = 0.7
    """Coulomb dynamic (kinetic) friction coefficient mu_k of the tissue surface [-]."""

    def __post_init__(self) -> None:
        o = "TissueConfig"
        _check_range(o, "density", self.density, 100.0, 1e7)
        _check_range(o, "extrude", self.extrude, 0.0, 0.1, lo_open=True)
        _check_int(o, "group_size", self.group_size, 4, 16)
        _check_range(o, "tissue_density", self.tissue_density, 100.0, 1e4)
        _check_range(o, "stiffness", self.stiffness, 0.1, 1.0)
        _check_range(o, "radius_scale", self.radius_scale, 0.0, 2.0, lo_open=True)
        _check_range(o, "normal_radius", self.normal_radius, 0.0, 0.1, lo_open=True)
        _check_range(o, "friction_static", self.friction_static, 0.0, 10.0)
        _check_range(o, "friction_dynamic", self.friction_dynamic, 0.0, 10.0)
        if self.friction_dynamic > self.friction_static:
            raise ValueError(
                "TissueConfig.friction_dynamic must not exceed friction_static, got "
                f"{self.friction_dynamic!r} > {self.friction_static!r}"
            )

    @property
    def spacing(self) -> float:
        """Mean distance between neighbouring attached particles [m]."""
        return 1.0 / math.sqrt(self.density)


def pad_thickness(fingers: str, tissue: TissueConfig) -> float:
    """How far a finger's pad reaches out from its core [m], on the inner face and the tip: the
    tissue to its outer particles' ellipsoids (extrude plus their normal radius), the FEM pad's
    thickness (extrude), the segments' depth; 0 for rigid fingers."""
    if fingers == "tissue":
        return tissue.extrude + tissue.normal_radius
    return {"fem": tissue.extrude, "segmented": SEGMENT_DEPTH}.get(fingers, 0.0)


@dataclass(frozen=True)
class SimConfig:
    """Time stepping and solver settings shared by tissue and pybullet."""

    dt: float = 1.0 / 240.0
    """Physics step [s], at most 1/60 s; one tissue step and one pybullet step per world step.
    Longer steps tear the tissue in the grasp (the contact and coupling corrections grow with dt
    squared): 1/40 s in 1 of 2 scripted episodes, 1/20 s in every episode at its second step;
    1/60 s ran every episode of the extremes probe (issue 12)."""
    iterations: int = 3
    """Gauss-Seidel iterations over the shape-matching groups and contacts per step. Measured on the
    scripted grasp at the default tissue (deepest penetration over every step, thesis coupling):
    1 -> 3.05 mm, 2 -> 0.81 mm, 3 -> 0.095 mm, 4 -> 0.034 mm; at dt / 2, 1 iteration gives 0.11 mm
    but the ramp breakaway comes 15 % early, 2 give 0.04 mm. 3 is the fewest at 1/240 s that meets
    every accuracy target (README, Measured); with the default 60 particles an iteration costs a
    few per cent of the step, most of which is pybullet's."""
    rotation_iterations: int = 1
    """Most warm-started rotation-extraction sweeps per group solve (Mueller et al. 2016); stops
    early once the correction is below 1e-10 rad. One sweep per solve suffices with the warm start
    carried by each group's spin: 4 sweeps changed the grasp's height error by 3 % (0.534 -> 0.518
    mm) and cost 20 % of the speed."""
    gravity: float = 9.81
    """Gravitational acceleration along -z [m/s^2]."""
    damping: float = 0.5
    """Damping rate of each tissue body's deviation from its rigid motion [1/s] (Mueller et al.
    2007 sec. 3.5): the deviation shrinks by exp(-damping * dt) per step. 0 disables it."""
    coupling: CouplingMode = "thesis"
    """'thesis': core infinitely heavy inside the solve, error -> impulse, snap back (thesis 5.1.3).
    'consistent': attachment projected with the core's generalised inverse mass (XPBD); a core on a
    prismatic joint slides along it under its motor's force."""
    orientation: Literal["goal"] = "goal"
    """How particle orientations follow their groups: 'goal', the paper's rule (Mueller & Chentanez
    2011 sec. 4.3), only a group's centre turns toward the group rotation. The only mode: the
    'reaction' mode of earlier versions (every member takes up the projection's torque as spin) was
    removed, its energy grew 10-fold in 1,000 steps with spinning particles; angular momentum of
    free bodies is now kept exactly in goal mode (tissue/momentum.py)."""
    contact_margin: float = 0.002
    """Extra distance [m] within which contact candidates are collected per step."""

    def __post_init__(self) -> None:
        o = "SimConfig"
        _check_range(o, "dt", self.dt, 1e-5, 1.0 / 60.0)
        _check_int(o, "iterations", self.iterations, 1, 200)
        _check_int(o, "rotation_iterations", self.rotation_iterations, 1, 100)
        _check_range(o, "gravity", self.gravity, 0.0, 100.0)
        _check_range(o, "damping", self.damping, 0.0, 1e4)
        if self.coupling not in COUPLING_MODES:
            raise ValueError(f"SimConfig.coupling must be one of {COUPLING_MODES}, got {self.coupling!r}")
        if self.orientation == "reaction":
            raise ValueError(
                "SimConfig.orientation='reaction' was removed (its energy grew with spinning particles); "
                "'goal' now keeps free bodies' angular momentum exactly: use orientation='goal'"
            )
        if self.orientation != "goal":
            raise ValueError(f"SimConfig.orientation must be 'goal', got {self.orientation!r}")
        _check_range(o, "contact_margin", self.contact_margin, 0.0, 0.1)


@dataclass(frozen=True)
class SceneConfig:
    """The grasp scene: ground, a two-finger gripper and a cylinder (thesis 5.2.1)."""

    fingers: str = "tissue"
    """How the fingers touch the cylinder, one of FINGER_KINDS: 'tissue' - each core is a combined
    body, wrapped in oriented-particle tissue (the thesis); 'rigid' - the bare cores, through
    pybullet's own contacts (the rigid-only twin); 'segmented' - each core carries
    ``finger_segments`` rigid segments on sprung two-axis gimbals that form its contact face (the
    thesis' "traditional" fix, softgrasp_env/segmented.py); 'fem' - each core carries a fully
    deformable pad (inner face and tip) simulated by pybullet's FEM soft bodies (softgrasp_env/fem.py)."""
    finger_segments: int = 3
    """Segments per finger (fingers='segmented'), side by side along the face's 40 mm: 3 gives
    13 mm wide segments, narrower than the cylinder's flat-contact zone, so one of them always
    takes a lateral offset of up to the face's half width on its centre part."""
    segment_stiffness_pitch: float = 0.3
    """Spring stiffness of a segment's pitch joint (about the face's long axis y) [N m/rad]."""
    segment_stiffness_yaw: float = 0.03
    """Spring stiffness of a segment's yaw joint (about z) [N m/rad]."""
    segment_damping_pitch: float = 0.002
    """Damping of a segment's pitch joint [N m s/rad] ('motor' springs apply at most 0.5 I / dt of
    it, I the joint's inertia: 4.5e-4 at 3 segments and 1/240 s; segmented.py says why)."""
    segment_damping_yaw: float = 0.0002
    """Damping of a segment's yaw joint [N m s/rad] (capped likewise: 2.4e-5 at the defaults)."""
    segment_spring: str = "motor"
    """How the segments' springs are made in pybullet: 'motor' - a force-limited position motor
    re-limited every step to the spring-damper torque (stable at any dt); 'torque' - the explicit
    torque -(k q + c q') every step (unstable at these inertias; kept to measure it)."""
    fem_resolution: str = "coarse"
    """Tetrahedral mesh of the 'fem' pads, one of FEM_RESOLUTIONS: 'coarse' - one hex cell (6 tets)
    through the 8 mm pad, about 8-10 mm cells along it; 'fine' - two, about 4 mm cells
    (fem.FEM_CELLS_THROUGH)."""
    fem_substeps: int = 8
    """pybullet steps per world step (``sim.dt``) for fingers='fem', each ``sim.dt / fem_substeps``
    long. pybullet's deformable world integrates the elastic forces explicitly (only the damping
    and the constraints are implicit). Measured with the coarse pads, scripted grasp of the default
    cylinder: 1 substep (1/240 s) blew up at first contact (nodes 25 mm inside the cylinder, which
    was thrown off at 6 m/s); 2 still gave 7 mm of penetration at the impact; 4 lifted it but it
    slid 17 mm down the pads in the 2 s hold (14-41 mm of lift left, depending on a 0.2 mm start
    offset); 8 holds it (0.11 mm of slip) at half the speed of 4."""
    tissue_faces: str = "contact"
    """Which faces of a finger core get tissue: 'contact' (default) - only the inner face and the
    tip, where the fingers can touch the cylinder (the rest of the core meets the world through
    pybullet's contacts); or 'all' - every face (2.5x the particles, the same grasp: penetration
    0.098 mm vs 0.095, at 0.6x the steps/s). Model no more than the scene needs."""
    cylinder_radius: float = 0.03
    """Cylinder radius [m]."""
    cylinder_height: float = 0.10
    """Cylinder height [m]."""
    cylinder_mass: float = 0.1
    """Cylinder mass [kg]."""
    cylinder_friction: float = 1.0
    """The cylinder's lateral friction in pybullet, which multiplies the other body's: 1 makes the
    ground's and the rigid fingers' own coefficients the effective ones."""
    finger_half_extents: tuple[float, float, float] = (0.008, 0.02, 0.03)
    """Half extents of a finger core box [m]: x (closing direction), y, z."""
    finger_mass: float = 0.05
    """Mass of one finger core [kg]."""
    finger_force: float = 3.0
    """Force limit of each finger's closing motor [N]. 3 N holds the default cylinder 5.5 times over
    (2 mu_s N / m g; measured within 1 % for a slow lift); at 10 N the motors push the cores through
    the 1 cm tissue (PBD contact stiffness scales with particle mass / dt^2) and pybullet's
    core-cylinder contact takes over."""
    finger_speed: float = 0.1
    """Maximum closing speed of a finger [m/s]. The deepest tissue penetration of the grasp comes
    the moment the fingers meet the cylinder: 0.095 mm at 0.1 m/s, 0.058 mm at 0.05 m/s (thesis
    coupling)."""
    finger_max_opening: float = 0.06
    """Largest distance of a finger core's inner face from the gripper centre [m]."""
    palm_mass: float = 0.5
    """Mass of the gripper palm [kg]."""
    palm_force: float = 200.0
    """Force limit of the constraint that drives the palm [N]."""
    ground_friction: float = 0.5
    """Friction coefficient of the ground [-]."""
    lateral_offset: float = 0.0
    """Misalignment: gripper offset along y (the finger face's long direction) [m]."""
    yaw: float = 0.0
    """Misalignment: gripper yaw about z [rad]."""
    jaw_wedge: float = 0.0
    """Misalignment: angle between the two finger faces [rad]. Each finger is tilted by half of it
    about its face's long (y) axis, the gap wider at the top for a positive wedge, so a rigid
    face meets the cylinder along a short edge instead of a line."""
    cylinder_xy: tuple[float, float] = (0.0, 0.0)
    """Where the cylinder stands on the ground [m]."""
    gripper_xy: tuple[float, float] = (0.0, 0.0)
    """Where the grip point (the palm's centre line) starts horizontally [m]; ``lateral_offset``
    adds to its y."""
    start_height: float = 0.05
    """Height of the grip point (the finger centres) above the cylinder's mid height at the start
    [m]. 0.05 starts the open fingers around the top of the default cylinder; the reach task
    starts them above it (``cylinder_height / 2 + finger half height + clearance``)."""
    tissue: TissueConfig = field(default_factory=TissueConfig)
    sim: SimConfig = field(default_factory=SimConfig)

    def __post_init__(self) -> None:
        o = "SceneConfig"
        if self.fingers not in FINGER_KINDS:
            raise ValueError(f"SceneConfig.fingers must be one of {FINGER_KINDS}, got {self.fingers!r}")
        if self.fem_resolution not in FEM_RESOLUTIONS:
            raise ValueError(f"SceneConfig.fem_resolution must be one of {FEM_RESOLUTIONS}, got {self.fem_resolution!r}")
        _check_int(o, "fem_substeps", self.fem_substeps, 1, 64)
        if self.tissue_faces not in TISSUE_FACES:
            raise ValueError(f"SceneConfig.tissue_faces must be one of {TISSUE_FACES}, got {self.tissue_faces!r}")
        _check_int(o, "finger_segments", self.finger_segments, 1, 8)
        _check_range(o, "segment_stiffness_pitch", self.segment_stiffness_pitch, 0.0, 100.0, lo_open=True)
        _check_range(o, "segment_stiffness_yaw", self.segment_stiffness_yaw, 0.0, 100.0, lo_open=True)
        _check_range(o, "segment_damping_pitch", self.segment_damping_pitch, 0.0, 10.0)
        _check_range(o, "segment_damping_yaw", self.segment_damping_yaw, 0.0, 10.0)
        if self.segment_spring not in SEGMENT_SPRINGS:
            raise ValueError(f"SceneConfig.segment_spring must be one of {SEGMENT_SPRINGS}, got {self.segment_spring!r}")
        _check_range(o, "cylinder_radius", self.cylinder_radius, 0.005, 0.2)
        _check_range(o, "cylinder_height", self.cylinder_height, 0.01, 0.5)
        _check_range(o, "cylinder_mass", self.cylinder_mass, 0.001, 10.0)
        _check_range(o, "cylinder_friction", self.cylinder_friction, 0.0, 10.0)
        if len(self.finger_half_extents) != 3:
            raise ValueError(f"SceneConfig.finger_half_extents must have 3 entries, got {self.finger_half_extents!r}")
        for i, h in enumerate(self.finger_half_extents):
            _check_range(o, f"finger_half_extents[{i}]", h, 0.001, 0.2)
        _check_range(o, "finger_mass", self.finger_mass, 0.001, 10.0)
        _check_range(o, "finger_force", self.finger_force, 0.0, 1000.0, lo_open=True)
        _check_range(o, "finger_speed", self.finger_speed, 0.0, 10.0, lo_open=True)
        _check_range(o, "finger_max_opening", self.finger_max_opening, 0.005, 0.3)
        _check_range(o, "palm_mass", self.palm_mass, 0.01, 100.0)
        _check_range(o, "palm_force", self.palm_force, 0.0, 1e4, lo_open=True)
        _check_range(o, "ground_friction", self.ground_friction, 0.0, 10.0)
        _check_range(o, "lateral_offset", self.lateral_offset, -0.1, 0.1)
        _check_range(o, "yaw", self.yaw, -math.pi / 4, math.pi / 4)
        _check_range(o, "jaw_wedge", self.jaw_wedge, -math.pi / 6, math.pi / 6)
        for name, lim in (("cylinder_xy", 0.1), ("gripper_xy", 0.15)):
            xy = getattr(self, name)
            if len(xy) != 2:
                raise ValueError(f"SceneConfig.{name} must have 2 entries, got {xy!r}")
            for i, v in enumerate(xy):
                _check_range(o, f"{name}[{i}]", v, -lim, lim)
        _check_range(o, "start_height", self.start_height, 0.0, 0.3)
        if not isinstance(self.tissue, TissueConfig):
            raise ValueError(f"SceneConfig.tissue must be a TissueConfig, got {type(self.tissue).__name__}")
        if not isinstance(self.sim, SimConfig):
            raise ValueError(f"SceneConfig.sim must be a SimConfig, got {type(self.sim).__name__}")
        self._check_geometry()

    def _check_geometry(self) -> None:
        """The scene as a whole: the cylinder fits between the open fingers with their pads on, and
        the start puts no finger and no palm inside it. Each clash is a ValueError naming the
        settings and the limit."""
        fh = self.finger_half_extents
        pad = pad_thickness(self.fingers, self.tissue)
        if self.fingers == "tissue":
            # The consistent coupling's squeeze per step (MAX_CONSISTENT_SQUEEZE_IMPULSE).
            impulse = self.finger_force * self.sim.dt
            if self.sim.coupling == "consistent" and impulse > MAX_CONSISTENT_SQUEEZE_IMPULSE:
                raise ValueError(
                    f"SceneConfig: coupling='consistent' with finger_force={self.finger_force:g} N at dt="
                    f"{self.sim.dt:g} s pushes {impulse:.3g} N s per step into the tissue, more than "
                    f"{MAX_CONSISTENT_SQUEEZE_IMPULSE:g} N s; at this dt finger_force must be at most "
                    f"{MAX_CONSISTENT_SQUEEZE_IMPULSE / self.sim.dt:.3g} N (or use coupling='thesis')")  # fmt: skip
            # Shape matching pulls a particle a fraction k of the way to its goal per step
            # (Mueller 2005, alpha = k), so gravity's g dt^2 per step settles at a sag of
            # g dt^2 / k (MAX_TISSUE_SAG: at 1.7 cm the probe's tissue tore one episode in three).
            sag = self.sim.gravity * self.sim.dt**2 / self.tissue.stiffness
            if sag > MAX_TISSUE_SAG:
                raise ValueError(
                    f"SceneConfig: the tissue is too slack for the time step: gravity={self.sim.gravity:g} m/s^2 "
                    f"times dt={self.sim.dt:g} s squared over stiffness={self.tissue.stiffness:g} sags it "
                    f"{sag * 100:.2f} cm, more than {MAX_TISSUE_SAG * 100:g} cm; raise the stiffness to at least "
                    f"{self.sim.gravity * self.sim.dt**2 / MAX_TISSUE_SAG:.3g} or shorten dt")  # fmt: skip
            # Coarse pads of wide particles overhang the core's edges and catch on the cylinder.
            reach = self.tissue.radius_scale * self.tissue.spacing
            if reach > MAX_PARTICLE_RADIUS:
                raise ValueError(
                    f"SceneConfig: the tissue particles are too wide: radius_scale={self.tissue.radius_scale:g} "
                    f"times the spacing {self.tissue.spacing:.4f} m (density={self.tissue.density:g} per m^2) "
                    f"gives {reach:.4f} m, more than {MAX_PARTICLE_RADIUS:g} m; raise the density to at least "
                    f"{(self.tissue.radius_scale / MAX_PARTICLE_RADIUS) ** 2:.0f} per m^2 or lower radius_scale")  # fmt: skip
        # narrowest half gap of the open fingers: a wedge turns one edge of each face inwards
        gap = self.finger_max_opening - pad - fh[2] * math.sin(0.5 * abs(self.jaw_wedge))
        r = self.cylinder_radius
        if r + GEOMETRY_MARGIN > gap:
            raise ValueError(
                f"SceneConfig: the cylinder (cylinder_radius={r:g} m) does not fit between the open fingers: "
                f"finger_max_opening={self.finger_max_opening:g} m less the {self.fingers} pad ({pad:g} m) and the "
                f"jaw_wedge={self.jaw_wedge:g} rad leave a half gap of {gap:.4f} m; the radius must be at most "
                f"{gap - GEOMETRY_MARGIN:.4f} m")  # fmt: skip
        h = self.cylinder_height
        grip_z = 0.5 * h + self.start_height
        dx = self.cylinder_xy[0] - self.gripper_xy[0]
        dy = self.cylinder_xy[1] - self.gripper_xy[1] - self.lateral_offset
        across = abs(dx * math.cos(self.yaw) + dy * math.sin(self.yaw))  # along the closing axis
        along = abs(-dx * math.sin(self.yaw) + dy * math.cos(self.yaw))  # along the faces
        tips = grip_z - fh[2] - pad
        if tips < h and along < fh[1] + r and across + r + GEOMETRY_MARGIN > gap:
            raise ValueError(
                f"SceneConfig: the open fingers start inside the cylinder: their tips ({tips:.3f} m up, start_height="
                f"{self.start_height:g}) are below its top (cylinder_height={h:g}) and it stands {across:.4f} m across "
                f"the closing axis from the grip (cylinder_xy={self.cylinder_xy}, gripper_xy={self.gripper_xy}, "
                f"lateral_offset={self.lateral_offset:g}, yaw={self.yaw:g}); with cylinder_radius={r:g} at most "
                f"{gap - r - GEOMETRY_MARGIN:.4f} m fits")  # fmt: skip
        palm_bottom = grip_z + fh[2] + FINGER_DROP
        if palm_bottom < h + GEOMETRY_MARGIN and across < PALM_HALF_EXTENTS[0] + r and along < PALM_HALF_EXTENTS[1] + r:
            raise ValueError(
                f"SceneConfig: the palm starts inside the cylinder: its underside is {palm_bottom:.3f} m up, the "
                f"cylinder (cylinder_height={h:g}) reaches {h:g} m; raise start_height={self.start_height:g} by "
                f"{h + GEOMETRY_MARGIN - palm_bottom:.3f} m or lower the cylinder")  # fmt: skip

    @property
    def soft(self) -> bool:
        """True if the fingers are wrapped in tissue (``fingers == 'tissue'``)."""
        return self.fingers == "tissue"


def field_names(cls: type) -> tuple[str, ...]:
    """Names of a config dataclass's fields (used by CLIs to map flags onto configs)."""
    return tuple(f.name for f in fields(cls))


__all__ = [
    "COUPLING_MODES",
    "FEM_RESOLUTIONS",
    "FINGER_KINDS",
    "SEGMENT_SPRINGS",
    "TISSUE_FACES",
    "CouplingMode",
    "SceneConfig",
    "SimConfig",
    "TissueConfig",
    "field_names",
    "replace",
]
