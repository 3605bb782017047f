"""The grasp scene's settings (thesis 5.2.1): ground, a two-finger gripper with a finger kind, a
cylinder, the start's misalignment, the tissue material and the time stepping.

``SceneConfig`` validates itself field by field (softgrasp_env/validation.py), then asks its finger
kind for the combinations that kind cannot run (softgrasp_env/fingers/), then checks the geometry
as a whole (:func:`geometry_error`): a cylinder that does not fit the open fingers, fingers or palm
that start inside it. Each is a ValueError naming the settings and the limit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

from ..config import SimConfig, TissueConfig
from ..fingers import FINGERS, FemConfig, FingerConfig, SegmentedConfig, TissueFingerConfig, finger_config
from ..validation import accept_old_names, check_choice, check_range, check_type, deprecated, retired_choice
from .objects import PRESETS, ObjectGeometry, ObjectShape, object_geometry, object_shape

PALM_HALF_EXTENTS = (0.09, 0.03, 0.01)
"""Half extents of the gripper's palm box [m]."""
FINGER_DROP = 0.04
"""Gap between the palm's underside and the top of a finger core [m] (the finger's upper part is
not modelled: only the fingertip segment touches anything)."""
GEOMETRY_MARGIN = 0.001
"""Clearance the start geometry must leave between the cylinder and the open fingers or palm [m]."""
GROUND_CLEARANCE = 0.003
"""The fingertips come down to this far above the ground at most, pads included [m]."""


ARM_PUSH = 40.0
"""What the arm pushes or pulls with beyond carrying the gripper's weight [N]."""


