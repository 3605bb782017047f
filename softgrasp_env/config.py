"""Configuration of the oriented-particle tissue and of the time stepping both simulators share.

Frozen dataclasses with SI units stated per field. Each validates itself in ``__post_init__``
(softgrasp_env/validation.py) and raises :class:`ValueError` naming the field and the allowed
range: a bad value is never clamped silently. The grasp scene's own settings (``SceneConfig``) are
in softgrasp_env/scene/config.py, each finger kind's in its module under softgrasp_env/fingers/.
"""

from __future__ import annotations

import math
import os
import warnings
from dataclasses import dataclass, field, fields, replace
from typing import Literal

from .validation import accept_old_names, check_bool, check_int, check_range, deprecated, retired_choice

CouplingMode = Literal["thesis", "consistent"]
DEFAULT_SHEAR_MODULUS = 4_000.0
"""The compliant tissue's shear modulus when none is given [Pa]."""
DEFAULT_MAX_DEVIATION = 0.02
"""The compliant tissue's strain limit when none is given [m] (TissueConfig.max_deviation)."""
COMPLIANT_DAMPING = 300.0
"""SimConfig.damping for the compliant tissue when none is given [1/s]."""
COUPLING_MODES: tuple[str, ...] = ("thesis", "consistent")
GroupEnergy = Literal["shape_matching", "continuum"]
GROUP_ENERGIES: tuple[str, ...] = ("shape_matching", "continuum")
FrictionLaw = Literal["patch", "contact"]
FRICTION_LAWS: tuple[str, ...] = ("patch", "contact")
MaterialSolve = Literal["groups", "global"]
MATERIAL_SOLVES: tuple[str, ...] = ("groups", "global")
GlobalLinearSolve = Literal["direct", "multigrid"]
GLOBAL_LINEAR_SOLVES: tuple[str, ...] = ("direct", "multigrid")


