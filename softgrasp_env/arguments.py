"""``gym.make`` keyword arguments -> the configs an env is made of, in one place with one validator.

:class:`EnvArguments` holds every argument (its fields are the env card's argument table:
:func:`argument_table`), checks each with softgrasp_env/validation.py, and derives what the env
composes: the base :class:`~softgrasp_env.scene.SceneConfig`, the task (``make_task``), the
gripper's actions (``make_actions``), the physics steps per env step. Old spellings keep working
with a DeprecationWarning (:meth:`EnvArguments.from_kwargs`). The corners of the randomisation
ranges are checked here, when the env is made, as pure geometry (no scene is built).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import MISSING, dataclass, field, fields, replace
from typing import Any

from . import presets
from .config import SimConfig, TissueConfig, kinetic_friction
from .fingers import FINGERS, FemConfig, FingerConfig, TissueFingerConfig, finger_config
from .fingers.tactile import MAX_TAXELS, TaxelGrid
from .observation import CARRY_OBS_NAMES, OBS_NAMES, tactile_names, without_object
from .scene import GRIP_TOP, GripperActions, SceneConfig, Workspace, fit_error, geometry_error
from .scene.gripper import FINGER_ACTIONS, VelocityActions
from .tasks import STARTS, CarryTest, GripForceTask, StartRanges, Task
from .tasks.carry import (
    CARRY_ACCELERATION_RANGE,
    CARRY_DURATION,
    CARRY_FREQUENCY_BAND,
    CARRY_SLIDE_LIMIT,
    CARRY_START,
    sway_limits_error,
)
from .tasks.reach import APPROACH
from .validation import check_bool, check_choice, check_int, check_range, check_type, deprecated, retired_choice

MAX_ARM_STEP = 1.0 / 120.0
"""Farthest the arm's target may move in one physics step, arm_speed * dt [m]: 3.3 cm tore
the tissue in 2 of 5 probe episodes, 1.7 cm in 2 of 8 (1/60 s with the strongest fingers,
tests/test_extremes.py); the default moves 0.6 mm."""
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


def _arg(default: Any, doc: str, *, type_: str) -> Any:
    return field(default=default, metadata={"doc": doc, "type": type_})


@dataclass(frozen=True)
class EnvArguments:
    """The env's keyword arguments, validated (each field's metadata has its card entry)."""

    fingers: str | FingerConfig = _arg("tissue", "The finger kind: 'tissue' (oriented-particle tissue on rigid cores, "
        "the thesis), 'rigid' (the bare cores), 'segmented' (sprung rigid segments), 'fem' (pybullet's FEM pads), "
        "'rigid_torsion' (the bare cores with torsional friction of the tissue's contact patch); or a kind's config "
        "(`SegmentedConfig(segments=4)`) for its own settings", type_="str or FingerConfig")
    tissue_faces: str | None = _arg(None, "fingers='tissue': 'contact' (the inner face and tip of each core) or "
        "'all' faces get tissue; None: the kind's default, 'contact'", type_="str")
    fem_resolution: str | None = _arg(None, "fingers='fem': the pads' mesh, 'coarse' or 'fine' (several times "
        "slower); None: 'coarse'", type_="str")
    preset: str = _arg("default", "Tissue and solver settings to start from ('fast', 'default', 'accurate', "
        "softgrasp_env/presets.py); `tissue`, `sim` and the tissue arguments override them", type_="str")
    start: str = _arg("reach", "The start: 'reach' (above and away from the cylinder, misaligned fingers) or "
        "'easy' (v0's gentle start, for debugging)", type_="str")
    reward_type: str = _arg("dense", "'dense' (lift + reach) or 'sparse' (1 while held)", type_="str")
    control_frequency: float = _arg(20.0, "Env steps per second [Hz]; must divide the physics rate 1 / sim.dt",
                                    type_="float")
    arm_speed: float = _arg(0.15, "Arm speed at full action [m/s]: the action's x, y, z are the palm's "
        "velocity, followed along a speed- and acceleration-limited path; at most 2 and at most 1/120 m per physics "
        "step (arm_speed * sim.dt)", type_="float")
    arm_acceleration: float = _arg(1.5, "Largest acceleration of the arm's path [m/s²]; the palm starts and stops "
        "smoothly, the same at every dt", type_="float")
    particle_density: float | None = _arg(None, "Tissue particles per m² of core surface (None: the preset's, "
        "4,000); `tissue_density` before 0.3", type_="float")
    friction_static: float | None = _arg(None, "μ_s of the finger surface (None: the preset's, 0.9; the rigid "
        "kinds' pybullet coefficient)", type_="float")
    friction_kinetic: float | None = _arg(None, "μ_k of the tissue, at most μ_s (None: the preset's: equal to μ_s, "
        "one coefficient as pybullet's rigid contacts have)", type_="float")
    tissue_contact_cone: bool | None = _arg(None, "Coulomb's cone on every tissue contact as well as on each pad's "
        "patch (True) or on the patch alone (False: a pad squeezed on the way down can hold the cylinder after the "
        "squeeze is gone; TissueConfig.contact_cone says why the cones are not the default yet); None: the "
        "preset's, False", type_="bool")
    shear_modulus: float | None = _arg(None, "The compliant tissue's shear modulus [Pa] (None: the preset's, 4,000: "
        "the pad compresses ~4.4 mm under 3 N)", type_="float")
    tissue: TissueConfig | None = _arg(None, "A whole TissueConfig to start from (None: the preset's)",
                                       type_="TissueConfig")
    sim: SimConfig | None = _arg(None, "A whole SimConfig (dt, iterations, coupling; None: the preset's)",
                                 type_="SimConfig")
    cylinder_radius: float = _arg(0.03, "Cylinder radius [m]", type_="float")
    cylinder_height: float = _arg(0.10, "Cylinder height [m]", type_="float")
    cylinder_mass: float = _arg(0.1, "Cylinder mass [kg]", type_="float")
    finger_force: float = _arg(3.0, "Force limit of each finger's motor [N]", type_="float")
    success_height: float = _arg(0.05, "Lift that counts as picked up [m]", type_="float")
    reach_weight: float = _arg(0.1, "Weight of the reach shaping term", type_="float")
    max_tilt: float = _arg(math.pi / 4, "Tilt of the cylinder that ends the episode (knocked over) [rad]",
                           type_="float")
    carry: bool | None = _arg(None, "The carry test (None: on for start 'reach', off for 'easy')", type_="bool")
    carry_start: float = _arg(CARRY_START, "When the carry begins after reset [s]", type_="float")
    carry_duration: float = _arg(CARRY_DURATION, "How long the arm carries [s]", type_="float")
    carry_frequency: float | tuple[float, float] = _arg(CARRY_FREQUENCY_BAND, "The sway's frequency [Hz], or a "
        "(low, high) band drawn per episode (1.2-3.0, around the two-point grasp's ~1.9 Hz pendulum)",
        type_="float or (float, float)")
    carry_acceleration: float | tuple[float, float] = _arg(CARRY_ACCELERATION_RANGE, "The sway's peak "
        "acceleration [m/s²], or a (low, high) range drawn per episode; the amplitude is a / (2 pi f)² (0.5-1.0); "
        "the direction is any horizontal one, drawn per episode (reset option carry_direction fixes it)",
        type_="float or (float, float)")
    carry_slide_limit: float = _arg(CARRY_SLIDE_LIMIT, "Success needs the cylinder held at every step of the carry "
        "and its in-hand slide at most this [m]", type_="float")
    cylinder_position_range: float | None = _arg(None, "Cylinder at U(±range) in x and y [m] (None: the start's, "
        "0.07 reach / 0.01 easy)", type_="float")
    lateral_offset_range: float = _arg(0.005, "Palm offset along the faces, U(±range) [m]", type_="float")
    yaw_range: float | None = _arg(None, "Palm yaw U(±range) [rad] (None: π/4 reach / 5° easy)", type_="float")
    jaw_wedge_range: float | None = _arg(None, "Wedge between the faces U(±range) [rad] (None: 0.15 reach / 0 "
        "easy)", type_="float")
    approach_range: tuple[float, float] = _arg(APPROACH, "start='reach': the annulus the grip starts in, around the "
        "origin [m]", type_="(float, float)")
    friction_range: float = _arg(0.0, "Every friction coefficient × U(1 ± range)", type_="float")
    cylinder_radius_range: float = _arg(0.0, "Cylinder radius ± U(range) [m]", type_="float")
    cylinder_mass_range: float = _arg(0.0, "Cylinder mass × U(1 ± range)", type_="float")
    finger_action: str = _arg("position", "What the action's last entry commands: 'position', the fingers' "
        "closing travel (-1 fully open, +1 the faces meeting) with the motors squeezing at most finger_force; 'force', "
        "the squeeze itself, 0 N at -1 to finger_force at +1, the fingers closing until they meet resistance (they "
        "never open: for a start with the cylinder between them)", type_="str")
    squeeze_weight: float = _arg(0.0, "The grip-force task (SoftGraspGrip-v3: 0.5): the reward charges "
        "squeeze_weight * mean finger force / finger_force per step (info['reward_terms']['squeeze']); needs "
        "carry=True", type_="float")
    squeeze_factor: float | None = _arg(None, "The grip-force task (SoftGraspGrip-v3: 2): success also needs the "
        "carry's mean squeeze at most this many times the least force that holds the cylinder through it (Coulomb, "
        "with its measured accelerations; info['carry_squeeze'], info['least_squeeze']); needs carry=True. None: off",
        type_="float")
    tactile: tuple[int, int] | None = _arg(None, "(rows, cols): the observation ends with each pad's taxels on a "
        "rows x cols grid over the core's inner face, five per taxel: pressure and traction along y, z [Pa] and the "
        "tissue's shear along y, z [m] (0 for rigid pads); `softgrasp_env.observation.tactile_view` reshapes them. "
        "None: no tactile entries", type_="(int, int)")
    observe_object: bool = _arg(True, "False: the observation leaves out the cylinder's pose and motion "
        "(cyl_rel, cyl_axis, cyl_v, cyl_w, lift), keeping what the gripper's own sensors give - its pose and "
        "velocity, the fingers' gap and forces, the clock, the taxels (the grip ids: an exact in-hand pose would "
        "show a slip without touch)", type_="bool")
    render_width: int = _arg(480, "Width of an rgb_array frame [px]", type_="int")
    render_height: int = _arg(360, "Height of an rgb_array frame [px]", type_="int")
    render_camera: str = _arg("follow", "'follow' (frame the gripper and the cylinder wherever they are) or "
        "'fixed' (look at the cylinder's start, so a video shows the lift as motion)", type_="str")
    camera_distance: float | None = _arg(None, "Camera distance from its target [m] (None: follow fits the "
        "bodies in the frame, fixed 0.55)", type_="float")
    camera_yaw: float = _arg(35.0, "Camera yaw about the vertical [deg]", type_="float")
    camera_pitch: float = _arg(-25.0, "Camera pitch [deg], negative looking down", type_="float")
    camera_target: tuple[float, float, float] | None = _arg(None, "The point the camera looks at [m] (None: "
        "follow aims at the bodies, fixed at the cylinder's start 12 cm up)", type_="(float, float, float)")

    # --- derived in __post_init__ ------------------------------------------------------------------
    start_class: type = field(init=False, repr=False, compare=False)
    """The start's class (STARTS[start])."""
    substeps: int = field(init=False, repr=False, compare=False)
    """Physics steps per env step."""
    scene: SceneConfig = field(init=False, repr=False, compare=False)
    """The base scene every episode's draw starts from."""
    ranges: StartRanges = field(init=False, repr=False, compare=False)
    workspace: Workspace = field(init=False, repr=False, compare=False)
    obs_names: tuple[str, ...] = field(init=False, repr=False, compare=False)
    """The observation's entries, in order."""
    taxel_grid: TaxelGrid | None = field(init=False, repr=False, compare=False)
    """The pads' taxel grid of ``tactile`` (None without)."""

    def __post_init__(self) -> None:
        check_choice("start", self.start, tuple(STARTS))
        self._set("start_class", STARTS[self.start])
        defaults = self.start_class.defaults
        for name in ("cylinder_position", "yaw", "jaw_wedge"):
            if getattr(self, f"{name}_range") is None:
                object.__setattr__(self, f"{name}_range", defaults[name])
        if self.carry is None:
            object.__setattr__(self, "carry", defaults["carry"])
        check_bool("carry", self.carry, hint=" (or None: the start's default)")
        try:
            a_lo, a_hi = (float(v) for v in self.approach_range)
        except (TypeError, ValueError):
            raise ValueError(f"approach_range must be (min, max) distances in m, got {self.approach_range!r}") from None
        if not (math.isfinite(a_lo) and math.isfinite(a_hi) and 0.0 <= a_lo <= a_hi <= 0.14):
            raise ValueError("approach_range must be 0 <= min <= max <= 0.14 m (the grip's workspace is +-0.15 m), "
                             f"got {self.approach_range!r}")  # fmt: skip
        object.__setattr__(self, "approach_range", (a_lo, a_hi))
        fingers = finger_config(self.fingers)
        if self.tissue_faces is not None:
            if not isinstance(fingers, TissueFingerConfig):
                raise ValueError(f"tissue_faces is a setting of fingers='tissue', but fingers={fingers.kind!r}")
            fingers = replace(fingers, faces=self.tissue_faces)
        if self.fem_resolution is not None:
            if not isinstance(fingers, FemConfig):
                raise ValueError(f"fem_resolution is a setting of fingers='fem', but fingers={fingers.kind!r}")
            fingers = replace(fingers, resolution=self.fem_resolution)
        object.__setattr__(self, "fingers", fingers)
        check_choice("reward_type", self.reward_type, ("dense", "sparse"))
        check_range("control_frequency", self.control_frequency, 0.5, 240.0)
        check_choice("finger_action", self.finger_action, FINGER_ACTIONS)
        check_range("arm_speed", self.arm_speed, 0.0, 2.0, lo_open=True)
        check_range("arm_acceleration", self.arm_acceleration, 0.0, 50.0, lo_open=True)
        check_range("success_height", self.success_height, 0.0, 0.15, lo_open=True)
        check_range("reach_weight", self.reach_weight, 0.0, 10.0)
        check_range("max_tilt", self.max_tilt, 0.0, math.pi, lo_open=True)
        check_range("carry_start", self.carry_start, 0.0, 600.0)
        check_range("carry_duration", self.carry_duration, 0.0, 600.0, lo_open=True)
        self._check_carry()
        check_range("cylinder_position_range", self.cylinder_position_range, 0.0, 0.08)
        check_range("lateral_offset_range", self.lateral_offset_range, 0.0, 0.05)
        check_range("yaw_range", self.yaw_range, 0.0, math.pi / 4)
        check_range("jaw_wedge_range", self.jaw_wedge_range, 0.0, math.pi / 6)
        check_range("friction_range", self.friction_range, 0.0, 0.9)
        check_range("cylinder_radius_range", self.cylinder_radius_range, 0.0, 0.02)
        check_range("cylinder_mass_range", self.cylinder_mass_range, 0.0, 0.9)
        check_range("squeeze_weight", self.squeeze_weight, 0.0, 10.0)
        if self.squeeze_factor is not None:
            check_range("squeeze_factor", self.squeeze_factor, 1.0, 100.0)
        if (self.squeeze_weight > 0.0 or self.squeeze_factor is not None) and not self.carry:
            raise ValueError(f"squeeze_weight={self.squeeze_weight!r} / squeeze_factor={self.squeeze_factor!r} set "
                             "the grip-force task, which judges the squeeze over the carry: give carry=True")  # fmt: skip
        check_int("render_width", self.render_width, 16, 4096)
        check_int("render_height", self.render_height, 16, 4096)
        self._check_camera()
        self._derive_physics()
        self._derive_scene()
        self._check_range_corners()

    def _check_camera(self) -> None:
        check_choice("render_camera", self.render_camera, ("follow", "fixed"))
        if self.camera_distance is not None:
            check_range("camera_distance", self.camera_distance, 0.05, 3.0)
        check_range("camera_yaw", self.camera_yaw, -360.0, 360.0)
        check_range("camera_pitch", self.camera_pitch, -89.0, 89.0)
        if self.camera_target is not None:
            try:
                target = tuple(float(v) for v in self.camera_target)
            except (TypeError, ValueError):
                raise ValueError(f"camera_target must be (x, y, z) in m or None, got {self.camera_target!r}") from None
            if len(target) != 3 or not all(math.isfinite(v) and abs(v) <= 1.0 for v in target):
                raise ValueError(f"camera_target must be (x, y, z) with each within 1 m of the origin, "
                                 f"got {self.camera_target!r}")  # fmt: skip
            object.__setattr__(self, "camera_target", target)

    def _set(self, name: str, value: Any) -> None:
        object.__setattr__(self, name, value)

    def _derive_physics(self) -> None:
        check_choice("preset", self.preset, tuple(presets.PRESETS))
        p_cfg = presets.scene_config(self.preset)
        tissue = self.tissue if self.tissue is not None else p_cfg.tissue
        check_type("tissue", tissue, TissueConfig)
        if self.tissue is not None and None not in (tissue.friction_kinetic, self.friction_kinetic) \
                and tissue.friction_kinetic != self.friction_kinetic:  # fmt: skip
            raise ValueError(f"friction_kinetic={self.friction_kinetic!r} and "
                             f"tissue.friction_kinetic={tissue.friction_kinetic!r} disagree: give one of them")
        overrides = {k: v for k, v in (("particle_density", self.particle_density),
                                       ("friction_static", self.friction_static),
                                       ("friction_kinetic", self.friction_kinetic),
                                       ("contact_cone", self.tissue_contact_cone),
                                       ("shear_modulus", self.shear_modulus)) if v is not None}  # fmt: skip
        self._set("tissue", replace(tissue, **overrides))  # validated by TissueConfig
        sim = self.sim if self.sim is not None else p_cfg.sim
        check_type("sim", sim, SimConfig)
        self._set("sim", sim)
        ratio = 1.0 / (sim.dt * self.control_frequency)
        substeps = int(round(ratio))
        if abs(ratio - substeps) > 1e-9 * ratio or substeps < 1:
            raise ValueError(f"control_frequency must divide the physics rate 1/sim.dt = {1.0 / sim.dt:g} Hz, "
                             f"got {self.control_frequency!r}")  # fmt: skip
        self._set("substeps", substeps)
        if self.arm_speed * sim.dt > MAX_ARM_STEP + 1e-12:
            raise ValueError(f"arm_speed={self.arm_speed:g} m/s with sim.dt={sim.dt:g} s moves the arm "
                             f"{self.arm_speed * sim.dt * 100:.2f} cm per physics step, more than "
                             f"{MAX_ARM_STEP * 100:.2f} cm; at this dt arm_speed must be at most "
                             f"{MAX_ARM_STEP / sim.dt:.3g} m/s")  # fmt: skip
        # (The carry's sway keeps within arm_speed, _check_carry, so within MAX_ARM_STEP per step too.)

    def _check_carry(self) -> None:
        """The carry's settings, each on its own, then the sway's corners against the arm's limits."""
        for name in ("carry_frequency", "carry_acceleration"):
            value = getattr(self, name)
            if isinstance(value, list):
                value = tuple(value)
                object.__setattr__(self, name, value)
            if isinstance(value, tuple):
                if len(value) != 2:
                    raise ValueError(f"{name} must be a number or (low, high), got {value!r}")
                for k, v in enumerate(value):
                    check_range(f"{name}[{k}]", v, 0.0, 10.0 if name == "carry_frequency" else 50.0,
                                lo_open=name == "carry_frequency")  # fmt: skip
                if value[0] > value[1]:
                    raise ValueError(f"{name} must be (low, high) with low <= high, got {value!r}")
                object.__setattr__(self, name, tuple(float(v) for v in value))
            else:
                check_range(name, value, 0.0, 10.0 if name == "carry_frequency" else 50.0,
                            lo_open=name == "carry_frequency")  # fmt: skip
        check_range("carry_slide_limit", self.carry_slide_limit, 0.0, 0.1, lo_open=True)
        if self.carry:
            for f, amplitude in self._carry_corners():
                problem = sway_limits_error(f, amplitude=amplitude, speed=self.arm_speed,
                                            arm_acceleration=self.arm_acceleration)  # fmt: skip
                if problem:
                    raise ValueError(f"the carry's sway at {f:g} Hz ({amplitude * 100:.3g} cm) {problem}: lower "
                                     "carry_acceleration or carry_frequency")  # fmt: skip

    def _carry_corners(self) -> list[tuple[float, float]]:
        """(frequency, amplitude) at the corners of the sway's ranges: its peak speed and
        acceleration are largest at one of them."""
        fs = self.carry_frequency if isinstance(self.carry_frequency, tuple) else (self.carry_frequency,)
        accels = self.carry_acceleration if isinstance(self.carry_acceleration, tuple) else (self.carry_acceleration,)
        return [(f, a / (2.0 * math.pi * f) ** 2) for f in fs for a in accels]

    def _derive_scene(self) -> None:
        """The base scene: the start height is the task's, decided once; the pad must fit the
        open fingers before the start is judged, so a pad too thick is named as such."""
        check_range("cylinder_height", self.cylinder_height, 0.01, 0.5)
        check_range("cylinder_radius", self.cylinder_radius, 0.005, 0.2)
        field_defaults = SceneConfig.__dataclass_fields__
        fh = field_defaults["finger_half_extents"].default
        stroke = field_defaults["finger_stroke"].default
        kind = FINGERS[self.fingers.kind]
        pad = kind.pad_thickness(self.fingers, self.tissue)
        error = fit_error(cylinder_radius=self.cylinder_radius, jaw_wedge=0.0, finger_stroke=stroke,
                          pad=pad, finger_half_height=fh[2], kind=self.fingers.kind)  # fmt: skip
        if error is not None:
            raise ValueError(error)
        start_height = self.start_class.start_height(self.cylinder_height, fh[2], pad)
        top = GRIP_TOP - GRIP_TOP_MARGIN
        grip_z = 0.5 * self.cylinder_height + start_height
        if grip_z > top:
            raise ValueError(f"cylinder_height={self.cylinder_height:g} m is too tall for start={self.start!r}: the grip "
                             f"would start {grip_z:.3f} m up, too near the top of the arm's workspace ({GRIP_TOP:g} "
                             f"m); at most {self.start_class.tallest_cylinder(top, fh[2], pad):.3f} m")  # fmt: skip
        base = SceneConfig(fingers=self.fingers, cylinder_radius=self.cylinder_radius,
                           cylinder_height=self.cylinder_height, cylinder_mass=self.cylinder_mass,
                           finger_force=self.finger_force, tissue=self.tissue, sim=self.sim,
                           start_height=start_height, arm_speed=self.arm_speed,
                           arm_acceleration=self.arm_acceleration)  # fmt: skip
        self._set("scene", base)
        if self.cylinder_radius - self.cylinder_radius_range < MIN_CYLINDER_RADIUS:
            raise ValueError(f"cylinder_radius - cylinder_radius_range must be >= {MIN_CYLINDER_RADIUS} m, got "
                             f"{self.cylinder_radius} - {self.cylinder_radius_range}")  # fmt: skip
        self._set("ranges", StartRanges(
            cylinder_position=float(self.cylinder_position_range), lateral_offset=float(self.lateral_offset_range),
            yaw=float(self.yaw_range), jaw_wedge=float(self.jaw_wedge_range), friction=float(self.friction_range),
            cylinder_radius=float(self.cylinder_radius_range), cylinder_mass=float(self.cylinder_mass_range)))  # fmt: skip
        self._set("workspace", Workspace.of(base))
        names = CARRY_OBS_NAMES if self.carry else OBS_NAMES
        check_bool("observe_object", self.observe_object)
        if not self.observe_object:
            names = without_object(names)
        grid = None
        if self.tactile is not None:
            try:
                rows, cols = self.tactile
            except (TypeError, ValueError):
                raise ValueError(f"tactile must be (rows, cols) or None, got {self.tactile!r}") from None
            reason = FINGERS[self.fingers.kind].no_tactile
            if reason is not None:
                raise ValueError(f"tactile={self.tactile!r} with fingers={self.fingers.kind!r}: {reason}")
            grid = TaxelGrid(check_int("tactile[0] (rows)", rows, 1, MAX_TAXELS),
                             check_int("tactile[1] (cols)", cols, 1, MAX_TAXELS), float(fh[1]), float(fh[2]))  # fmt: skip
            object.__setattr__(self, "tactile", (grid.rows, grid.cols))
            names = names + tactile_names(grid.rows, grid.cols)
        self._set("taxel_grid", grid)
        self._set("obs_names", names)

    def _check_range_corners(self) -> None:
        """Every corner of the randomisation ranges must be a scene that starts without overlap:
        the largest cylinder with the widest wedge, at each corner of its square, against each
        extreme of lateral offset and yaw (geometry_error on the values; no scene is built); and
        the scaled quantities at their extremes stay in the configs' own ranges."""
        rg, b = self.ranges, self.scene
        p, lo, yw, w = rg.cylinder_position, rg.lateral_offset, rg.yaw, rg.jaw_wedge
        r = b.cylinder_radius + rg.cylinder_radius
        for sx, sy, so, syaw, sw in itertools.product((-1.0, 1.0), repeat=5):
            error = geometry_error(b, cylinder_radius=r, cylinder_xy=(sx * p, sy * p), lateral_offset=so * lo,
                                   yaw=syaw * yw, jaw_wedge=sw * w)  # fmt: skip
            if error is not None:
                raise ValueError(
                    f"the randomisation ranges reach a scene that cannot start (cylinder_position_range={p:g}, "
                    f"lateral_offset_range={lo:g}, yaw_range={yw:g}, jaw_wedge_range={w:g}, cylinder_radius_range="
                    f"{rg.cylinder_radius:g}, start={self.start!r}): {error}")  # fmt: skip
        # (a 9 kg cylinder with cylinder_mass_range=0.9 used to fail at some reset, at 17 kg)
        for sign in (-1.0, 1.0):
            scale = 1.0 + sign * rg.friction
            try:
                check_range("cylinder_mass", b.cylinder_mass * (1.0 + sign * rg.cylinder_mass), 0.001, 10.0,
                            owner="SceneConfig")  # fmt: skip
                check_range("friction_static", b.tissue.friction_static * scale, 0.0, 10.0, owner="TissueConfig")
                check_range("friction_kinetic", kinetic_friction(b.tissue) * scale, 0.0, 10.0, owner="TissueConfig")
                check_range("ground_friction", b.ground_friction * scale, 0.0, 10.0, owner="SceneConfig")
            except ValueError as e:
                raise ValueError(
                    f"the randomisation ranges reach a scene that cannot be built (friction_range={rg.friction:g}, "
                    f"cylinder_mass_range={rg.cylinder_mass:g}, cylinder_mass={b.cylinder_mass:g}): {e}") from None  # fmt: skip

    # --- what the env composes -------------------------------------------------------------------

    def make_task(self) -> Task:
        """A new task (it keeps per-episode state): the start, with the carry test if it is on."""
        start = self.start_class(self.ranges, success_height=self.success_height, reach_weight=self.reach_weight,
                           max_tilt=self.max_tilt, reward_type=self.reward_type,
                           **({"approach": self.approach_range} if self.start == "reach" else {}))  # fmt: skip
        if not self.carry:
            return start
        carry = CarryTest(start, dt=self.sim.dt, workspace=self.workspace, start=self.carry_start,
                          duration=self.carry_duration, frequency=self.carry_frequency,
                          acceleration=self.carry_acceleration, slide_limit=self.carry_slide_limit,
                          arm_speed=self.arm_speed, arm_acceleration=self.arm_acceleration)  # fmt: skip
        if self.squeeze_weight == 0.0 and self.squeeze_factor is None:
            return carry
        return GripForceTask(carry, squeeze_weight=self.squeeze_weight, squeeze_factor=self.squeeze_factor,
                            finger_force=self.finger_force)  # fmt: skip

    def make_actions(self) -> GripperActions:
        return VelocityActions(self.arm_speed, self.control_frequency, self.workspace, self.scene.finger_travel,
                               finger=self.finger_action, finger_force=self.scene.finger_force)  # fmt: skip

    # --- construction from gym.make's kwargs -----------------------------------------------------

    @classmethod
    def from_kwargs(cls, **kwargs: Any) -> EnvArguments:
        """The arguments from ``gym.make``'s keywords: unknown names are a TypeError listing the
        known ones; the spellings of 0.2 (``soft=``, ``tissue_density=``) keep working with a
        DeprecationWarning, and so do the choices that are the only ones left since 0.7
        (``arm="smooth"``, ``tissue_material="compliant"``, ``carry_direction="any"``); the retired
        ones (``arm="jump"``, ``tissue_material="per_step"``, ``carry_direction="across"``,
        ``carry_amplitude``, ``carry_slide_limit=None``) are a ValueError naming 0.6.0, the last
        release that has them."""
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
        known = {f.name for f in fields(cls) if f.init}
        unknown = sorted(set(kwargs) - known)
        if unknown:
            raise TypeError(f"unknown argument(s) {unknown}; the env takes {sorted(known)}")
        return cls(**kwargs)


def argument_table() -> str:
    """The env card's argument table (Gymnasium v5 style), from :class:`EnvArguments`'s fields."""
    rows = ["| Parameter | Type | Default | Description |", "|---|---|---|---|"]
    for f in fields(EnvArguments):
        if not f.init:
            continue
        default = f"`{f.default!r}`" if f.default is not MISSING else "-"
        if f.default == math.pi / 4:
            default = "π/4"
        rows.append(f"| `{f.name}` | {f.metadata['type']} | {default} | {f.metadata['doc']} |")
    return "\n".join(rows)


__all__ = ["MAX_ARM_STEP", "EnvArguments", "argument_table"]