@dataclass(frozen=True)
class SceneConfig:
    """The grasp scene: ground, a two-finger gripper and a cylinder (thesis 5.2.1)."""

    fingers: FingerConfig = field(default_factory=TissueFingerConfig)
    """The finger kind and its own settings: a kind's name ('tissue', 'rigid', 'segmented', 'fem';
    softgrasp_env.fingers.FINGERS) for its defaults, or its config (``SegmentedConfig(segments=4)``).
    Held as the config, which compares equal to the kind's name (``cfg.fingers == "rigid"``).
    'tissue' - each core a combined body, wrapped in oriented-particle tissue (the thesis);
    'rigid' - the bare cores, through pybullet's own contacts (the rigid-only twin); 'segmented' -
    sprung rigid segments on each core's face (the thesis' "traditional" fix); 'fem' - a fully
    deformable pad on each core's inner face and tip, pybullet's FEM soft bodies."""
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
    finger_stroke: float = 0.06
    """Each finger core's stroke [m]: its prismatic joint's range, from fully open (the core's
    inner face this far from the gripper centre) to the bare faces meeting at the centre. The
    action commands the part of it up to the stop, :attr:`finger_travel` (``finger_max_opening``
    before 0.7)."""
    palm_mass: float = 0.5
    """Mass of the gripper palm [kg]."""
    arm_force: float | None = None
    """Force limit of the constraint that drives the palm, the arm's strength [N] (``palm_force``
    before 0.7; :func:`arm_force_limit` gives the value in force); None: the
    gripper's weight (palm and cores) plus :data:`ARM_PUSH` (40 N), as an arm that compensates
    gravity and pushes or pulls with at most 40 N more. 40 N carries the heaviest cylinder the grasp holds (0.5 kg at the lift's 1.5 m/s^2:
    6 N) with room to spare; 200 N pressed the tissue onto the cylinder's rim hard enough to tear
    it, 4 times in 10^5 noisy scripted steps (benchmarks/random_soak.py), once at 40 N."""
    finger_stop: str | None = None
    """Where the fingers' closing travel ends: ``"pads"`` when the two pads' surfaces meet (each core
    face stops a pad thickness from the centre), ``"faces"`` when the bare cores' inner faces meet
    (the pads, if any, crushed to nothing between them); None: "pads". Fingers closing on nothing crushed the tissue between the cores and
    tore it (tests/test_extremes.py's fuzz); a real gripper's jaws stop on their pads."""
    arm_speed: float = 0.15
    """Fastest the arm moves the palm [m/s]: its setpoint (the palm constraint's pivot) follows the
    commanded target or velocity along a path (softgrasp_env/scene/gripper.py, PalmPath) at no
    more than this speed."""
    arm_acceleration: float = 1.5
    """Largest acceleration of the arm's setpoint [m/s^2]: the palm starts, stops and turns
    smoothly, the same at every dt (a target that jumped once per control step, closed ~20 % per
    physics step by the constraint, kicked the palm at 86 m/s^2 at 1/240 s and 500 at 1/1000)."""
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
    """The finger surface's material: friction for every kind (a rigid finger's pybullet
    coefficient is ``friction_static``), pad depth and mass density for the tissue and the FEM
    pads, the particles' discretisation for the tissue."""
    sim: SimConfig = field(default_factory=SimConfig)
    object: ObjectShape | str | None = None
    """What is grasped, if not the cylinder of ``cylinder_radius`` and ``cylinder_height``: a named
    object ('sphere', 'cube', 'rod', ...: softgrasp_env.scene.objects.PRESETS) or an
    :class:`~softgrasp_env.scene.objects.ObjectShape`. It has the mass ``cylinder_mass`` and the
    friction ``cylinder_friction``. A cylinder given here becomes ``cylinder_radius`` and
    ``cylinder_height`` (and ``object`` None), so a scene has one description of its cylinder."""
    object_name: str = field(default="", compare=False)
    """What the object is called ('rod', 'cube', 'pebble-1', ...): its
    :attr:`~softgrasp_env.scene.objects.ObjectShape.name` when ``object`` is given (a preset's
    name, kept when a cylinder folds into ``cylinder_radius``), else the name given, or
    'cylinder'. A label, no part of the scene: configs that differ only in it are equal."""

    @property
    def object_shape(self) -> ObjectShape:
        """The grasped object's shape: :attr:`object`, or the cylinder."""
        if self.object is not None:
            return self.object  # type: ignore[return-value]
        return ObjectShape("cylinder", (self.cylinder_radius, self.cylinder_height))

    def with_object(self, shape: ObjectShape) -> SceneConfig:
        """This scene grasping ``shape`` instead: the cylinder's own fields back at their defaults,
        the object describing it (a cylinder ``shape`` folds into them again)."""
        fields = SceneConfig.__dataclass_fields__
        return replace(self, object=shape, cylinder_radius=fields["cylinder_radius"].default,
                       cylinder_height=fields["cylinder_height"].default)  # fmt: skip

    @property
    def object_geometry(self) -> ObjectGeometry | None:
        """The object's :class:`~softgrasp_env.scene.objects.ObjectGeometry` (shape, mass properties,
        the tissue's collision kind), None for the cylinder."""
        return None if self.object is None else object_geometry(self.object)

    def preset_scale(self) -> tuple[str, float] | None:
        """(name, factor) when the object is a named object (softgrasp_env.scene.objects.PRESETS):
        one of them itself (factor 1.0, whatever :attr:`object_name` says), or :attr:`object_name`'s
        preset at ``factor`` times its size, every dimension alike; else None."""
        shape = self.object_shape
        for name, preset in PRESETS.items():  # a preset by value, whatever it is called
            if preset == shape:
                return name, 1.0
        preset = PRESETS.get(self.object_name)
        if preset is None or (preset.kind, preset.mesh) != (shape.kind, shape.mesh):
            return None
        ratios = [a / b for a, b in zip(shape.size, preset.size, strict=True)]
        if max(ratios) - min(ratios) > 1e-9 * max(ratios):
            return None
        return self.object_name, ratios[0]

    @property
    def finger_travel(self) -> float:
        """Each finger's closing travel from fully open to its stop [m]: the :attr:`finger_stroke`,
        less the pad's thickness when the stop is where the pads meet (``finger_stop``)."""
        stop = self.finger_stop or "pads"
        return self.finger_stroke - (self.pad_thickness if stop == "pads" else 0.0)

    def __post_init__(self) -> None:
        o = "SceneConfig"
        object.__setattr__(self, "fingers", finger_config(self.fingers, owner=o))
        if self.object is not None:
            shape = object_shape(self.object)
            object.__setattr__(self, "object_name", shape.name)
            if shape.kind == "cylinder":
                default = SceneConfig.__dataclass_fields__
                for name in ("cylinder_radius", "cylinder_height"):
                    if getattr(self, name) != default[name].default:
                        raise ValueError(f"SceneConfig: object={self.object!r} and {name}={getattr(self, name)!r} both "
                                         "describe the cylinder; give one")  # fmt: skip
                object.__setattr__(self, "cylinder_radius", shape.size[0])
                object.__setattr__(self, "cylinder_height", shape.size[1])
                shape = None
            else:
                default = SceneConfig.__dataclass_fields__
                for name in ("cylinder_radius", "cylinder_height"):
                    if getattr(self, name) != default[name].default:
                        raise ValueError(f"SceneConfig: {name}={getattr(self, name)!r} is the cylinder's, but the "
                                         f"object is a {shape.kind} ({shape.name}); give its size in the object")  # fmt: skip
            object.__setattr__(self, "object", shape)
        elif not self.object_name:
            object.__setattr__(self, "object_name", "cylinder")
        check_type("object_name", self.object_name, str, owner=o)
        check_range("cylinder_radius", self.cylinder_radius, 0.005, 0.2, owner=o)
        check_range("cylinder_height", self.cylinder_height, 0.01, 0.5, owner=o)
        check_range("cylinder_mass", self.cylinder_mass, 0.001, 10.0, owner=o)
        check_range("cylinder_friction", self.cylinder_friction, 0.0, 10.0, owner=o)
        if len(self.finger_half_extents) != 3:
            raise ValueError(f"SceneConfig.finger_half_extents must have 3 entries, got {self.finger_half_extents!r}")
        for i, h in enumerate(self.finger_half_extents):
            check_range(f"finger_half_extents[{i}]", h, 0.001, 0.2, owner=o)
        check_range("finger_mass", self.finger_mass, 0.001, 10.0, owner=o)
        check_range("finger_force", self.finger_force, 0.0, 1000.0, lo_open=True, owner=o)
        check_range("finger_speed", self.finger_speed, 0.0, 10.0, lo_open=True, owner=o)
        check_range("finger_stroke", self.finger_stroke, 0.005, 0.3, owner=o)
        check_range("palm_mass", self.palm_mass, 0.01, 100.0, owner=o)
        if self.arm_force is not None:
            check_range("arm_force", self.arm_force, 0.0, 1e4, lo_open=True, owner=o)
        if self.finger_stop is not None:
            check_choice("finger_stop", self.finger_stop, ("pads", "faces"), owner=o)
        check_range("arm_speed", self.arm_speed, 0.0, 2.0, lo_open=True, owner=o)
        check_range("arm_acceleration", self.arm_acceleration, 0.0, 50.0, lo_open=True, owner=o)
        check_range("ground_friction", self.ground_friction, 0.0, 10.0, owner=o)
        check_range("lateral_offset", self.lateral_offset, -0.1, 0.1, owner=o)
        check_range("yaw", self.yaw, -math.pi / 4, math.pi / 4, owner=o)
        check_range("jaw_wedge", self.jaw_wedge, -math.pi / 6, math.pi / 6, owner=o)
        for name, lim in (("cylinder_xy", 0.1), ("gripper_xy", 0.15)):
            xy = getattr(self, name)
            if len(xy) != 2:
                raise ValueError(f"SceneConfig.{name} must have 2 entries, got {xy!r}")
            for i, v in enumerate(xy):
                check_range(f"{name}[{i}]", v, -lim, lim, owner=o)
        check_range("start_height", self.start_height, 0.0, 0.3, owner=o)
        check_type("tissue", self.tissue, TissueConfig, owner=o)
        check_type("sim", self.sim, SimConfig, owner=o)
        self.kind.check(self)
        error = geometry_error(self)
        if error is not None:
            raise ValueError(error)

    @property
    def kind(self):
        """The finger kind's class (softgrasp_env.fingers.FINGERS[name])."""
        return FINGERS[self.fingers.kind]

    @property
    def soft(self) -> bool:
        """True if the fingers are wrapped in tissue (``fingers == 'tissue'``)."""
        return self.kind.has_tissue

    @property
    def pad_thickness(self) -> float:
        """How far a finger's pad reaches out from its core's inner face and tip [m]."""
        return self.kind.pad_thickness(self.fingers, self.tissue)