@dataclass(frozen=True)
class TissueConfig:
    """Soft tissue wrapped around a rigid core (thesis 5.1.1 and 5.2.1).

    The core's surface is sampled with *attached* particles; each gets one *outer* partner pushed
    out by ``extrude`` along the direction from the core's centre of mass. The shape matching's
    elasticity (Mueller & Chentanez 2011 sec. 4) is a material in SI, ``shear_modulus`` [Pa],
    projected as XPBD compliance (Macklin, Mueller & Chentanez 2016) with the attached particles
    held by their cores inside the solve: the pad compresses the same under a load at every dt and
    iteration count (tissue/compliant.py). ``material="compliant"`` (when there was a second
    material) is accepted with a DeprecationWarning; ``material="per_step"`` and ``stiffness``
    (the thesis' fraction of the way to the goal per step, a different material at every dt) are a
    ValueError naming 0.6.0, the last release that has them.
    """

    particle_density: float = 4_000.0
    """Attached particles per square metre of core surface [1/m^2] (``density`` before 0.3);
    4,000/m^2 is ~16 mm spacing (30 particles on a finger's inner face and tip), chosen on the
    speed/accuracy chart (the package's documentation, Finger kinds, gives the measurements)."""
    extrude: float = 0.008
    """Distance from an attached particle to its outer partner [m] (thesis 5.2.1 *extrude*)."""
    layers: int = field(default=1, kw_only=True)
    """Element layers through the ``extrude`` thickness [-], 1 to 8: layers + 1 particle layers at
    depths k extrude / layers (k = 0 attached to the core, k = layers the outer, contact surface;
    tissue/builder.py, build_combined_body). 1, the default, is the thesis' pad: one attached and one
    outer particle per column, so a group's deformation gradient is linear across the whole layer,
    which the continuum group energy's limit shows as a pad 5 to 10 % stiffer than the continuum
    (the package's documentation, Results: convergence in space). Keyword-only, so that the
    positional order of the fields after it is that of the releases before it."""
    group_size: int = 8
    """Particles per implicit shape-matching group, centre included (thesis 5.2.1 *groupSize*), 4 to
    16. Larger groups span most of a pad (30 particles a face at the default density) and let it
    sag and tear. With ``layers`` > 1 it is the others a group takes from its particle's own layer,
    besides the particle and its column neighbours (the default 8: the two whole rings of the
    face's grid; tissue/builder.py, _layered)."""
    mass_density: float = 1_000.0
    """Mass density of the tissue [kg/m^3] (``tissue_density`` before 0.3), 100 to 1e4; particle
    mass = density * (its share of the layer volume). Heavier tissue outweighs its shape matching
    under the arm's shoves, and tissue lighter than foam tears too."""
    shear_modulus: float = DEFAULT_SHEAR_MODULUS
    """The tissue's shear modulus G [Pa], 1e3 to 1e6. Each implicit group's shape matching is an elastic energy
    G V e^2 / l^2 (V a member's volume, l the group's radius of gyration), so a group's stiffness
    per unit mass is kappa = G / (rho l^2): its shear wave across the group (builder.group_kappa)."""
    max_deviation: float = DEFAULT_MAX_DEVIATION
    """The tissue's strain limit [m], 1 mm to 3 cm: the farthest a particle may be pulled
    from the spot its core carries it to (a deformation constraint, Provot 1995, projected after
    friction: tissue/anchors.py, limit_deviation). A particle snagged
    on the cylinder's top face is pulled through the cylinder by its group and held there by its
    own friction; without the limit the tissue tears."""
    radius_scale: float = 0.6
    """Tangential ellipsoid radius as a fraction of the particle spacing (>0.5 closes gaps)."""
    normal_radius: float = 0.003
    """Ellipsoid radius along the surface normal [m] (flat, pebble-like particles). With ``extrude``
    it is the pad thickness that SceneConfig checks the cylinder against (0.1 m used to pass the
    check and diverge at the first step)."""
    friction_static: float = 0.9
    """Coulomb static friction coefficient mu_s of the tissue surface [-]."""
    friction_kinetic: float | None = None
    """Coulomb kinetic friction coefficient mu_k of the tissue surface [-]; None: equal to
    mu_s, one coefficient, the law of pybullet's rigid contacts, so that every finger kind is
    compared under the same friction. A number below mu_s gives the two-coefficient law (Macklin et
    al. 2014)."""
    group_energy: GroupEnergy = "shape_matching"
    """Each implicit group's elastic energy. "shape_matching", the default:
    ``E = sum_j kappa m_j |x_j - g_j|^2 / 2``, ``kappa = G / (rho l^2)`` (Mueller & Chentanez 2011; builder.group_kappa), which
    weighs a group's strain by its second moment and so changes with the groups' shape: the same G
    is a different pad at every particle_density. "continuum" (opt-in): ``E = G V ||F - R||_F^2``, F the
    group's least-squares deformation gradient A_pq A_qq^-1, R its rotation and V the volume it
    stands for (linear elasticity with nu = 0 for small strain; tissue/compliant.py,
    continuum_groups), independent of the group's shape. The package's documentation (Results:
    convergence in space) measures both against a finite-element reference."""
    hourglass_stiffness: float = 0.0
    """The continuum group energy's hourglass control h [-]: each member's miss r from its group's
    affine fit costs h G V ||r||^2 / l^2 (l the group's radius of gyration; builder.continuum_groups),
    which stiffens the zig-zag patterns the energy G V ||F - R||^2 sees only through the groups'
    affine fits and leaves every affine motion's energy alone. 0 (default): none. At most 1;
    only with group_energy "continuum"."""
    contact_cone: bool = False
    """Coulomb per contact as well as per patch (tissue/friction.py, _apply_with_cones): each tissue
    contact's friction at most mu_s times its normal force, what that sheds handed to the patch's
    other contacts so that the patch still transmits what its law decides, and a contact its cone
    held back re-anchored where it slipped to. False, the default: the patch's bound on what it
    transmits alone, which lets the self-equilibrated friction of a pad wrapped round the cylinder
    grow without bound (a relaxed pad can hold the cylinder with almost no squeeze). Not the
    default, because it changes the material (a squeezed pad's edges slip, and it compresses more
    under the same load): the ids' shear modulus would want re-choosing and the soft ids a new
    version. The package's documentation (Results: tactile pads, "The contact cones") gives the
    measurements."""

    friction_law: FrictionLaw = "patch"
    """Where Coulomb's law is decided for tissue contacts against rigid shapes (tissue/friction.py).
    "patch", the default: per (tissue body, shape) patch, a soft-finger contact (Howe & Cutkosky
    1996) whose net force and twist stick within mu_s N; the rest of its contacts' friction is
    self-equilibrated and unbounded while the patch sticks. "contact": every contact sticks or
    slides in its own cone, with its own stick/slide state and anchor; a patch's torsion and
    partial slip then follow from its contacts. ``contact_cone`` refines the patch law and is an
    error with "contact"."""

    min_rows: int = field(default=1, kw_only=True)
    """The fewest rows of particles across each side of a box core's face [-], 1 to 4: a face gets
    max(min_rows, round(side / spacing)) along each side. 1, the default: as the spacing gives, so
    at 4,000 per m^2 the finger's 16 mm wide tip has one row, and the groups that straddle the tip
    and the inner face are nearly flat. A flat group is stiff across its thin side (its stiffness
    per unit mass is 2 G V over its rest moments' smallest eigenvalue: builder.continuum_groups),
    and the world takes its steps from the stiffest group (compliant.substeps_for): 6 per physics
    step at 1/240 s, where 2 rows give 3 (the package's documentation, Results: speed, "Which
    groups set the world steps"). Changes nothing where the spacing gives 2 rows already.
    Keyword-only, the last field."""

    def __post_init__(self) -> None:
        o = "TissueConfig"
        if self.friction_law not in FRICTION_LAWS:
            raise ValueError(f"TissueConfig.friction_law must be one of {FRICTION_LAWS}, got {self.friction_law!r}")
        if self.friction_law == "contact" and self.contact_cone:
            raise ValueError("TissueConfig.contact_cone bounds the contacts inside a friction patch; with "
                             "friction_law='contact' every contact already has its own cone: leave contact_cone False")
        check_range("particle_density", self.particle_density, 100.0, 1e7, owner=o)
        check_range("extrude", self.extrude, 0.0, 0.1, lo_open=True, owner=o)
        check_int("layers", self.layers, 1, 8, owner=o)
        check_int("min_rows", self.min_rows, 1, 4, owner=o)
        check_int("group_size", self.group_size, 4, 16, owner=o)
        check_range("mass_density", self.mass_density, 100.0, 1e4, owner=o)
        check_bool("contact_cone", self.contact_cone, owner=o)
        if self.group_energy not in GROUP_ENERGIES:
            raise ValueError(f"TissueConfig.group_energy must be one of {GROUP_ENERGIES}, got {self.group_energy!r}")
        check_range("hourglass_stiffness", self.hourglass_stiffness, 0.0, 1.0, owner=o)
        if self.hourglass_stiffness > 0.0 and self.group_energy != "continuum":
            raise ValueError("TissueConfig.hourglass_stiffness acts on the continuum group energy only; got "
                             f"{self.hourglass_stiffness!r} with group_energy={self.group_energy!r}")  # fmt: skip
        check_range("shear_modulus", self.shear_modulus, 1e3, 1e6, owner=o)
        check_range("max_deviation", self.max_deviation, 1e-3, 0.03, owner=o)
        check_range("radius_scale", self.radius_scale, 0.0, 2.0, lo_open=True, owner=o)
        check_range("normal_radius", self.normal_radius, 0.0, 0.1, lo_open=True, owner=o)
        check_range("friction_static", self.friction_static, 0.0, 10.0, owner=o)
        if self.friction_kinetic is not None:
            check_range("friction_kinetic", self.friction_kinetic, 0.0, 10.0, owner=o)
            if self.friction_kinetic > self.friction_static:
                raise ValueError("TissueConfig.friction_kinetic must not exceed friction_static, got "
                                 f"{self.friction_kinetic!r} > {self.friction_static!r}")  # fmt: skip

    @property
    def modulus(self) -> float:
        """Deprecated name of ``shear_modulus`` (before 0.7 that field could be None)."""
        deprecated("TissueConfig.modulus", "TissueConfig.shear_modulus")
        return self.shear_modulus

    @property
    def deviation_limit(self) -> float:
        """Deprecated name of ``max_deviation`` (before 0.7 that field could be None)."""
        deprecated("TissueConfig.deviation_limit", "TissueConfig.max_deviation")
        return self.max_deviation

    @property
    def spacing(self) -> float:
        """Mean distance between neighbouring attached particles [m]."""
        return 1.0 / math.sqrt(self.particle_density)

    @property
    def auto_layers(self) -> int:
        """The element layers that keep a layer about as thick as the particle spacing,
        max(1, round(extrude / spacing)): 1 / 1 / 2 / 4 at 4,000 / 16,000 / 64,000 / 256,000 per m^2
        for the 8 mm pad, so that the groups keep their shape as the tissue is refined (``layers="auto"``
        of ``gym.make`` and the presets)."""
        return max(1, round(self.extrude / self.spacing))


