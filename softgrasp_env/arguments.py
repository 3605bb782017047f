"""``gym.make`` keyword arguments -> the configs an env is made of, in one place with one validator.

The keywords stay flat, as users pass them (Gymnasium's convention; :data:`KEYWORDS` is the env
card's argument table, :func:`argument_table`). :meth:`EnvArguments.from_kwargs` maps them into
:class:`EnvArguments`, a frozen group of frozen configs - the physics (finger kind, tissue,
solver), the cylinder, the arm's control, the lift task and its start, the start's ranges
(:class:`~softgrasp_env.tasks.StartRanges`), the carry test, the grip-force task, the observation,
the camera - each of which checks its own fields in ``__post_init__`` (softgrasp_env/validation.py's
checkers) and never changes after it is made. What the env derives from them - the start's class,
the physics steps per env step, the base :class:`~softgrasp_env.scene.SceneConfig`, the workspace,
the observation's names, the taxel grid - is a separate frozen :class:`EnvPlan`
(``EnvPlan.of(args)``), which checks what only the derived scene can show: the cylinder fits, the
start is in reach, every corner of the randomisation ranges can start (pure geometry, no scene is
built). :class:`GoalConfig` holds the goal env's own keywords and :func:`check_reset_options` the
reset options. Old spellings keep working with a DeprecationWarning.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from . import presets
from .config import SimConfig, TissueConfig, kinetic_friction
from .fingers import FINGERS, FemConfig, FingerConfig, TissueFingerConfig, finger_config
from .fingers.tactile import MAX_TAXELS, TaxelGrid
from .observation import CARRY_OBS_NAMES, OBS_NAMES, SHAPE_OBS_NAMES, tactile_names, without_object
from .scene import GRIP_TOP, GripperActions, SceneConfig, Workspace, fit_error, geometry_error
from .scene.config import lowest_grip
from .scene.gripper import FINGER_ACTIONS, VelocityActions
from .scene.objects import ObjectShape, object_geometry, object_shape
from .tasks import STARTS, CarryTest, GripForceTask, StartRanges, Task, check_option
from .tasks.carry import (
    CARRY_ACCELERATION_RANGE,
    CARRY_DURATION,
    CARRY_FREQUENCY_BAND,
    CARRY_SLIDE_LIMIT,
    CARRY_START,
    sway_limits_error,
)
from .tasks.goal import DISTANCE_THRESHOLD, GOAL_HEIGHT_RANGE
from .tasks.grip import SQUEEZE_CHARGE_STEPS, SQUEEZE_REFERENCES
from .tasks.reach import APPROACH
from .validation import (
    check_bool,
    check_choice,
    check_int,
    check_range,
    check_type,
    deprecated,
    is_real,
    retired_choice,
)

MAX_ARM_STEP = 1.0 / 120.0
"""Farthest the arm's target may move in one physics step, arm_speed * dt [m]: 3.3 cm tore
the tissue in 2 of 5 probe episodes, 1.7 cm in 2 of 8 (1/60 s with the strongest fingers); the
default moves 0.6 mm."""
MAX_TACTILE_HISTORY = 16
"""Most taxel frames an observation keeps (``tactile_history``): 0.8 s at the default 20 Hz."""
GRIP_TOP_MARGIN = 0.01
"""The start's grip point stays this far below the top of the arm's workspace [m]."""
MIN_CYLINDER_RADIUS = 0.005
"""The smallest cylinder radius a draw may reach [m] (SceneConfig's lower end)."""


RETIRED_CHOICES: tuple[tuple[str, Any, tuple[Any, ...]], ...] = (
    ("arm", "smooth", ("jump",)),
    ("tissue_material", "compliant", ("per_step",)),
    ("carry_direction", "any", ("across",)),
)
"""Keywords removed after 0.6.0 because one choice is left: (name, the choice left, the retired
ones). The one left is accepted with a DeprecationWarning, a retired one is a ValueError naming
0.6.0 (:meth:`EnvArguments.from_kwargs`)."""

RENAMED_KEYWORDS: dict[str, str] = {
    "tissue_density": "particle_density",  # 0.3: one word meant particles per m^2 here, kg/m^3 in TissueConfig
    "gripper_speed": "arm_speed",  # 0.7: SceneConfig's name
    "friction_dynamic": "friction_kinetic",  # 0.7: TissueConfig's name
    "task": "start",  # 0.7: it selects the start; "task" is the composed task (start, carry, grip force)
}
"""Keywords spelled differently before: the old spelling keeps working with a DeprecationWarning
(:meth:`EnvArguments.from_kwargs`)."""


# --- the keywords ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class Keyword:
    """One ``gym.make`` keyword: its row of the env card's argument table, and where it goes."""

    name: str
    group: str
    """The :class:`EnvArguments` config it goes into (``physics``, ``cylinder``, ...)."""
    type: str
    default: Any
    doc: str


def _kw(name: str, group: str, type_: str, default: Any, doc: str) -> Keyword:
    return Keyword(name, group, type_, default, doc)


KEYWORDS: tuple[Keyword, ...] = (
    # physics
    _kw("fingers", "physics", "str or FingerConfig", "tissue",
        "The finger kind: 'tissue' (oriented-particle tissue on rigid cores, the thesis), 'rigid' (the bare "
        "cores), 'segmented' (sprung rigid segments), 'fem' (pybullet's FEM pads), 'rigid_torsion' (the bare "
        "cores with torsional friction of the tissue's contact patch); or a kind's config "
        "(`SegmentedConfig(segments=4)`) for its own settings"),
    _kw("tissue_faces", "physics", "str", None,
        "fingers='tissue': 'contact' (the inner face and tip of each core) or 'all' faces get tissue; None: the "
        "kind's default, 'contact'"),
    _kw("fem_resolution", "physics", "str", None,
        "fingers='fem': the pads' mesh, 'coarse' or 'fine' (several times slower); None: 'coarse'"),
    _kw("preset", "physics", "str", "default",
        "Tissue and solver settings to start from ('fast', 'default', 'accurate', softgrasp_env/presets.py); "
        "`tissue`, `sim` and the tissue arguments override them"),
    _kw("particle_density", "physics", "float", None,
        "Tissue particles per m² of core surface (None: the preset's, 4,000); `tissue_density` before 0.3"),
    _kw("friction_static", "physics", "float", None,
        "μ_s of the finger surface (None: the preset's, 0.9; the rigid kinds' pybullet coefficient)"),
    _kw("friction_kinetic", "physics", "float", None,
        "μ_k of the tissue, at most μ_s (None: the preset's: equal to μ_s, one coefficient as pybullet's rigid "
        "contacts have) (`friction_dynamic` before 0.7)"),
    _kw("tissue_contact_cone", "physics", "bool", None,
        "Coulomb's cone on every tissue contact as well as on each pad's patch (True) or on the patch alone "
        "(False: a pad squeezed on the way down can hold the cylinder after the squeeze is gone; "
        "TissueConfig.contact_cone says why the cones are not the default yet); None: the preset's, False"),
    _kw("friction_law", "physics", "str", None,
        "Where the tissue's Coulomb law is decided: 'patch' (each pad's patch as a whole, a soft-finger contact) "
        "or 'contact' (every contact in its own cone, with its own stick/slide state); None: the preset's, "
        "'patch'"),
    _kw("shear_modulus", "physics", "float", None,
        "The compliant tissue's shear modulus [Pa] (None: the preset's, 4,000: the pad compresses ~4.4 mm under 3"
        " N)"),
    _kw("group_energy", "physics", "str", None,
        "Each tissue group's elastic energy: 'shape_matching' (the thesis' fit, whose stiffness changes with the "
        "groups' size) or 'continuum' (G V ||F - R||², the same material at every particle_density); None: the "
        "preset's, 'shape_matching'"),
    _kw("hourglass_stiffness", "physics", "float", None,
        "The continuum energy's hourglass control, 0 to 1 (a member's miss from its group's affine fit costs "
        "h G V ||r||² / l²; keeps a layered pad's surface smooth); None: the preset's, 0"),
    _kw("layers", "physics", "int or 'auto'", None,
        "Element layers through the pad's thickness, 1 to 8, or 'auto' (a layer about as thick as the particle "
        "spacing: 1 up to 16,000 per m², 2 at 64,000, 4 at 256,000); None: the preset's, 1"),
    _kw("tissue_min_rows", "physics", "int", None,
        "The fewest rows of tissue particles across each side of a finger face, 1 to 4 (2: the 16 mm tip gets two "
        "rows at 4,000 per m², its groups round and the world 3 steps per physics step instead of 6; "
        "TissueConfig.min_rows); None: the preset's, 1"),
    _kw("tissue", "physics", "TissueConfig", None,
        "A whole TissueConfig to start from (None: the preset's)"),
    _kw("sim", "physics", "SimConfig", None,
        "A whole SimConfig (dt, iterations, coupling; None: the preset's)"),
    _kw("threads", "physics", "int", None,
        "Threads of the tissue solver, 1 to 64: each finger's pad swept on its own thread, the same result to the "
        "bit; None: the sim's, else the SOFTGRASP_THREADS environment variable, else 1"),
    _kw("material_solve", "physics", "str", None,
        "How the tissue's material is solved each pass (SimConfig.material_solve): 'groups', a Gauss-Seidel sweep "
        "over the element groups, or 'global', one prefactored solve across all of them, whose passes do not grow "
        "with the resolution and whose world steps are the coupling's alone (the continuum energy; no effect on "
        "fingers without tissue); None: the sim's, 'groups'"),
    _kw("global_linear_solve", "physics", "str", None,
        "How each pass of material_solve='global' solves its system (SimConfig.global_linear_solve): 'direct', the "
        "prefactored Cholesky factor (exact), or 'multigrid', one smoothed-aggregation V-cycle (a cost linear in the "
        "particles, the faster past a few thousand particles a pad; needs scipy); None: the sim's, 'direct'"),
    # cylinder
    _kw("cylinder_radius", "cylinder", "float", 0.03,
        "Cylinder radius [m]"),
    _kw("cylinder_height", "cylinder", "float", 0.1,
        "Cylinder height [m]"),
    _kw("cylinder_mass", "cylinder", "float", 0.1,
        "Cylinder mass [kg] (the object's, when ``object`` is another shape)"),
    _kw("object", "cylinder", "str or ObjectShape", None,
        "What is grasped, if not the cylinder of cylinder_radius and cylinder_height: a named object "
        "('sphere', 'cube', 'slab', 'capsule', 'cone', 'rod', 'elliptic', 'pebble-0', 'pebble-1', 'pebble-2'; "
        "softgrasp_env.scene.objects.PRESETS) or an ObjectShape, or a list of them: one drawn per episode, each as "
        "likely; it has the cylinder_mass and its friction"),
    # control
    _kw("control_frequency", "control", "float", 20.0,
        "Env steps per second [Hz]; must divide the physics rate 1 / sim.dt"),
    _kw("arm_speed", "control", "float", 0.15,
        "Arm speed at full action [m/s]: the action's x, y, z are the palm's velocity, followed along a speed- "
        "and acceleration-limited path; at most 2 and at most 1/120 m per physics step (arm_speed * sim.dt) "
        "(`gripper_speed` before 0.7)"),
    _kw("arm_acceleration", "control", "float", 1.5,
        "Largest acceleration of the arm's path [m/s²]; the palm starts and stops smoothly, the same at every dt"),
    _kw("finger_force", "control", "float", 3.0,
        "Force limit of each finger's motor [N]"),
    _kw("finger_action", "control", "str", "position",
        "What the action's last entry commands: 'position', the fingers' closing travel (-1 fully open, +1 the "
        "faces meeting) with the motors squeezing at most finger_force; 'force', the squeeze itself, 0 N at -1 to"
        " finger_force at +1, the fingers closing until they meet resistance (they never open: for a start with "
        "the cylinder between them)"),
    # lift
    _kw("start", "lift", "str", "reach",
        "The start (`task` before 0.7): 'reach' (above and away from the cylinder, misaligned fingers) or 'easy' "
        "(v0's gentle start, for debugging)"),
    _kw("reward_type", "lift", "str", "dense",
        "'dense' (lift + reach) or 'sparse' (1 while held)"),
    _kw("success_height", "lift", "float", 0.05,
        "Lift that counts as picked up [m]"),
    _kw("reach_weight", "lift", "float", 0.1,
        "Weight of the reach shaping term"),
    _kw("max_tilt", "lift", "float", math.pi / 4,
        "Tilt of the cylinder that ends the episode (knocked over) [rad]"),
    _kw("approach_range", "lift", "(float, float)", APPROACH,
        "start='reach': the annulus the grip starts in, around the origin [m]"),
    # ranges
    _kw("cylinder_position_range", "ranges", "float", None,
        "Cylinder at U(±range) in x and y [m] (None: the start's, 0.07 reach / 0.01 easy)"),
    _kw("lateral_offset_range", "ranges", "float", 0.005,
        "Palm offset along the faces, U(±range) [m]"),
    _kw("yaw_range", "ranges", "float", None,
        "Palm yaw U(±range) [rad] (None: π/4 reach / 5° easy)"),
    _kw("jaw_wedge_range", "ranges", "float", None,
        "Wedge between the faces U(±range) [rad] (None: 0.15 reach / 0 easy)"),
    _kw("friction_range", "ranges", "float", 0.0,
        "Every friction coefficient × U(1 ± range)"),
    _kw("cylinder_radius_range", "ranges", "float", 0.0,
        "Cylinder radius ± U(range) [m]"),
    _kw("cylinder_mass_range", "ranges", "float", 0.0,
        "Cylinder mass × U(1 ± range) (the object's, when ``object`` is another shape)"),
    _kw("object_scale_range", "ranges", "float", 0.0,
        "The object's size, every dimension, × U(1 ± range), 0 to 0.5 (the cylinder's too: then radius and height "
        "together, instead of cylinder_radius_range)"),
    # carry_test
    _kw("carry", "carry_test", "bool", None,
        "The carry test (None: on for start 'reach', off for 'easy')"),
    _kw("carry_start", "carry_test", "float", CARRY_START,
        "When the carry begins after reset [s]"),
    _kw("carry_duration", "carry_test", "float", CARRY_DURATION,
        "How long the arm carries [s]"),
    _kw("carry_frequency", "carry_test", "float or (float, float)", CARRY_FREQUENCY_BAND,
        "The sway's frequency [Hz], or a (low, high) band drawn per episode (1.2-3.0, around the two-point "
        "grasp's ~1.9 Hz pendulum)"),
    _kw("carry_acceleration", "carry_test", "float or (float, float)", CARRY_ACCELERATION_RANGE,
        "The sway's peak acceleration [m/s²], or a (low, high) range drawn per episode; the amplitude is a / (2 "
        "pi f)² (0.5-1.0); the direction is any horizontal one, drawn per episode (reset option carry_direction "
        "fixes it)"),
    _kw("carry_slide_limit", "carry_test", "float", CARRY_SLIDE_LIMIT,
        "Success needs the cylinder held at every step of the carry and its in-hand slide at most this [m]"),
    # grip_force
    _kw("squeeze_weight", "grip_force", "float", 0.0,
        "The grip-force task (the soft grip ids and the rigid ones' v5: 1; the rigid ones' v4: 0.3): the reward "
        "charges squeeze_weight * mean finger force / the reference of squeeze_reference per step "
        "(info['reward_terms']['squeeze']); needs carry=True"),
    _kw("squeeze_reference", "grip_force", "str", "finger_force",
        "What the squeeze charge measures the squeeze in: 'finger_force' (the object set's rigid grip ids' v1: "
        "its share of the finger's full force, the same for every cylinder) or 'least' (every other grip id: in "
        "least forces, m g / (2 mu_s) with this episode's mass and friction, so a squeeze 1.3 x the least costs "
        "the same on a light cylinder as on a heavy one)"),
    _kw("squeeze_charge_steps", "grip_force", "str", "all",
        "Which env steps pay the squeeze charge: 'all' (the rigid grip ids' v4) or 'carry' (the soft grip ids, "
        "the rigid ones' v5: only the carry's, where the least force is judged: closing and lifting cost nothing, "
        "so a grasp carried through pays more than leaving the cylinder alone)"),
    _kw("squeeze_free", "grip_force", "float", 0.0,
        "The part of the squeeze, in units of squeeze_reference, that the charge leaves free: the charge is "
        "squeeze_weight * max(0, F / reference - squeeze_free) (with squeeze_reference='least', 1 charges only "
        "the margin over the static least force; the soft grip ids and the rigid ones' v5: 1, before it 0)"),
    _kw("squeeze_factor", "grip_force", "float", None,
        "The grip-force task (the grip ids: 2): success also needs the carry's mean squeeze at most this many"
        " times the least force that holds the cylinder through it (Coulomb, with its measured accelerations; "
        "info['carry_squeeze'], info['least_squeeze']); needs carry=True. None: off"),
    # observation
    _kw("tactile", "observation", "(int, int)", None,
        "(rows, cols): the observation ends with each pad's taxels on a rows x cols grid over the core's inner "
        "face, five per taxel: pressure and traction along y, z [Pa] and the tissue's shear along y, z [m] (0 for"
        " rigid pads); `softgrasp_env.observation.tactile_view` reshapes them. None: no tactile entries"),
    _kw("tactile_history", "observation", "int", 1,
        "Taxel frames in the observation, this env step's and the k - 1 before it (needs `tactile`): each earlier"
        " frame's entries follow the current one's, tactile_past<d>_<left/right>_r<row>_c<col>_<channel> d env "
        "steps back (a new episode's first observation repeats its frame); "
        "`softgrasp_env.observation.tactile_frames` reshapes them. A slip is a change: one frame does not show it"),
    _kw("observe_object", "observation", "bool", True,
        "False: the observation leaves out the cylinder's pose and motion (cyl_rel, cyl_axis, cyl_v, cyl_w, "
        "lift), keeping what the gripper's own sensors give - its pose and velocity, the fingers' gap and forces,"
        " the clock, the taxels (the grip ids: an exact in-hand pose would show a slip without touch)"),
    _kw("observe_shape", "observation", "bool", None,
        "True: the observation describes the object after the clock - its kind one-hot (shape_cylinder, "
        "shape_sphere, ..., shape_hull) and its half extents at rest (shape_extent_x/y/z [m]); None: on when "
        "`object` or `object_scale_range` is given"),
    # camera
    _kw("render_width", "camera", "int", 480,
        "Width of an rgb_array frame [px]"),
    _kw("render_height", "camera", "int", 360,
        "Height of an rgb_array frame [px]"),
    _kw("render_camera", "camera", "str", "follow",
        "'follow' (frame the gripper and the cylinder wherever they are) or 'fixed' (look at the cylinder's "
        "start, so a video shows the lift as motion)"),
    _kw("camera_distance", "camera", "float", None,
        "Camera distance from its target [m] (None: follow fits the bodies in the frame, fixed 0.55)"),
    _kw("camera_yaw", "camera", "float", 35.0,
        "Camera yaw about the vertical [deg]"),
    _kw("camera_pitch", "camera", "float", -25.0,
        "Camera pitch [deg], negative looking down"),
    _kw("camera_target", "camera", "(float, float, float)", None,
        "The point the camera looks at [m] (None: follow aims at the bodies, fixed at the cylinder's start 12 cm "
        "up)"),
)
"""Every ``gym.make`` keyword, in the order of the env card's argument table."""

KEYWORD = {k.name: k for k in KEYWORDS}


# --- the configs, each validating itself ----------------------------------------------------------


@dataclass(frozen=True)
class PhysicsConfig:
    """The finger kind with its own settings, the finger surface's material and the solver:
    ``fingers``, ``tissue_faces``, ``fem_resolution``, ``preset``, the tissue keywords, ``tissue``
    and ``sim`` (:meth:`of` resolves the preset and the overrides)."""

    fingers: FingerConfig
    tissue: TissueConfig
    sim: SimConfig

    def __post_init__(self) -> None:
        finger_config(self.fingers)  # a registered kind's config
        check_type("tissue", self.tissue, TissueConfig)
        check_type("sim", self.sim, SimConfig)

    @classmethod
    def of(cls, *, fingers: str | FingerConfig = "tissue", tissue_faces: str | None = None,
           fem_resolution: str | None = None, preset: str = "default", particle_density: float | None = None,
           friction_static: float | None = None, friction_kinetic: float | None = None,
           tissue_contact_cone: bool | None = None, friction_law: str | None = None,
           shear_modulus: float | None = None, group_energy: str | None = None,
           hourglass_stiffness: float | None = None, layers: int | str | None = None,
           tissue_min_rows: int | None = None, tissue: TissueConfig | None = None, sim: SimConfig | None = None,
           threads: int | None = None, material_solve: str | None = None,
           global_linear_solve: str | None = None) -> PhysicsConfig:  # fmt: skip
        """The configs the keywords mean: the kind's config with its own keywords folded in, the
        preset's tissue and solver (or the whole ones given) with the tissue keywords over them.
        ``layers="auto"`` (given, or the preset's when neither ``layers`` nor ``tissue`` is given)
        is resolved last, for the density the tissue ends up with (TissueConfig.auto_layers)."""
        fingers = finger_config(fingers)
        if tissue_faces is not None:
            if not isinstance(fingers, TissueFingerConfig):
                raise ValueError(f"tissue_faces is a setting of fingers='tissue', but fingers={fingers.kind!r}")
            fingers = replace(fingers, faces=tissue_faces)
        if fem_resolution is not None:
            if not isinstance(fingers, FemConfig):
                raise ValueError(f"fem_resolution is a setting of fingers='fem', but fingers={fingers.kind!r}")
            fingers = replace(fingers, resolution=fem_resolution)
        check_choice("preset", preset, tuple(presets.PRESETS))
        base = presets.scene_config(preset)
        given = tissue
        tissue = tissue if tissue is not None else base.tissue
        check_type("tissue", tissue, TissueConfig)
        if given is not None and None not in (tissue.friction_kinetic, friction_kinetic) \
                and tissue.friction_kinetic != friction_kinetic:  # fmt: skip
            raise ValueError(f"friction_kinetic={friction_kinetic!r} and tissue.friction_kinetic="
                             f"{tissue.friction_kinetic!r} disagree: give one of them")  # fmt: skip
        if layers is None and given is None:
            layers = presets.PRESETS[preset].get("tissue", {}).get("layers")
        if layers is not None and layers != "auto" and not (isinstance(layers, int) and not isinstance(layers, bool)):
            raise ValueError(f"layers must be an int from 1 to 8 or 'auto', got {layers!r}")
        overrides = {k: v for k, v in (("particle_density", particle_density), ("friction_static", friction_static),
                                       ("friction_kinetic", friction_kinetic), ("contact_cone", tissue_contact_cone),
                                       ("friction_law", friction_law), ("shear_modulus", shear_modulus),
                                       ("group_energy", group_energy), ("hourglass_stiffness", hourglass_stiffness),
                                       ("layers", layers if layers != "auto" else None),
                                       ("min_rows", tissue_min_rows))
                     if v is not None}  # fmt: skip
        tissue = replace(tissue, **overrides)  # validated by TissueConfig
        if layers == "auto":
            tissue = replace(tissue, layers=tissue.auto_layers)
        sim = sim if sim is not None else base.sim
        check_type("sim", sim, SimConfig)
        if threads is not None:
            sim = replace(sim, threads=threads)  # validated by SimConfig
        if material_solve is not None:
            # a setting of the tissue's solver, like the tissue's own keywords taken by every kind of
            # finger: the soft ids carry it, and gym.make(SoftGrasp-v5, fingers="rigid") is the rigid
            # twin, whose sim no tissue reads
            sim = replace(sim, material_solve=material_solve)  # validated by SimConfig
        if global_linear_solve is not None:
            sim = replace(sim, global_linear_solve=global_linear_solve)  # validated by SimConfig
        return cls(fingers, tissue, sim)


@dataclass(frozen=True)
class CylinderConfig:
    """The cylinder every episode's draw starts from (``cylinder_radius``, ``cylinder_height``,
    ``cylinder_mass``)."""

    radius: float = 0.03
    """[m]"""
    height: float = 0.10
    """[m]"""
    mass: float = 0.1
    """[kg]"""
    object: ObjectShape | None = None
    """Another shape to grasp instead (``object``; a cylinder given there becomes radius and
    height), or None: the cylinder."""
    name: str = "cylinder"
    """What the object is called (``info["object"]``): the named object's name ('rod' for the rod,
    which is radius and height here), or the shape's."""

    def __post_init__(self) -> None:
        check_type("name", self.name, str)
        check_range("cylinder_height", self.height, 0.01, 0.5)
        check_range("cylinder_radius", self.radius, 0.005, 0.2)
        check_range("cylinder_mass", self.mass, 0.001, 10.0)
        if self.object is not None:
            check_type("object", self.object, ObjectShape)
            if self.object.kind == "cylinder":
                raise ValueError("CylinderConfig.object: a cylinder is given by radius and height")


@dataclass(frozen=True)
class ControlConfig:
    """How the action drives the gripper (``control_frequency``, ``arm_speed``,
    ``arm_acceleration``, ``finger_action``, ``finger_force``)."""

    frequency: float = 20.0
    """Env steps per second [Hz]."""
    arm_speed: float = 0.15
    """The palm's speed at full action [m/s]."""
    arm_acceleration: float = 1.5
    """The arm path's largest acceleration [m/s^2]."""
    finger_action: str = "position"
    """What the action's last entry commands: 'position' or 'force'."""
    finger_force: float = 3.0
    """Each finger motor's force limit, the squeeze at full action with 'force' [N]."""

    def __post_init__(self) -> None:
        check_range("control_frequency", self.frequency, 0.5, 240.0)
        check_choice("finger_action", self.finger_action, FINGER_ACTIONS)
        check_range("arm_speed", self.arm_speed, 0.0, 2.0, lo_open=True)
        check_range("arm_acceleration", self.arm_acceleration, 0.0, 50.0, lo_open=True)
        check_range("finger_force", self.finger_force, 0.0, 1000.0, lo_open=True)


@dataclass(frozen=True)
class LiftConfig:
    """The lift task: which start, and how a step is judged (``start``, ``reward_type``,
    ``success_height``, ``reach_weight``, ``max_tilt``, ``approach_range``)."""

    start: str = "reach"
    """The start's name in :data:`~softgrasp_env.tasks.STARTS`."""
    reward_type: str = "dense"
    success_height: float = 0.05
    """[m]"""
    reach_weight: float = 0.1
    max_tilt: float = math.pi / 4
    """[rad]"""
    approach: tuple[float, float] = APPROACH
    """The annulus the reach start's grip starts in [m]."""

    def __post_init__(self) -> None:
        check_choice("start", self.start, tuple(STARTS))
        check_choice("reward_type", self.reward_type, ("dense", "sparse"))
        check_range("success_height", self.success_height, 0.0, 0.15, lo_open=True)
        check_range("reach_weight", self.reach_weight, 0.0, 10.0)
        check_range("max_tilt", self.max_tilt, 0.0, math.pi, lo_open=True)
        a = self.approach
        if not (isinstance(a, tuple) and len(a) == 2 and all(is_real(v) for v in a)):
            raise ValueError(f"approach_range must be (min, max) distances in m, got {a!r}")
        if not (math.isfinite(a[0]) and math.isfinite(a[1]) and 0.0 <= a[0] <= a[1] <= 0.14):
            raise ValueError("approach_range must be 0 <= min <= max <= 0.14 m (the grip's workspace is +-0.15 m), "
                             f"got {a!r}")  # fmt: skip


@dataclass(frozen=True)
class CarryConfig:
    """The carry test (``carry``, ``carry_start``, ``carry_duration``, ``carry_frequency``,
    ``carry_acceleration``, ``carry_slide_limit``); its settings are checked whether it is on or
    not."""

    on: bool = True
    start_time: float = CARRY_START
    """When the carry begins after reset [s]."""
    duration: float = CARRY_DURATION
    """[s]"""
    frequency: float | tuple[float, float] = CARRY_FREQUENCY_BAND
    """The sway's frequency, or a (low, high) band drawn per episode [Hz]."""
    acceleration: float | tuple[float, float] = CARRY_ACCELERATION_RANGE
    """The sway's peak acceleration, or a (low, high) range drawn per episode [m/s^2]."""
    slide_limit: float = CARRY_SLIDE_LIMIT
    """The success's largest in-hand slide [m]."""

    def __post_init__(self) -> None:
        check_bool("carry", self.on, hint=" (or None: the start's default)")
        check_range("carry_start", self.start_time, 0.0, 600.0)
        check_range("carry_duration", self.duration, 0.0, 600.0, lo_open=True)
        for name, value, hi, lo_open in (("carry_frequency", self.frequency, 10.0, True),
                                         ("carry_acceleration", self.acceleration, 50.0, False)):  # fmt: skip
            if isinstance(value, tuple):
                if len(value) != 2:
                    raise ValueError(f"{name} must be a number or (low, high), got {value!r}")
                for k, v in enumerate(value):
                    check_range(f"{name}[{k}]", v, 0.0, hi, lo_open=lo_open)
                if value[0] > value[1]:
                    raise ValueError(f"{name} must be (low, high) with low <= high, got {value!r}")
            else:
                check_range(name, value, 0.0, hi, lo_open=lo_open)
        check_range("carry_slide_limit", self.slide_limit, 0.0, 0.1, lo_open=True)

    def corners(self) -> list[tuple[float, float]]:
        """(frequency, amplitude) at the corners of the sway's ranges: its peak speed and
        acceleration are largest at one of them."""
        fs = self.frequency if isinstance(self.frequency, tuple) else (self.frequency,)
        accels = self.acceleration if isinstance(self.acceleration, tuple) else (self.acceleration,)
        return [(f, a / (2.0 * math.pi * f) ** 2) for f in fs for a in accels]


@dataclass(frozen=True)
class GripForceConfig:
    """The grip-force task over the carry (``squeeze_weight``, ``squeeze_factor``); on when either
    is set."""

    squeeze_weight: float = 0.0
    squeeze_factor: float | None = None
    squeeze_reference: str = "finger_force"
    """The charge's unit of squeeze: the finger's full force, or the episode's static least force
    (tasks.grip.SQUEEZE_REFERENCES)."""
    squeeze_charge_steps: str = "all"
    """Which env steps pay the charge: every one, or the carry's (tasks.grip.SQUEEZE_CHARGE_STEPS)."""
    squeeze_free: float = 0.0
    """The squeeze the charge leaves free, in references (tasks.grip.GripForceTask)."""

    def __post_init__(self) -> None:
        check_range("squeeze_weight", self.squeeze_weight, 0.0, 10.0)
        if self.squeeze_factor is not None:
            check_range("squeeze_factor", self.squeeze_factor, 1.0, 100.0)
        check_choice("squeeze_reference", self.squeeze_reference, SQUEEZE_REFERENCES)
        check_choice("squeeze_charge_steps", self.squeeze_charge_steps, SQUEEZE_CHARGE_STEPS)
        check_range("squeeze_free", self.squeeze_free, 0.0, 100.0)

    @property
    def on(self) -> bool:
        return self.squeeze_weight > 0.0 or self.squeeze_factor is not None


@dataclass(frozen=True)
class ObservationConfig:
    """What the observation holds beyond the gripper's own state (``observe_object``,
    ``tactile``)."""

    observe_object: bool = True
    tactile: tuple[int, int] | None = None
    """(rows, cols) of each pad's taxel grid, or None."""
    observe_shape: bool = False
    """Whether the observation describes the object's shape (its kind and extents)."""
    tactile_history: int = 1
    """Taxel frames in the observation: this env step's and the ``tactile_history - 1`` before it."""

    def __post_init__(self) -> None:
        check_bool("observe_object", self.observe_object)
        check_bool("observe_shape", self.observe_shape)
        check_int("tactile_history", self.tactile_history, 1, MAX_TACTILE_HISTORY)
        if self.tactile is not None:
            if not isinstance(self.tactile, tuple) or len(self.tactile) != 2:
                raise ValueError(f"tactile must be (rows, cols) or None, got {self.tactile!r}")
            check_int("tactile[0] (rows)", self.tactile[0], 1, MAX_TAXELS)
            check_int("tactile[1] (cols)", self.tactile[1], 1, MAX_TAXELS)
        elif self.tactile_history > 1:
            raise ValueError(f"tactile_history={self.tactile_history!r} keeps earlier taxel frames: give tactile=(rows, "
                             "cols) too")  # fmt: skip


@dataclass(frozen=True)
class CameraConfig:
    """An ``rgb_array`` frame's size and where it is seen from (``render_width``,
    ``render_height``, ``render_camera``, ``camera_distance``, ``camera_yaw``, ``camera_pitch``,
    ``camera_target``)."""

    width: int = 480
    """[px]"""
    height: int = 360
    """[px]"""
    mode: str = "follow"
    """'follow' or 'fixed'."""
    distance: float | None = None
    """[m]"""
    yaw: float = 35.0
    """[deg]"""
    pitch: float = -25.0
    """[deg]"""
    target: tuple[float, float, float] | None = None
    """[m]"""

    def __post_init__(self) -> None:
        check_int("render_width", self.width, 16, 4096)
        check_int("render_height", self.height, 16, 4096)
        check_choice("render_camera", self.mode, ("follow", "fixed"))
        if self.distance is not None:
            check_range("camera_distance", self.distance, 0.05, 3.0)
        check_range("camera_yaw", self.yaw, -360.0, 360.0)
        check_range("camera_pitch", self.pitch, -89.0, 89.0)
        t = self.target
        if t is not None:
            if not (isinstance(t, tuple) and all(is_real(v) for v in t)):
                raise ValueError(f"camera_target must be (x, y, z) in m or None, got {t!r}")
            if len(t) != 3 or not all(math.isfinite(v) and abs(v) <= 1.0 for v in t):
                raise ValueError(f"camera_target must be (x, y, z) with each within 1 m of the origin, got {t!r}")


GROUPS: dict[str, type] = {"physics": PhysicsConfig, "cylinder": CylinderConfig, "control": ControlConfig,
                           "lift": LiftConfig, "ranges": StartRanges, "carry_test": CarryConfig,
                           "grip_force": GripForceConfig, "observation": ObservationConfig, "camera": CameraConfig}  # fmt: skip
""":class:`EnvArguments`' configs by field name (the argument table's groups)."""


@dataclass(frozen=True)
class EnvArguments:
    """The env's keyword arguments as validated configs (:meth:`from_kwargs` makes them from
    ``gym.make``'s flat keywords). Each config checks its own fields; this checks the rules that
    join two of them."""

    physics: PhysicsConfig
    cylinder: CylinderConfig
    control: ControlConfig
    lift: LiftConfig
    ranges: StartRanges
    carry_test: CarryConfig
    grip_force: GripForceConfig
    observation: ObservationConfig
    camera: CameraConfig

    def __post_init__(self) -> None:
        for name, cls in GROUPS.items():
            check_type(name, getattr(self, name), cls)
        grip, carry, control, sim = self.grip_force, self.carry_test, self.control, self.physics.sim
        if grip.on and not carry.on:
            raise ValueError(f"squeeze_weight={grip.squeeze_weight!r} / squeeze_factor={grip.squeeze_factor!r} set "
                             "the grip-force task, which judges the squeeze over the carry: give carry=True")  # fmt: skip
        if carry.on:
            for f, amplitude in carry.corners():
                problem = sway_limits_error(f, amplitude=amplitude, speed=control.arm_speed,
                                            arm_acceleration=control.arm_acceleration)  # fmt: skip
                if problem:
                    raise ValueError(f"the carry's sway at {f:g} Hz ({amplitude * 100:.3g} cm) {problem}: lower "
                                     "carry_acceleration or carry_frequency")  # fmt: skip
        ratio = 1.0 / (sim.dt * control.frequency)
        substeps = int(round(ratio))
        if abs(ratio - substeps) > 1e-9 * ratio or substeps < 1:
            raise ValueError(f"control_frequency must divide the physics rate 1/sim.dt = {1.0 / sim.dt:g} Hz, "
                             f"got {control.frequency!r}")  # fmt: skip
        if control.arm_speed * sim.dt > MAX_ARM_STEP + 1e-12:
            raise ValueError(f"arm_speed={control.arm_speed:g} m/s with sim.dt={sim.dt:g} s moves the arm "
                             f"{control.arm_speed * sim.dt * 100:.2f} cm per physics step, more than "
                             f"{MAX_ARM_STEP * 100:.2f} cm; at this dt arm_speed must be at most "
                             f"{MAX_ARM_STEP / sim.dt:.3g} m/s")  # fmt: skip
        # (the carry's sway keeps within arm_speed, above, so within MAX_ARM_STEP per step too)
        if self.cylinder.radius - self.ranges.cylinder_radius < MIN_CYLINDER_RADIUS:
            raise ValueError(f"cylinder_radius - cylinder_radius_range must be >= {MIN_CYLINDER_RADIUS} m, got "
                             f"{self.cylinder.radius} - {self.ranges.cylinder_radius}")  # fmt: skip
        if self.observation.tactile is not None:
            reason = FINGERS[self.physics.fingers.kind].no_tactile
            if reason is not None:
                raise ValueError(f"tactile={self.observation.tactile!r} with fingers={self.physics.fingers.kind!r}: "
                                 f"{reason}")  # fmt: skip

    @classmethod
    def from_kwargs(cls, **kwargs: Any) -> EnvArguments:
        """The arguments from ``gym.make``'s flat keywords (:data:`KEYWORDS`): unknown names are a
        TypeError listing the known ones; the old spellings (``soft=``, and
        :data:`RENAMED_KEYWORDS`: ``tissue_density=``, ``gripper_speed=``, ``friction_dynamic=``,
        ``task=``) keep working with a DeprecationWarning, and so do the choices that are the only
        ones left since 0.7 (``arm="smooth"``, ``tissue_material="compliant"``,
        ``carry_direction="any"``); the retired ones (``arm="jump"``, ``tissue_material="per_step"``,
        ``carry_direction="across"``, ``carry_amplitude``, ``carry_slide_limit=None``) are a
        ValueError naming 0.6.0, the last release that has them."""
        kwargs = dict(kwargs)
        for name, kept, gone in RETIRED_CHOICES:
            retired_choice(kwargs, name, kept=kept, gone=gone, release="0.6.0", stacklevel=5)
        if "carry_amplitude" in kwargs:
            raise ValueError(f"carry_amplitude={kwargs['carry_amplitude']!r} was retired; `pip install "
                             "softgrasp-env==0.6.0` (git tag v0.6.0) has it. Give the sway's peak acceleration "
                             "instead: carry_acceleration = amplitude * (2 pi carry_frequency)^2 [m/s^2]")  # fmt: skip
        if "carry_slide_limit" in kwargs and kwargs["carry_slide_limit"] is None:
            raise ValueError("carry_slide_limit=None (success once the carry is over) was retired; `pip install "
                             "softgrasp-env==0.6.0` (git tag v0.6.0) has it. Give a slide limit in m")  # fmt: skip
        if "soft" in kwargs:
            soft = kwargs.pop("soft")
            deprecated("the soft= argument", "fingers='tissue' or fingers='rigid'", stacklevel=5)
            check_bool("soft", soft)
            given = kwargs.get("fingers", "tissue")
            kind = given.kind if isinstance(given, FingerConfig) else given
            # soft chooses between the two kinds it used to; a kind it never named (segmented,
            # fem) wins, as it did
            if kind in ("tissue", "rigid"):
                want = "tissue" if soft else "rigid"
                if isinstance(given, FingerConfig) and kind != want:
                    raise ValueError(f"soft={soft} contradicts fingers={given!r}: give fingers= alone")
                kwargs["fingers"] = given if kind == want else want
        for old, new in RENAMED_KEYWORDS.items():
            if old in kwargs:
                if new in kwargs:
                    raise TypeError(f"give {new}= (the new name of {old}=), not both")
                deprecated(f"the {old}= argument", f"{new}=", stacklevel=5)
                kwargs[new] = kwargs.pop(old)
        unknown = sorted(set(kwargs) - set(KEYWORD))
        if unknown:
            raise TypeError(f"unknown argument(s) {unknown}; the env takes {sorted(KEYWORD)}")
        v = {**{k.name: k.default for k in KEYWORDS}, **kwargs}
        physics = PhysicsConfig.of(**{k: v[k] for k in ("fingers", "tissue_faces", "fem_resolution", "preset",
                                                         "particle_density", "friction_static", "friction_kinetic",
                                                         "tissue_contact_cone", "friction_law", "shear_modulus",
                                                         "group_energy", "hourglass_stiffness", "layers",
                                                         "tissue_min_rows", "tissue", "sim", "threads",
                                                         "material_solve", "global_linear_solve")})  # fmt: skip
        lift = LiftConfig(v["start"], v["reward_type"], v["success_height"], v["reach_weight"], v["max_tilt"],
                          _tuple(v["approach_range"]))  # fmt: skip
        defaults = STARTS[lift.start].defaults  # None: the start's
        ranges = StartRanges(**{name: _real(_given(v[f"{name}_range"], defaults.get(name))) for name in (
            "cylinder_position", "lateral_offset", "yaw", "jaw_wedge", "friction", "cylinder_radius", "cylinder_mass",
            "object_scale")},
            objects=_object_set(v["object"], kwargs))
        if ranges.object_scale and ranges.cylinder_radius:
            raise ValueError(f"object_scale_range={ranges.object_scale!r} and cylinder_radius_range="
                             f"{ranges.cylinder_radius!r} both draw the cylinder's size; give one")  # fmt: skip
        carry = CarryConfig(_given(v["carry"], defaults["carry"]), v["carry_start"], v["carry_duration"],
                            _tuple(v["carry_frequency"]), _tuple(v["carry_acceleration"]), v["carry_slide_limit"])  # fmt: skip
        return cls(
            physics=physics,
            cylinder=_cylinder_or_object(v, kwargs),
            control=ControlConfig(v["control_frequency"], v["arm_speed"], v["arm_acceleration"], v["finger_action"],
                                  v["finger_force"]),
            lift=lift,
            ranges=ranges,
            carry_test=carry,
            grip_force=GripForceConfig(v["squeeze_weight"], v["squeeze_factor"], v["squeeze_reference"],
                                       v["squeeze_charge_steps"], v["squeeze_free"]),
            observation=ObservationConfig(v["observe_object"], _tuple(v["tactile"], integers=True),
                                          _given(v["observe_shape"], v["object"] is not None or
                                                 bool(ranges.object_scale)), v["tactile_history"]),
            camera=CameraConfig(v["render_width"], v["render_height"], v["render_camera"], v["camera_distance"],
                                v["camera_yaw"], v["camera_pitch"], _tuple(v["camera_target"])),
        )  # fmt: skip

    def __getattr__(self, name: str) -> Any:
        # a keyword's value under its flat name, as EnvArguments held them before 0.7
        if name in _FLAT:
            group, attr = _FLAT[name]
            deprecated(f"EnvArguments.{name}", f"EnvArguments.{group}.{attr}")
            return getattr(getattr(self, group), attr)
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")


_FLAT: dict[str, tuple[str, str]] = {
    "fingers": ("physics", "fingers"), "tissue": ("physics", "tissue"), "sim": ("physics", "sim"),
    **{f"cylinder_{a}": ("cylinder", a) for a in ("radius", "height", "mass")},
    "control_frequency": ("control", "frequency"),
    **{a: ("control", a) for a in ("arm_speed", "arm_acceleration", "finger_action", "finger_force")},
    **{a: ("lift", a) for a in ("start", "reward_type", "success_height", "reach_weight", "max_tilt")},
    "approach_range": ("lift", "approach"),
    **{f"{a}_range": ("ranges", a) for a in ("cylinder_position", "lateral_offset", "yaw", "jaw_wedge", "friction",
                                             "cylinder_radius", "cylinder_mass")},
    "carry": ("carry_test", "on"),
    "carry_start": ("carry_test", "start_time"),
    **{f"carry_{a}": ("carry_test", a) for a in ("duration", "frequency", "acceleration", "slide_limit")},
    **{a: ("grip_force", a) for a in ("squeeze_weight", "squeeze_factor", "squeeze_reference",
                                      "squeeze_charge_steps", "squeeze_free")},
    **{a: ("observation", a) for a in ("observe_object", "tactile", "observe_shape", "tactile_history")},
    "render_width": ("camera", "width"), "render_height": ("camera", "height"), "render_camera": ("camera", "mode"),
    **{f"camera_{a}": ("camera", a) for a in ("distance", "yaw", "pitch", "target")},
}  # fmt: skip
"""Flat keyword -> (config, field) of the keywords that are a field of one config (the others fold
into a config: ``tissue_faces`` into ``physics.fingers``, the tissue keywords into
``physics.tissue``)."""


def _cylinder_or_object(v: dict[str, Any], given: dict[str, Any]) -> CylinderConfig:
    """The ``cylinder`` group of the keywords ``v`` (``given``: those the caller gave): ``object``
    a cylinder sets radius and height, another shape stands instead of the cylinder, and neither
    may come with the cylinder's own size keywords."""
    if v["object"] is None or isinstance(v["object"], (tuple, list)):  # a set: drawn per episode (StartRanges)
        return CylinderConfig(v["cylinder_radius"], v["cylinder_height"], v["cylinder_mass"])
    shape = object_shape(v["object"])
    clash = sorted(k for k in ("cylinder_radius", "cylinder_height", "cylinder_radius_range")
                   if k in given and given[k] != KEYWORD[k].default)  # fmt: skip
    if clash:
        raise ValueError(f"object={v['object']!r} with {', '.join(f'{k}={given[k]!r}' for k in clash)}: the object "
                         "has its own size (give an ObjectShape for another size)")  # fmt: skip
    if shape.kind == "cylinder":
        return CylinderConfig(shape.size[0], shape.size[1], v["cylinder_mass"], name=shape.name)
    return CylinderConfig(mass=v["cylinder_mass"], object=shape, name=shape.name)


def _object_set(value: Any, given: dict[str, Any]) -> tuple[ObjectShape, ...]:
    """The objects of ``object=`` given as a list or tuple (names or ObjectShapes), drawn one per
    episode; () for one object or none."""
    if not isinstance(value, (tuple, list)):
        return ()
    if len(value) < 2:
        raise ValueError(f"object= as a set needs at least two objects, got {value!r} (give one object by itself)")
    shapes = tuple(object_shape(x) for x in value)
    if len(set(shapes)) != len(shapes):
        raise ValueError(f"object= names an object twice: {value!r}")
    clash = sorted(k for k in ("cylinder_radius", "cylinder_height", "cylinder_radius_range")
                   if k in given and given[k] != KEYWORD[k].default)  # fmt: skip
    if clash:
        raise ValueError(f"object={value!r} with {', '.join(f'{k}={given[k]!r}' for k in clash)}: the objects have "
                         "their own sizes")  # fmt: skip
    return shapes


def _given(value: Any, default: Any) -> Any:
    return default if value is None else value


def _real(value: Any) -> Any:
    return float(value) if is_real(value) else value


def _tuple(value: Any, *, integers: bool = False) -> Any:
    """A list or tuple of numbers as a tuple of floats (with ``integers``: numpy's integers as
    Python's, the rest as given); anything else as given, for its config to judge."""
    if isinstance(value, (list, tuple)) and all(is_real(v) for v in value):
        if integers:
            return tuple(int(v) if isinstance(v, np.integer) else v for v in value)
        return tuple(float(v) for v in value)
    if isinstance(value, list):
        return tuple(value)
    return value


# --- what the env derives from the arguments ------------------------------------------------------


@dataclass(frozen=True)
class EnvPlan:
    """What the env is composed of, derived from its :class:`EnvArguments` by :meth:`of` (which
    checks what only the derived scene can show)."""

    args: EnvArguments
    start_class: type
    """The start's class (``STARTS[args.lift.start]``)."""
    substeps: int
    """Physics steps per env step."""
    scene: SceneConfig
    """The base scene every episode's draw starts from."""
    workspace: Workspace
    obs_names: tuple[str, ...]
    """The observation's entries, in order."""
    taxel_grid: TaxelGrid | None
    """The pads' taxel grid of ``tactile`` (None without)."""

    @classmethod
    def of(cls, args: EnvArguments) -> EnvPlan:
        """The plan of ``args``: the start height is the start's, decided once; the pad must fit
        the open fingers before the start is judged, so a pad too thick is named as such; then
        every corner of the randomisation ranges must start."""
        start = STARTS[args.lift.start]
        phys, cyl = args.physics, args.cylinder
        substeps = int(round(1.0 / (phys.sim.dt * args.control.frequency)))
        field_defaults = SceneConfig.__dataclass_fields__
        fh = field_defaults["finger_half_extents"].default
        stroke = field_defaults["finger_stroke"].default
        pad = FINGERS[phys.fingers.kind].pad_thickness(phys.fingers, phys.tissue)
        # (another object's fit is judged with the scene, below: SceneConfig's geometry_error)
        error = None if cyl.object is not None else fit_error(
            cylinder_radius=cyl.radius, jaw_wedge=0.0, finger_stroke=stroke, pad=pad, finger_half_height=fh[2],
            kind=phys.fingers.kind)  # fmt: skip
        if error is not None:
            raise ValueError(error)
        objects = args.ranges.objects or ((cyl.object,) if cyl.object is not None else ())
        scale = args.ranges.object_scale
        if scale and not objects:  # the cylinder, scaled as an object
            objects = (ObjectShape("cylinder", (cyl.radius, cyl.height), label=cyl.name),)
        if scale:  # each object at both ends of its size range: the largest decides the start
            objects = tuple(_scaled(shape, f, "object_scale_range", scale) for shape in objects
                            for f in (1.0 - scale, 1.0 + scale))  # fmt: skip
        if not objects:
            height, grasp_z = cyl.height, 0.5 * cyl.height
            start_height = start.start_height(height, fh[2], pad)
        else:
            # each gripped at its centre of mass or just above the ground (scene.config.grasp_height)
            # stands as a cylinder whose mid height that is and whose top is the object's; a set
            # starts as high above each as its tallest needs
            start_height, grasp_z = -math.inf, -math.inf
            for shape in objects:
                geo = object_geometry(shape)
                z = max(geo.rest_height, lowest_grip(fh[2], phys.tissue.extrude))
                start_height = max(start_height, start.start_height(2.0 * (geo.top - z), fh[2], pad))
                grasp_z = max(grasp_z, z)
        top = GRIP_TOP - GRIP_TOP_MARGIN
        grip_z = grasp_z + start_height
        if objects and grip_z > top:
            raise ValueError(f"object={args.ranges.objects or cyl.object!r} is too tall for start={args.lift.start!r}: "
                             f"the grip would start {grip_z:.3f} m up, too near the top of the arm's workspace "
                             f"({GRIP_TOP:g} m)")  # fmt: skip
        if grip_z > top:
            raise ValueError(f"cylinder_height={cyl.height:g} m is too tall for start={args.lift.start!r}: the grip "
                             f"would start {grip_z:.3f} m up, too near the top of the arm's workspace ({GRIP_TOP:g} "
                             f"m); at most {start.tallest_cylinder(top, fh[2], pad):.3f} m")  # fmt: skip
        scene = SceneConfig(fingers=phys.fingers, cylinder_radius=cyl.radius, cylinder_height=cyl.height,
                            cylinder_mass=cyl.mass, finger_force=args.control.finger_force, tissue=phys.tissue,
                            sim=phys.sim, start_height=start_height, arm_speed=args.control.arm_speed,
                            arm_acceleration=args.control.arm_acceleration, object=cyl.object,
                            object_name=cyl.name)  # fmt: skip
        for shape in (objects if scale else args.ranges.objects) or (None,):
            _check_range_corners(args, scene if shape is None else scene.with_object(shape))
        names = CARRY_OBS_NAMES if args.carry_test.on else OBS_NAMES
        if not args.observation.observe_object:
            names = without_object(names)
        if args.observation.observe_shape:
            names = names + SHAPE_OBS_NAMES
        grid = None
        if args.observation.tactile is not None:
            rows, cols = args.observation.tactile
            grid = TaxelGrid(int(rows), int(cols), float(fh[1]), float(fh[2]))
            names = names + tactile_names(grid.rows, grid.cols, args.observation.tactile_history)
        return cls(args, start, substeps, scene, Workspace.of(scene), names, grid)

    def make_task(self) -> Task:
        """A new task (it keeps per-episode state): the start, with the carry test if it is on,
        judged as the grip-force task if that is on."""
        a = self.args
        lift, carry, grip, control = a.lift, a.carry_test, a.grip_force, a.control
        start = self.start_class(a.ranges, success_height=lift.success_height, reach_weight=lift.reach_weight,
                                 max_tilt=lift.max_tilt, reward_type=lift.reward_type,
                                 **({"approach": lift.approach} if lift.start == "reach" else {}))  # fmt: skip
        if not carry.on:
            return start
        test = CarryTest(start, dt=self.scene.sim.dt, workspace=self.workspace, start_time=carry.start_time,
                         duration=carry.duration, frequency=carry.frequency, acceleration=carry.acceleration,
                         slide_limit=carry.slide_limit, arm_speed=control.arm_speed,
                         arm_acceleration=control.arm_acceleration)  # fmt: skip
        if not grip.on:
            return test
        return GripForceTask(test, squeeze_weight=grip.squeeze_weight, squeeze_factor=grip.squeeze_factor,
                             finger_force=control.finger_force, squeeze_reference=grip.squeeze_reference,
                             squeeze_charge_steps=grip.squeeze_charge_steps,
                             squeeze_free=grip.squeeze_free)  # fmt: skip

    def make_actions(self) -> GripperActions:
        c = self.args.control
        return VelocityActions(c.arm_speed, c.frequency, self.workspace, self.scene.finger_travel,
                               finger=c.finger_action, finger_force=self.scene.finger_force)  # fmt: skip


def _scaled(shape: ObjectShape, factor: float, keyword: str, value: float) -> ObjectShape:
    """``shape`` at ``factor`` of its size, or a ValueError naming the range (``keyword=value``) that
    reaches a size the shape cannot have."""
    try:
        return shape.scaled(factor)
    except ValueError as e:
        raise ValueError(f"{keyword}={value!r} reaches a {shape.name} {factor:g} times its size: {e}") from None


def _check_range_corners(args: EnvArguments, base: SceneConfig) -> None:
    """Every corner of the randomisation ranges must be a scene that starts without overlap: the
    largest cylinder with the widest wedge, at each corner of its square, against each extreme of
    lateral offset and yaw (geometry_error on the values; no scene is built); and the scaled
    quantities at their extremes stay in the configs' own ranges."""
    rg = args.ranges
    p, lo, yw, w = rg.cylinder_position, rg.lateral_offset, rg.yaw, rg.jaw_wedge
    r = base.cylinder_radius + rg.cylinder_radius
    for sx, sy, so, syaw, sw in itertools.product((-1.0, 1.0), repeat=5):
        error = geometry_error(base, cylinder_radius=r, cylinder_xy=(sx * p, sy * p), lateral_offset=so * lo,
                               yaw=syaw * yw, jaw_wedge=sw * w)  # fmt: skip
        if error is not None:
            raise ValueError(
                f"the randomisation ranges reach a scene that cannot start (cylinder_position_range={p:g}, "
                f"lateral_offset_range={lo:g}, yaw_range={yw:g}, jaw_wedge_range={w:g}, cylinder_radius_range="
                f"{rg.cylinder_radius:g}, start={args.lift.start!r}): {error}")  # fmt: skip
    # (a 9 kg cylinder with cylinder_mass_range=0.9 used to fail at some reset, at 17 kg)
    for sign in (-1.0, 1.0):
        scale = 1.0 + sign * rg.friction
        try:
            check_range("cylinder_mass", base.cylinder_mass * (1.0 + sign * rg.cylinder_mass), 0.001, 10.0,
                        owner="SceneConfig")  # fmt: skip
            check_range("friction_static", base.tissue.friction_static * scale, 0.0, 10.0, owner="TissueConfig")
            check_range("friction_kinetic", kinetic_friction(base.tissue) * scale, 0.0, 10.0, owner="TissueConfig")
            check_range("ground_friction", base.ground_friction * scale, 0.0, 10.0, owner="SceneConfig")
        except ValueError as e:
            raise ValueError(
                f"the randomisation ranges reach a scene that cannot be built (friction_range={rg.friction:g}, "
                f"cylinder_mass_range={rg.cylinder_mass:g}, cylinder_mass={base.cylinder_mass:g}): {e}") from None  # fmt: skip


# --- the goal env's own keywords and the reset options --------------------------------------------


@dataclass(frozen=True)
class GoalConfig:
    """The goal env's own keywords (``distance_threshold``, ``goal_height_range``,
    ``end_when_knocked_over``; :class:`~softgrasp_env.env.SoftGraspGoalEnv`)."""

    distance_threshold: float = DISTANCE_THRESHOLD
    """[m]"""
    goal_height_range: tuple[float, float] = GOAL_HEIGHT_RANGE
    """[m] above the cylinder's resting height."""
    end_when_knocked_over: bool = False

    def __post_init__(self) -> None:
        check_range("distance_threshold", self.distance_threshold, 0.0, 0.1, lo_open=True)
        g = self.goal_height_range
        if not (isinstance(g, tuple) and len(g) == 2 and all(is_real(v) for v in g) and 0.0 <= g[0] <= g[1] <= 0.15):
            raise ValueError(f"goal_height_range must be (lo, hi) with 0 <= lo <= hi <= 0.15 m, got {g!r}")
        if not isinstance(self.end_when_knocked_over, bool):
            raise TypeError(f"end_when_knocked_over must be True or False, got {self.end_when_knocked_over!r}")

    @classmethod
    def of(cls, *, distance_threshold: float = DISTANCE_THRESHOLD,
           goal_height_range: tuple[float, float] = GOAL_HEIGHT_RANGE, end_when_knocked_over: bool = False) -> GoalConfig:  # fmt: skip
        """The config of the keywords as given (a list for the range, numpy's bool)."""
        g = goal_height_range
        g = tuple(g) if isinstance(g, (list, tuple)) else g
        end = bool(end_when_knocked_over) if isinstance(end_when_knocked_over, (bool, np.bool_)) else end_when_knocked_over
        return cls(distance_threshold, g, end)


RESET_OPTION_RANGES: dict[str, tuple[float, float, bool]] = {
    "friction_scale": (0.0, 10.0, True),
    "carry_frequency": (0.05, 10.0, False),
    "carry_acceleration": (0.0, 50.0, False),
    "carry_direction": (-math.pi, math.pi, False),
}
"""(low, high, low open) of the reset options that have a fixed range; the rest are geometry the
scene checks (and the carry's sway, checked against the arm's limits when it is drawn)."""


def check_reset_options(options: Any, allowed: tuple[str, ...]) -> dict[str, Any]:
    """``reset(options=...)`` as the task's draw takes them: a dict (or None) of the options the
    task allows, each of the right type (:func:`~softgrasp_env.tasks.check_option`) and within its
    range; else a TypeError / ValueError naming the option."""
    if options is not None and not isinstance(options, dict):
        raise TypeError(f"reset options must be a dict (or None), got {type(options).__name__}: {options!r}")
    options = dict(options or {})
    unknown = set(options) - set(allowed)
    if unknown:
        raise ValueError(f"unknown reset option(s) {sorted(unknown)}; allowed: {allowed}")
    out = {k: check_option(k, v) for k, v in options.items()}
    for k, v in out.items():
        if k in RESET_OPTION_RANGES:
            lo, hi, lo_open = RESET_OPTION_RANGES[k]
            if (v <= lo if lo_open else v < lo) or v > hi:
                raise ValueError(f"reset option {k!r} must be in {'(' if lo_open else '['}{lo:g}, {hi:g}], got {v!r}")
    return out


# --- the env card ---------------------------------------------------------------------------------


def argument_table() -> str:
    """The env card's argument table (Gymnasium v5 style), from :data:`KEYWORDS`: every keyword
    once, with its type, default and description, and the config it goes into."""
    rows = ["| Parameter | Type | Default | Description |", "|---|---|---|---|"]
    for k in KEYWORDS:
        default = "π/4" if k.default == math.pi / 4 else f"`{k.default!r}`"
        rows.append(f"| `{k.name}` | {k.type} | {default} | {k.doc} |")
    return "\n".join(rows)


__all__ = ["KEYWORDS", "MAX_ARM_STEP", "CameraConfig", "CarryConfig", "ControlConfig", "CylinderConfig",
           "EnvArguments", "EnvPlan", "GoalConfig", "GripForceConfig", "Keyword", "LiftConfig", "ObservationConfig",
           "PhysicsConfig", "argument_table", "check_reset_options"]