def arm_force_limit(cfg: SceneConfig) -> float:
    """The palm constraint's force limit in force [N]: ``cfg.arm_force``, or, when that is None, the
    gripper's weight (palm and cores) plus :data:`ARM_PUSH`."""
    if cfg.arm_force is not None:
        return cfg.arm_force
    return ARM_PUSH + (cfg.palm_mass + 2.0 * cfg.finger_mass) * cfg.sim.gravity


def open_half_gap(finger_stroke: float, pad: float, finger_half_height: float, jaw_wedge: float) -> float:
    """The narrowest half gap of the open fingers [m]: a wedge turns one edge of each face inwards."""
    return finger_stroke - pad - finger_half_height * math.sin(0.5 * abs(jaw_wedge))


def fit_error(*, cylinder_radius: float, jaw_wedge: float, finger_stroke: float, pad: float,
              finger_half_height: float, kind: str) -> str | None:  # fmt: skip
    """Why a cylinder of ``cylinder_radius`` does not fit between the open fingers with their pads
    on, or None."""
    r, gap = cylinder_radius, open_half_gap(finger_stroke, pad, finger_half_height, jaw_wedge)
    if r + GEOMETRY_MARGIN > gap:
        return (f"SceneConfig: the cylinder (cylinder_radius={r:g} m) does not fit between the open fingers: "
                f"finger_stroke={finger_stroke:g} m less the {kind} pad ({pad:g} m) and the "
                f"jaw_wedge={jaw_wedge:g} rad leave a half gap of {gap:.4f} m; the radius must be at most "
                f"{gap - GEOMETRY_MARGIN:.4f} m")  # fmt: skip
    return None