THREADS_ENV = "SOFTGRASP_THREADS"
"""The environment variable that sets the tissue solver's threads where SimConfig.threads is None."""


@dataclass(frozen=True)
class SimConfig:
    """Time stepping and solver settings shared by tissue and pybullet."""

    dt: float = 1.0 / 240.0
    """Physics step [s], at most 1/60 s; one tissue step and one pybullet step per world step.
    Longer steps tear the tissue in the grasp (the contact and coupling corrections grow with dt
    squared)."""
    iterations: int = 3
    """Gauss-Seidel iterations over the shape-matching groups and contacts per step. 3 is the fewest
    at 1/240 s that meets every accuracy target of the defaults; with the default 60 particles an
    iteration costs a few per cent of the step, most of which is pybullet's."""
    rotation_iterations: int = 1
    """Most warm-started rotation-extraction sweeps per group solve (Mueller et al. 2016); stops
    early once the correction is below 1e-10 rad. One sweep per solve suffices with the warm start
    carried by each group's spin."""
    gravity: float = 9.81
    """Gravitational acceleration along -z [m/s^2]."""
    damping: float | None = None
    """Damping rate of each tissue body's deviation from its rigid motion [1/s] (Mueller et al.
    2007 sec. 3.5): the deviation's velocity shrinks by exp(-damping * dt) per step, the same rate
    at every dt; rigid motion, so momentum and angular momentum, are kept. 0 disables it; None:
    COMPLIANT_DAMPING (300/s, about 0.8 of critical for the pad's own ~180 rad/s mode): the pad is
    stiff enough to ring against its finger core, which it pushes on a step late."""
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
    material_solve: MaterialSolve = "groups"
    """How each iteration solves the tissue's material (the implicit step's elastic part):
    'groups', a Newton step per group, Gauss-Seidel over the overlapping groups (tissue/compliant.py),
    which closes the gap to the step's solution by a fixed fraction a pass; 'global', every group's
    rotation from its deformation (the polar factor, by Newton's method) and then one prefactored
    solve over all particles at once with each pad's rest Hessian, a quasi-Newton step of the
    implicit step (tissue/global_step.py), whose passes do not grow with the resolution: 2 world
    steps x 3 passes are within 1.1 % of the converged pad at 16,000 and 64,000 per m^2. 'global'
    needs the continuum group energy (TissueConfig.group_energy) and the thesis coupling; with
    ``threads`` each pad's part of the solve (its block of the factor) runs on a thread of its own.
    Its factor is made once per process for each pad and step length:
    0.04 s for a default pad of 24 free particles, 0.2 s at 450, 10 s at 3,000 (256,000 per m^2) on
    an AMD EPYC core. The world then takes the coupling rule's steps only (compliant.world_substeps).
    On SoftGrasp-v4's scripted grasp it is x2.4 faster than 'groups' at the default density and x3
    at the converged preset, with the same returns to 0.3; the package's documentation, Results:
    speed, "The global material solve", has the figures. ``gym.make(..., material_solve=...)`` sets
    it on an env."""
    global_linear_solve: GlobalLinearSolve = "direct"
    """How each pass of the global material solve (``material_solve`` 'global') solves its linear
    system: 'direct', by the prefactored envelope Cholesky factor (exact; its fill grows faster
    than the particles: 1.6 us per particle a pass at 7,600 particles); 'multigrid', by
    ``multigrid_cycles`` smoothed-aggregation V-cycles (tissue/multigrid.py: a cost linear in the
    particles, each cycle leaving about 1.5 % of the solve's error), the faster past a few thousand
    particles a pad. No factor is made: the contacts' compliances are probed through the levels.
    Needs scipy for the setup (the 'multigrid' extra)."""
    multigrid_cycles: int = 1
    """V-cycles a pass under ``global_linear_solve`` 'multigrid', 1 to 20."""
    contact_margin: float = 0.002
    """Extra distance [m] within which contact candidates are collected per step."""
    threads: int | None = None
    """Threads of the tissue solver [-], 1 to 64: with more than one, the fingers' pads are swept
    (under ``material_solve`` 'global': solved) on threads of their own (each finger's groups touch
    only its own particles and core, so the result is the same to the bit as on one thread). The
    work is split by pad, so a gripper's two pads use at most two threads: more buy nothing. Where a pad has no core of its own (pads sharing one, a
    free block) the solver runs on one thread and warns once (RuntimeWarning). The contacts and
    friction stay on one thread (the pads share the cylinder). None: the environment variable
    SOFTGRASP_THREADS, or 1 without it, so that processes run side by side (vector envs, RLlib workers) do not
    oversubscribe the cores. At most numba's thread count (NUMBA_NUM_THREADS, the cores by
    default). The first threaded step starts numba's thread pool, which fixes NUMBA_NUM_THREADS
    for the process: numba refuses a different value afterwards. A one-thread step loads no
    parallel code and starts no pool."""

    def __post_init__(self) -> None:
        o = "SimConfig"
        check_range("dt", self.dt, 1e-5, 1.0 / 60.0, owner=o)
        check_int("iterations", self.iterations, 1, 200, owner=o)
        check_int("rotation_iterations", self.rotation_iterations, 1, 100, owner=o)
        check_range("gravity", self.gravity, 0.0, 100.0, owner=o)
        if self.damping is not None:
            check_range("damping", self.damping, 0.0, 1e4, owner=o)
        if self.coupling not in COUPLING_MODES:
            raise ValueError(f"SimConfig.coupling must be one of {COUPLING_MODES}, got {self.coupling!r}")
        if self.material_solve not in MATERIAL_SOLVES:
            raise ValueError(f"SimConfig.material_solve must be one of {MATERIAL_SOLVES}, got {self.material_solve!r}")
        if self.material_solve == "global" and self.coupling != "thesis":  # named at make, not at the first step
            raise ValueError("SimConfig.material_solve='global' needs coupling='thesis' (a core sliding inside the "
                             f"solve is not in the global system); got coupling={self.coupling!r}")  # fmt: skip
        if self.global_linear_solve not in GLOBAL_LINEAR_SOLVES:
            raise ValueError(f"SimConfig.global_linear_solve must be one of {GLOBAL_LINEAR_SOLVES}, "
                             f"got {self.global_linear_solve!r}")  # fmt: skip
        if self.global_linear_solve != "direct" and self.material_solve != "global":
            raise ValueError(f"SimConfig.global_linear_solve={self.global_linear_solve!r} solves the global material "
                             f"solve's system: it needs material_solve='global', got {self.material_solve!r}")  # fmt: skip
        check_int("multigrid_cycles", self.multigrid_cycles, 1, 20, owner=o)
        if self.orientation == "reaction":
            raise ValueError(
                "SimConfig.orientation='reaction' was removed (its energy grew with spinning particles); "
                "'goal' now keeps free bodies' angular momentum exactly: use orientation='goal'"
            )
        if self.orientation != "goal":
            raise ValueError(f"SimConfig.orientation must be 'goal', got {self.orientation!r}")
        check_range("contact_margin", self.contact_margin, 0.0, 0.1, owner=o)
        if self.threads is not None:
            check_int("threads", self.threads, 1, 64, owner=o)

    def solver_threads(self) -> int:
        """The tissue solver's thread count: ``threads``, else SOFTGRASP_THREADS, else 1. Raises
        ValueError if the variable is not an integer from 1 to 64, or if the count exceeds numba's
        (NUMBA_NUM_THREADS)."""
        n = self.threads
        if n is None:
            raw = os.environ.get(THREADS_ENV, "").strip()
            if not raw:
                return 1
            try:
                n = int(raw)
            except ValueError:
                raise ValueError(f"{THREADS_ENV} must be an integer from 1 to 64, got {raw!r}") from None
            if not 1 <= n <= 64:
                raise ValueError(f"{THREADS_ENV} must be an integer from 1 to 64, got {raw!r}")
        if n > 1:
            import numba

            if n > numba.config.NUMBA_NUM_THREADS:
                raise ValueError(f"the tissue solver is set to {n} threads, but numba has "
                                 f"{numba.config.NUMBA_NUM_THREADS} (NUMBA_NUM_THREADS, the cores by default)")  # fmt: skip
        return n