def grasp_height(cfg: SceneConfig) -> float:
    """Height of the finger centres when they grip the object [m]: the cylinder's mid height; for
    another object its centre of mass at rest, or, for a low one, the lowest the arm takes them
    (the workspace's floor: the tissue's depth and :data:`GROUND_CLEARANCE` above the ground,
    whatever the kind)."""
    if cfg.object is None:
        return 0.5 * cfg.cylinder_height
    return max(object_geometry(cfg.object).rest_height, lowest_grip(cfg.finger_half_extents[2], cfg.tissue.extrude))


def lowest_grip(finger_half_height: float, extrude: float) -> float:
    """The lowest grip point of the arm's workspace [m] (scene.gripper.Workspace)."""
    return finger_half_height + extrude + GROUND_CLEARANCE


def geometry_error(cfg: SceneConfig, **changes: Any) -> str | None:
    """Why the scene ``cfg`` - with ``changes`` to its misalignment, cylinder or start, if given -
    cannot start, or None: the object must fit between the open fingers with their pads on, and
    neither a finger nor the palm may start inside it. A pure function of the settings, so the env
    checks the corners of its ranges without building a config for each."""

    def get(name: str):
        return changes[name] if name in changes else getattr(cfg, name)

    fh = cfg.finger_half_extents
    pad = cfg.pad_thickness
    wedge, yaw = get("jaw_wedge"), get("yaw")
    if cfg.object is None:
        r, h = get("cylinder_radius"), get("cylinder_height")
        across_r = along_r = r
        grasp_z, what = 0.5 * h, "the cylinder"
        error = fit_error(cylinder_radius=r, jaw_wedge=wedge, finger_stroke=cfg.finger_stroke, pad=pad,
                          finger_half_height=fh[2], kind=cfg.fingers.kind)  # fmt: skip
        if error is not None:
            return error
    else:
        geo = object_geometry(cfg.object)
        c, s = math.cos(yaw), math.sin(yaw)
        # the object's reach along the closing axis and along the faces, both ways (a shape need not
        # be symmetric about its centre of mass)
        across_r = max(geo.half_width(c, s), geo.half_width(-c, -s))
        along_r = max(geo.half_width(-s, c), geo.half_width(s, -c))
        h, grasp_z, what = geo.top, grasp_height(cfg), f"the {cfg.object.name}"
        gap = open_half_gap(cfg.finger_stroke, pad, fh[2], wedge)
        if across_r + GEOMETRY_MARGIN > gap:
            return (f"SceneConfig: {what} ({across_r:.4f} m from its centre along the closing axis at yaw={yaw:g}) "
                    f"does not fit between the open fingers: finger_stroke={cfg.finger_stroke:g} m less the "
                    f"{cfg.fingers.kind} pad ({pad:g} m) and the jaw_wedge={wedge:g} rad leave a half gap of "
                    f"{gap:.4f} m")  # fmt: skip
    gap = open_half_gap(cfg.finger_stroke, pad, fh[2], wedge)
    start_height, cyl_xy, grip_xy = get("start_height"), get("cylinder_xy"), get("gripper_xy")
    lateral = get("lateral_offset")
    grip_z = grasp_z + start_height
    dx = cyl_xy[0] - grip_xy[0]
    dy = cyl_xy[1] - grip_xy[1] - lateral
    across = abs(dx * math.cos(yaw) + dy * math.sin(yaw))  # along the closing axis
    along = abs(-dx * math.sin(yaw) + dy * math.cos(yaw))  # along the faces
    tips = grip_z - fh[2] - pad
    if tips < h and along < fh[1] + along_r and across + across_r + GEOMETRY_MARGIN > gap:
        if cfg.object is None:
            return (f"SceneConfig: the open fingers start inside the cylinder: their tips ({tips:.3f} m up, start_height="
                    f"{start_height:g}) are below its top (cylinder_height={h:g}) and it stands {across:.4f} m across "
                    f"the closing axis from the grip (cylinder_xy={cyl_xy}, gripper_xy={grip_xy}, "
                    f"lateral_offset={lateral:g}, yaw={yaw:g}); with cylinder_radius={r:g} at most "
                    f"{gap - r - GEOMETRY_MARGIN:.4f} m fits")  # fmt: skip
        return (f"SceneConfig: the open fingers start inside {what}: their tips ({tips:.3f} m up, start_height="
                f"{start_height:g}) are below its top ({h:.3f} m) and it stands {across:.4f} m across the closing "
                f"axis from the grip (cylinder_xy={cyl_xy}, gripper_xy={grip_xy}, lateral_offset={lateral:g}, "
                f"yaw={yaw:g}); at most {gap - across_r - GEOMETRY_MARGIN:.4f} m fits")  # fmt: skip
    palm_bottom = grip_z + fh[2] + FINGER_DROP
    if palm_bottom < h + GEOMETRY_MARGIN and across < PALM_HALF_EXTENTS[0] + across_r and along < PALM_HALF_EXTENTS[1] + along_r:
        if cfg.object is None:
            return (f"SceneConfig: the palm starts inside the cylinder: its underside is {palm_bottom:.3f} m up, the "
                    f"cylinder (cylinder_height={h:g}) reaches {h:g} m; raise start_height={start_height:g} by "
                    f"{h + GEOMETRY_MARGIN - palm_bottom:.3f} m or lower the cylinder")  # fmt: skip
        return (f"SceneConfig: the palm starts inside {what}: its underside is {palm_bottom:.3f} m up, the object "
                f"reaches {h:.3f} m; raise start_height={start_height:g} by {h + GEOMETRY_MARGIN - palm_bottom:.3f} m")  # fmt: skip
    return None


def scale_friction(cfg: SceneConfig, scale: float) -> SceneConfig:
    """``cfg`` with every friction coefficient (the finger surface's static and kinetic, the
    ground's) scaled by ``scale``: how the env's ``friction_range`` and the ``friction_scale``
    reset option act."""
    mu_k = cfg.tissue.friction_kinetic  # None (equal to mu_s) stays so
    tissue = replace(cfg.tissue, friction_static=cfg.tissue.friction_static * scale,
                     friction_kinetic=None if mu_k is None else mu_k * scale)  # fmt: skip
    return replace(cfg, tissue=tissue, ground_friction=cfg.ground_friction * scale)


# --- the spellings of 0.2: a finger kind's settings were flat fields of SceneConfig ---------------

_LEGACY_FIELDS: dict[str, tuple[type[FingerConfig], str]] = {
    "tissue_faces": (TissueFingerConfig, "faces"),
    "fem_resolution": (FemConfig, "resolution"),
    "fem_substeps": (FemConfig, "substeps"),
    "finger_segments": (SegmentedConfig, "segments"),
    "segment_stiffness_pitch": (SegmentedConfig, "stiffness_pitch"),
    "segment_stiffness_yaw": (SegmentedConfig, "stiffness_yaw"),
    "segment_damping_pitch": (SegmentedConfig, "damping_pitch"),
    "segment_damping_yaw": (SegmentedConfig, "damping_yaw"),
    "segment_spring": (SegmentedConfig, "spring"),
}