def _retired_material(kwargs: dict) -> dict:
    """``material="compliant"`` (the only material since 0.7) is dropped with a DeprecationWarning;
    ``material="per_step"`` and the per-step ``stiffness`` are a ValueError naming 0.6.0.
    ``shear_modulus=None`` / ``max_deviation=None`` (the default, before 0.7) give the default, warned."""
    for name in ("shear_modulus", "max_deviation"):
        if name in kwargs and kwargs[name] is None:
            deprecated(f"TissueConfig({name}=None)", f"leaving {name} out (its default is a number now)")
            del kwargs[name]
    retired_choice(kwargs, "material", kept="compliant", gone=("per_step",), release="0.6.0", owner="TissueConfig")
    if "stiffness" in kwargs:
        raise ValueError(f"TissueConfig.stiffness={kwargs['stiffness']!r} (the per-step material's fraction) was "
                         "retired; `pip install softgrasp-env==0.6.0` (git tag v0.6.0) has it. The tissue's "
                         "elasticity is shear_modulus [Pa]")  # fmt: skip
    return kwargs


def kinetic_friction(tissue: TissueConfig) -> float:
    """mu_k as the solver uses it: ``tissue.friction_kinetic``, or mu_s when that is None."""
    return tissue.friction_static if tissue.friction_kinetic is None else tissue.friction_kinetic