def _translate_legacy(kwargs: dict) -> dict:
    """``SceneConfig(fingers="segmented", finger_segments=4)`` (0.2) as
    ``SceneConfig(fingers=SegmentedConfig(segments=4))``, with a DeprecationWarning; a setting of
    another kind than ``fingers`` is an error, as it would be lost. ``arm="smooth"`` (before 0.7,
    when the arm had two kinds) is dropped with a DeprecationWarning, ``arm="jump"`` a ValueError
    naming the release that has it."""
    retired_choice(kwargs, "arm", kept="smooth", gone=("jump",), release="0.6.0", owner="SceneConfig", stacklevel=4)
    legacy = {k: kwargs.pop(k) for k in list(kwargs) if k in _LEGACY_FIELDS}
    if not legacy:
        return kwargs
    fingers = finger_config(kwargs.get("fingers", "tissue"), owner="SceneConfig")
    for old, value in legacy.items():
        cls, new = _LEGACY_FIELDS[old]
        deprecated(f"SceneConfig({old}=...)", f"SceneConfig(fingers={cls.__name__}({new}=...))", stacklevel=4)
        if type(fingers) is not cls:
            raise ValueError(f"SceneConfig.{old} is a setting of fingers={cls.kind!r}, but fingers={fingers.kind!r}")
        fingers = replace(fingers, **{new: value})
    kwargs["fingers"] = fingers
    return kwargs


accept_old_names(SceneConfig, {"finger_max_opening": "finger_stroke", "palm_force": "arm_force"},
                 translate=_translate_legacy)  # fmt: skip
for _old, (_cls, _new) in _LEGACY_FIELDS.items():

    def _read(self, _old=_old, _cls=_cls, _new=_new):
        deprecated(f"SceneConfig.{_old}", f"SceneConfig.fingers.{_new}")
        return getattr(self.fingers if type(self.fingers) is _cls else _cls(), _new)

    setattr(SceneConfig, _old, property(_read, doc=f"Deprecated: ``fingers.{_new}`` of a {_cls.__name__}."))


__all__ = ["ARM_PUSH", "FINGER_DROP", "GEOMETRY_MARGIN", "PALM_HALF_EXTENTS", "SceneConfig", "arm_force_limit", "fit_error", "geometry_error", "open_half_gap", "scale_friction"]