accept_old_names(TissueConfig, {"density": "particle_density", "tissue_density": "mass_density",
                                "friction_dynamic": "friction_kinetic"}, translate=_retired_material)  # fmt: skip
"""Before 0.3 ``density`` (particles per m^2) and ``tissue_density`` (kg/m^3) - while gym.make's
``tissue_density`` meant particles per m^2: one word, two meanings; before 0.7 ``friction_dynamic``
(mu_k, read as ``friction_kinetic``). The old names keep working."""


def field_names(cls: type) -> tuple[str, ...]:
    """Names of a config dataclass's fields (used by CLIs to map flags onto configs)."""
    return tuple(f.name for f in fields(cls))


_MOVED = {"SceneConfig": "softgrasp_env.scene", "FINGER_KINDS": "softgrasp_env.fingers"}


def __getattr__(name: str):
    # Names that moved out of this module when the scene and the finger kinds got modules of their
    # own: still importable from here, with a DeprecationWarning.
    if name in _MOVED:
        import importlib

        warnings.warn(f"softgrasp_env.config.{name} moved to {_MOVED[name]}.{name}", DeprecationWarning, stacklevel=2)
        if name == "FINGER_KINDS":
            return tuple(importlib.import_module(_MOVED[name]).FINGERS)
        return getattr(importlib.import_module(_MOVED[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["COUPLING_MODES", "FRICTION_LAWS", "CouplingMode", "FrictionLaw", "SimConfig", "TissueConfig", "field_names", "kinetic_friction", "replace"]
