"""Gymnasium environments: two fingers pick up a cylinder, with soft tissue or rigid-only.

The class docstrings are the env cards (the user manual); ``softgrasp_env/registration.py`` lists
the registered ids.
"""

from __future__ import annotations

import itertools
import math
import os
import sys
from dataclasses import replace
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from . import presets
from .config import SceneConfig, SimConfig, TissueConfig, pad_thickness
from .scene import GraspScene
from .sim.world import SimulationDiverged

# Slots of GraspScene's rigid list and shapes (see scene.py).
_LEFT, _RIGHT, _CYL, _PALM = 0, 1, 2, 3

OBS_NAMES: tuple[str, ...] = (
    "grip_x", "grip_y", "grip_z",
    "grip_vx", "grip_vy", "grip_vz",
    "finger_gap",
    "cyl_rel_x", "cyl_rel_y", "cyl_rel_z",
    "cyl_axis_x", "cyl_axis_y", "cyl_axis_z",
    "cyl_vx", "cyl_vy", "cyl_vz",
    "cyl_wx", "cyl_wy", "cyl_wz",
    "force_left", "force_right",
    "lift",
    "gripper_yaw",
)  # fmt: skip
"""Names of the observation entries, in order (the env card documents each)."""

CARRY_OBS_NAMES: tuple[str, ...] = OBS_NAMES + ("time",)
"""With the carry test (``carry=True``, the v2 ids) the observation ends with the time since
reset [s]: the carry comes at a fixed time, and a policy that cannot see the clock would face a
task that is not Markov."""

RESET_OPTIONS = ("cylinder_xy", "lateral_offset", "yaw", "jaw_wedge", "friction_scale", "cylinder_radius",
                 "cylinder_mass", "gripper_xy")  # fmt: skip
"""Keys ``reset(options=...)`` accepts: each fixes a quantity that is otherwise randomised."""


GRIP_TOP = 0.20
"""Highest the arm takes the grip point [m]."""
REACH_CLEARANCE = 0.02
"""Task 'reach': the open fingertips start this far above the cylinder's top [m]."""
MAX_ARM_STEP = 1.0 / 120.0
"""Farthest the arm's target may move in one physics step, gripper_speed * dt [m]: 3.3 cm tore
the tissue in 2 of 5 probe episodes, 1.7 cm in 2 of 8 (1/60 s with the strongest fingers,
tests/test_extremes.py); the default moves 0.6 mm."""

TASKS: dict[str, dict[str, float]] = {
    # The grip starts above the cylinder's top, 4-14 cm from the origin in a random direction
    # (approach_range); the cylinder stands anywhere within +-7 cm of the origin: the two spread
    # the cylinder's offset from the grip over so wide a region that no constant action sequence
    # finds it often (tests/test_task.py). The fingers are misaligned by a jaw wedge of up to
    # +-0.15 rad and a yaw of up to +-pi/4. benchmarks/stability_map.py: rigid fingers lose the
    # cylinder from a 0.025 rad wedge on at every yaw tried (0-0.3 rad; 83 % of these episodes
    # have |wedge| > 0.025), the tissue holds it up to the 0.45 rad tried; offset and yaw alone
    # break neither, and the cylinder is round, so the yaw only turns the grasp.
    "reach": dict(cylinder_position_range=0.07, yaw_range=math.pi / 4, jaw_wedge_range=0.15, carry=True),
    # The gentle start of v0, for debugging: the open fingers around the top of the cylinder,
    # aligned (no wedge), the cylinder within +-1 cm of the origin.
    "easy": dict(cylinder_position_range=0.01, yaw_range=math.radians(5.0), jaw_wedge_range=0.0, carry=False),
}
"""Tasks (``task=``), the randomisation ranges and whether the carry test is on, as each defaults to."""

CARRY_START = 3.5
"""The carry test begins this long after reset [s] (step 70 of the 100 at 20 Hz): the scripted
policy holds the cylinder 5 cm up after 1.85 s (median) and 2.5 s at the latest over seeds
1000-1099, so it has a second to spare."""
CARRY_DURATION = 1.5
"""How long the arm carries [s]: three periods at CARRY_FREQUENCY, ending where it began."""
CARRY_AMPLITUDE = 0.01
"""Sideways displacement amplitude of the carry [m]."""
CARRY_FREQUENCY = 2.0
"""Frequency of the carry's sideways sway [Hz]: peak speed 2 pi f A = 0.13 m/s (below the arm's
0.15 m/s), peak acceleration (2 pi f)^2 A = 1.6 m/s^2 (0.16 g). A cylinder hanging from two rigid
contact points swings about the line through them as a pendulum of length l (the grasp's height
above the centre of mass), sqrt(g / l) / (2 pi) = 2.4 Hz for l = 4.5 cm, so this sway rocks it;
tissue pads hold it by their area and shear stiffness. Measured with the v1 baselines (seeds
1000-1029): scripted soft 30 / 30 held, SAC soft 26 / 26, scripted rigid 0 / 12, SAC rigid 5 / 28;
at 1.25 and 1.5 Hz the scripted rigid grasp held 12 / 12 (tilting 21-28 degrees)."""


def _display_available() -> bool:
    if sys.platform.startswith("linux"):
        return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    return True


class SoftGraspEnv(gym.Env):
    """Two fingers pick up a cylinder and hold it while the arm carries it; with ``soft=True`` each
    finger is a rigid core wrapped in oriented-particle tissue (``SoftGrasp-v2``), with
    ``soft=False`` the same cores touch the cylinder through pybullet's rigid contacts
    (``SoftGraspRigid-v2``). ``SoftGrasp-v1`` / ``SoftGraspRigid-v1`` are the same task without the
    carry test (``carry=False``).

    ## Description
    A gripper hangs above a cylinder (radius 3 cm, height 10 cm, 0.1 kg) standing on the ground.
    The gripper is a palm pulled by a force-limited arm (200 N) and two finger cores that close
    along the palm's x axis, each driven by a force-limited motor (3 N): squeezing is a force, not a
    teleport. The task is to reach the cylinder, close on it, lift it at least 5 cm and keep it
    through the carry test: for the episode's last 1.5 s the arm sways it sideways (Carry test,
    below), as a transport would. The gripper
    starts above the cylinder's top and 4-14 cm away from the origin, the cylinder anywhere within
    7 cm of it, and the fingers are only approximately aligned (thesis: "only approximate
    orientation of the fingers relative to the object"): a jaw wedge, a yaw and a lateral offset
    (Starting state, below). Physics runs at 240 Hz; one env step holds the action for
    ``240 / control_frequency`` physics steps.

    ## Action space
    ``Box(-1, 1, (4,), float32)``:

    | index | meaning | scaling |
    |---|---|---|
    | 0, 1, 2 | gripper displacement x, y, z (world frame; ignored during the carry test) | ``a * gripper_speed / control_frequency`` m added to the arm's target |
    | 3 | finger closing | target travel ``(a + 1) / 2 * finger_max_opening`` from fully open: -1 fully open, +1 fingers meet (the force limit sets the squeeze) |

    The arm's target is kept inside the workspace (x, y within ±15 cm of the origin, fingertip
    height between just above the ground and 20 cm) and at most 2 cm from where the palm is, as a
    real arm's reach and tracking limit would. Out-of-range actions are clipped to [-1, 1] and
    ``info["action_clipped"]`` says so; a NaN/inf action or one of the wrong shape raises
    ``ValueError``.

    ## Observation space
    ``Box(-inf, inf, (24,), float32)`` (23 without the carry test: the v1 ids), SI units, world frame (z up):

    | index | name | meaning |
    |---|---|---|
    | 0-2 | grip_x/y/z | grip point (midpoint of the two finger cores) [m] |
    | 3-5 | grip_vx/vy/vz | palm linear velocity [m/s] |
    | 6 | finger_gap | distance between the finger cores' inner faces [m] |
    | 7-9 | cyl_rel_x/y/z | cylinder centre minus grip point [m] |
    | 10-12 | cyl_axis_x/y/z | cylinder axis (unit vector; the orientation up to the cylinder's symmetry) |
    | 13-15 | cyl_vx/vy/vz | cylinder linear velocity [m/s] |
    | 16-18 | cyl_wx/wy/wz | cylinder angular velocity [rad/s] |
    | 19, 20 | force_left/right | normal force each finger presses on the cylinder with, tissue plus core contacts, mean over the env step [N] |
    | 21 | lift | cylinder centre above its resting height [m] |
    | 22 | gripper_yaw | palm yaw (the misalignment the agent cannot command) [rad] |
    | 23 | time | time since reset [s] (only with the carry test, which starts at a fixed time) |

    ``force_left/right`` can be far above the fingers' 3 N: the squeeze is limited by the finger
    motors, but the arm (200 N) can press a finger onto the cylinder, from the side or from above
    with the cylinder against the ground, and the contact carries whatever the arm pushes, as a
    real arm's would. Measured over 20 random-action episodes (seeds 0-19): up to 220 N soft, 267 N
    rigid (above 200 N: impacts within the env step and the ground's reaction). In the scripted
    grasp, where the arm only moves and lifts, no more than 2.9 N soft and 3.3 N rigid (its core
    hitting the cylinder), 3.0 N while the cylinder is in the air (tests/test_task.py). The forces
    are reported, not capped: a policy that shoves the cylinder should see it.

    ## Rewards
    ``reward_type="dense"`` (default): ``lift + reach`` where
    ``lift = clip(lift_height / success_height, 0, 1)`` (the task: 1 once the cylinder is 5 cm up)
    and ``reach = -reach_weight * min(d, 0.1 m) / 0.1 m`` with ``d`` the grip point's distance to the
    cylinder centre (small shaping, default weight 0.1). Both terms are in ``info["reward_terms"]``.
    ``reward_type="sparse"`` (``SoftGraspSparse-v2``): 1 on steps where ``info["held"]`` (lifted
    ≥ ``success_height``, both fingers pressing, upright: before, during and after the carry), else 0.

    ## Carry test
    With ``carry=True`` (the v2 ids; the default for ``task="reach"``), from ``carry_start``
    (3.5 s, step 70) for ``carry_duration`` (1.5 s, the last 30 steps of the 100) the arm, not the
    policy, moves the palm: ``carry_amplitude * sin(2 pi carry_frequency t)`` (1 cm at 2 Hz: peak
    speed 0.13 m/s, peak acceleration 1.6 m/s^2, 0.16 g) sideways across the jaw, horizontal and
    perpendicular to the fingers' closing axis, about where the palm's target was when it began;
    the arm's actions are ignored meanwhile (``info["carrying"]`` from the 3.5 s observation on),
    the finger action still acts. Success needs the cylinder held once the carry is over, so it
    must be lifted 5 cm by 3.5 s (the scripted policy holds it 5 cm up after 1.85 s, median, and
    2.5 s at the latest, over seeds 1000-1099). Why: without it (v1) a learned policy
    found a rigid grasp that holds statically, closing near the cylinder's top rim, and the task no
    longer told soft fingers from rigid ones (SAC: 94 % soft, 93 % rigid, docs/RESULTS.md). A grasp
    held at two contact points, as rigid fingers hold a round cylinder, lets it swing about the
    line through them like a pendulum of the grasp's height above the centre of mass
    (sqrt(g / l) / 2 pi = 2.4 Hz at 4.5 cm), which the 2 Hz sway rocks; the tissue's contact
    patches resist the turn. Measured with the v1 policies under this carry (seeds 1000-1029):
    scripted soft 30 / 30 held, SAC soft 26 / 26; scripted rigid 0 / 12, SAC rigid 5 / 28 of the
    grasps that held before the carry. A scripted soft grasp held through a 30 s carry (6 of 6
    seeds, tilt below 0.4 degrees, no slip: tests/test_task.py soaks it).

    ## Starting state
    ``task="reach"`` (every id but the Easy ones): fingers fully open, the fingertips 2 cm above the
    cylinder's top, the grip point uniformly over the annulus 4-14 cm (``approach_range``) around
    the origin; the cylinder at U(±7 cm) in x and y, the fingers misaligned by a jaw
    wedge U(±0.15 rad) and a yaw U(±pi/4). Why these ranges: the stability map
    (benchmarks/stability_map.py, docs/RESULTS.md) has rigid fingers lose the cylinder from a
    0.025 rad wedge on, at every yaw tried, while the tissue holds it up to 0.45 rad; offset and yaw
    alone break neither (the cylinder is round: the yaw only turns the grasp). 83 % of the
    episodes have |wedge| > 0.025 rad. Without the carry test (v1) what the rigid twin cannot hold
    is a grasp at mid-height with the gap open at the top (the map's sign): the scripted policy's
    rigid success is 1 of 46 such episodes, 30 of 30 with the gap open at the bottom (seeds
    1000-1099, benchmarks/wedge_sign.py), and a learned policy that closes near the top rim holds
    either way (SAC on SoftGraspRigid-v1: 88-93 % on two of three seeds). The carry test (v2)
    takes that way out: the rigid grasps that hold statically swing out under the sway.
    The spread of start and cylinder (as wide as the workspace allows) keeps every constant action
    sequence tried at or below 10 % (the best of 18: 4 of 40 episodes).
    A positive wedge opens the gap at the top (each inner face 6 mm further out at the top than
    at the bottom for 0.2 rad), a negative one at the bottom.

    ``task="easy"`` (``SoftGraspEasy-v1``, ``SoftGraspEasyRigid-v1``; v0's start, for debugging):
    fingers fully open, grip point 5 cm above the cylinder's mid height over the origin (the open
    fingers around the cylinder's top), no wedge, yaw U(±5°), the cylinder at U(±1 cm).

    Both: the palm
    offset laterally by U(±lateral_offset_range) along y and turned by U(±yaw_range) about z,
    fingers tilted by U(±jaw_wedge_range) against each other; cylinder upright at rest at
    U(±cylinder_position_range) in x and y. Friction (scaled by U(1 ± friction_range)), cylinder
    radius (± cylinder_radius_range) and mass (× U(1 ± cylinder_mass_range)) are randomised too if
    their ranges are non-zero. All draws come from the env's ``np_random``; ``reset(options=...)``
    may fix any of them (keys in ``RESET_OPTIONS``).

    ## Episode end
    - ``info["is_success"]`` (every step): ``info["held"]`` - lifted ≥ ``success_height``, both
      fingers press on it (≥ 0.05 N each), not tilted more than ``max_tilt`` - and, with the carry
      test, the carry is over (so only on the last step of a 100-step episode).
    - Terminated: the cylinder tilts more than ``max_tilt`` (knocked over), leaves the workspace
      (more than 15 cm from the origin horizontally, below the ground or above 50 cm), or the
      simulation diverges (non-finite numbers, a body faster than 20 m/s, tissue torn more than
      3 cm from its core, a finger segment turning faster than 90 rad/s): then ``info["diverged"] = True``, ``info["divergence"]``
      says which (else it is ``None``), the reward is 0 and the observation is the last finite one, never a NaN.
    - Truncated: by the registered time limit (100 steps = 5 s at 20 Hz).

    ## Arguments
    ``gym.make("SoftGrasp-v2", **kwargs)``; all keyword-only except ``render_mode``:

    - ``soft`` (True): tissue on the fingers, or rigid-only fingers; ``fingers`` ('tissue' |
      'rigid' | 'segmented' | 'fem', overrides ``soft``) names the finger kind; ``tissue_faces``
      ('all' | 'contact': only the inner face and tip of each core get tissue);
      ``fem_resolution`` ('coarse' | 'fine') the pads' mesh for fingers='fem' (pybullet's FEM;
      measured 0.025x real time coarse, fine several times slower: softgrasp_env/fem.py).
    - ``preset`` ('fast' | 'default' | 'accurate', softgrasp_env/presets.py): the tissue and
      solver settings to start from; ``tissue``, ``sim``, ``tissue_faces`` and the tissue
      arguments below override them.
    - ``reward_type`` ("dense" | "sparse").
    - ``control_frequency`` (20 Hz): must divide the physics rate ``1 / sim.dt`` (240 Hz).
    - ``gripper_speed`` (0.15 m/s, at most 2 and at most 1/120 m per physics step, ``gripper_speed * sim.dt``):
      arm displacement per step at full action, times the step time.
    - ``tissue_density`` (particles per m² of core surface), ``friction_static``,
      ``friction_dynamic``: tissue settings (also the rigid fingers' pybullet friction);
      ``tissue`` / ``sim``: whole ``TissueConfig`` / ``SimConfig`` objects to start from.
    - ``cylinder_radius``, ``cylinder_height``, ``cylinder_mass``, ``finger_force``.
    - ``success_height`` (0.05 m), ``reach_weight`` (0.1), ``max_tilt`` (π/4 rad).
    - ``carry`` (None: on for task "reach", off for "easy"), ``carry_start`` (3.5 s),
      ``carry_duration`` (1.5 s), ``carry_amplitude`` (0.01 m), ``carry_frequency`` (2 Hz): the
      carry test, above. Its sway may move the arm's target at most 1/120 m per physics step.
    - ``task`` ("reach" | "easy", see Starting state) and the randomisation ranges, their defaults
      per task (reach / easy): ``cylinder_position_range`` (0.07 / 0.01 m), ``yaw_range``
      (pi/4 / 5° in rad), ``jaw_wedge_range`` (0.15 / 0 rad), ``approach_range`` ((0.04, 0.14) m,
      reach only); ``lateral_offset_range`` (0.005 m), ``friction_range`` (0),
      ``cylinder_radius_range`` (0 m), ``cylinder_mass_range`` (0).
    - ``render_width``, ``render_height`` (480 × 360 px).

    Out-of-range arguments raise ``ValueError`` naming the argument. So do combinations that
    would not run, each naming the rule and the limit (measured where they stopped running,
    tests/test_extremes.py): a cylinder that does not fit the open fingers with their pads, or a
    range whose extremes start a finger or the palm inside it; tissue particles wider than 1.25 cm
    (``radius_scale`` times the spacing); a tissue that sags more than 0.6 cm under gravity per ``g dt^2 / stiffness``; the
    consistent coupling's squeeze ``finger_force * dt`` above 0.125 N s; the arm's target moving
    more than 1/120 m per physics step. What is accepted runs: the ends of every range (the slowest,
    1e-5 s steps, 200 iterations, 0.5 Hz control, only in the slow selection or by a stand-in), 13
    combinations of them and a seeded fuzz over all ranges at once run without divergence, except
    for the one known failure, rare everywhere: a tissue particle snagged over the cylinder's rim
    and torn past the 3 cm limit (at the defaults about once in 10,000 random-action steps; 2 of
    the 56 ends and combinations once in 8 further episodes).

    ## Rendering
    ``render_mode="rgb_array"`` draws the scene with pybullet's CPU renderer in a separate viewer
    (tissue particles as ellipsoids, cores, cylinder), headless. ``render_mode="human"`` runs the
    simulation in the pybullet GUI (needs a display) with the particles shown; on a machine without
    one, asking for it raises ``ValueError`` and an instance's ``metadata["render_modes"]`` lists
    only ``rgb_array``.

    ## Determinism and copies
    Reset rebuilds the simulation (pybullet's restoreState is not bit-exact), so two envs with the
    same seed and actions give bit-identical trajectories. Pickling or deep-copying an env records
    its reset draw and the actions since, and the copy replays them: an exact copy, at the cost of
    re-simulating the episode so far, and only that: earlier episodes are not replayed, so the
    cost is bounded by the time limit (100 steps: measured 0.54 s soft, 0.29 s rigid for a copy
    at step 99, 0.1 s right after a reset). An env made without the time limit pays per step since
    its last reset; copy it after a reset to pay nothing. A snapshot of pybullet's state would be
    cheaper but not exact (pybullet's restoreState is not bit-exact, above).

    ## Physics and its accuracy (measured at the defaults, ``benchmarks/accuracy_defaults.py``)
    Both fingers are geared to equal travel (a parallel gripper's rack and pinion) within
    [0, ``finger_max_opening``]. Tissue friction is Coulomb's with mu_s > mu_k, decided per contact
    patch, with anchors (softgrasp_env/tissue/friction.py):

    | check | Coulomb / physics | measured |
    |---|---|---|
    | heaviest cylinder held at 3 N per finger, slow lift | 2 mu_s F / g = 0.551 kg | soft 0.534 kg (-3.0 %), soft ``coupling="consistent"`` 0.536 kg (-2.6 %), rigid twin 0.550 kg (-0.0 %) |
    | held cylinder over 60 s | stays put | slip < 0.025 mm, tilt < 0.05 deg (all three) |
    | tissue pad on a slowly tilted ramp, mu_s 0.3 / 0.6 / 0.9 | breaks loose at tan = mu_s | +0.15 / +0.09 / +0.08 % |
    | pad sliding to a stop from 0.25 / 0.5 / 1 m/s | v^2 / (2 mu_k g) | -1.1 / -0.4 / -0.05 % |
    | free tissue body, 1,000 steps | momentum and angular momentum conserved | 7e-10 / 1e-10 relative |
    | deepest tissue penetration, every step | 0 | 0.095 mm (thesis coupling, at the fingers' 0.1 m/s impact), 0.122 mm (consistent) |

    The tissue is compliant: under load the pads shear (about 1 mm of in-hand motion with the
    default cylinder), and a fast lift loses part of the bound to the lift-off transient (the
    cylinder leaves the ground only once the pads have sheared, then catches up with the palm): with
    a 1 s lift the soft fingers hold 0.421 kg, 24 % less than Coulomb's static bound and about its
    kinetic one, 2 mu_k F / g = 0.428 kg - the pads slip while the load comes on (the previous,
    finer default pad: 14 % less; the rigid twin: 0.9 %). The env lifts at full speed, so its
    heaviest cylinder is nearer 0.4 kg than 0.55.

    Cost (``benchmarks/throughput.py``, this 2-core machine, quiet): about 4,900 physics steps/s
    with the soft fingers (60 particles on the inner faces and tips), 10,400 with the rigid twin;
    ``preset="fast"`` 5,200; every face covered at 10,000 per m^2 (the previous default) 1,800.
    An env step is 12 physics steps. ``fingers="segmented"`` runs at about half the soft speed,
    ``fingers="fem"`` (pybullet's FEM, 8 substeps) at a few steps/s: docs/RESULTS.md.

    ## Version history
    - v2: the carry test (for the soft, rigid and sparse ids; the observation gains the time);
      the v1 ids stay, unchanged (``carry=False``), because their published baselines reproduce on
      them. SoftGraspGoal-v1 and the Easy ids have no carry test and keep v1.
    - v1: the reach task (approach from above and away, misaligned fingers) for every id; the
      gentle start as SoftGraspEasy-v1 / SoftGraspEasyRigid-v1; the final physics and default
      preset (contact-face tissue, 4,000 particles per m^2). ``reset(options=...)`` takes
      ``gripper_xy``.
    - v0: initial release. Since then, with the ids kept until the task's next version (results
      change): the rigid twin's fingers get the friction asked for (pybullet had silently kept 0.5,
      not 0.9); the fingers are geared and limited; tissue friction obeys Coulomb at the defaults
      (anchored, per patch, kinetic friction half on velocities); free tissue bodies keep their
      angular momentum; the consistent coupling moves a finger core only along its joint;
      ``SimConfig(orientation="reaction")`` was removed.
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 20}

    def __init__(
        self,
        render_mode: str | None = None,
        *,
        soft: bool = True,
        fingers: str | None = None,
        tissue_faces: str | None = None,
        fem_resolution: str = "coarse",
        preset: str = "default",
        task: str = "reach",
        reward_type: str = "dense",
        control_frequency: float = 20.0,
        gripper_speed: float = 0.15,
        tissue_density: float | None = None,
        friction_static: float | None = None,
        friction_dynamic: float | None = None,
        tissue: TissueConfig | None = None,
        sim: SimConfig | None = None,
        cylinder_radius: float = 0.03,
        cylinder_height: float = 0.10,
        cylinder_mass: float = 0.1,
        finger_force: float = 3.0,
        success_height: float = 0.05,
        reach_weight: float = 0.1,
        max_tilt: float = math.pi / 4,
        carry: bool | None = None,
        carry_start: float = CARRY_START,
        carry_duration: float = CARRY_DURATION,
        carry_amplitude: float = CARRY_AMPLITUDE,
        carry_frequency: float = CARRY_FREQUENCY,
        cylinder_position_range: float | None = None,
        lateral_offset_range: float = 0.005,
        yaw_range: float | None = None,
        jaw_wedge_range: float | None = None,
        approach_range: tuple[float, float] = (0.04, 0.14),
        friction_range: float = 0.0,
        cylinder_radius_range: float = 0.0,
        cylinder_mass_range: float = 0.0,
        render_width: int = 480,
        render_height: int = 360,
    ) -> None:
        self._init_kwargs = {k: v for k, v in locals().items() if k not in ("self", "__class__")}
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']} or None, got {render_mode!r}")
        if render_mode == "human" and not _display_available():
            raise ValueError("render_mode='human' opens the pybullet GUI and needs a display (DISPLAY is not set); "
                             "use render_mode='rgb_array' headless")  # fmt: skip
        if not isinstance(soft, bool):
            raise ValueError(f"soft must be a bool, got {soft!r}")
        if task not in TASKS:
            raise ValueError(f"task must be one of {tuple(TASKS)}, got {task!r}")
        defaults = TASKS[task]
        cylinder_position_range = defaults["cylinder_position_range"] if cylinder_position_range is None else cylinder_position_range
        yaw_range = defaults["yaw_range"] if yaw_range is None else yaw_range
        jaw_wedge_range = defaults["jaw_wedge_range"] if jaw_wedge_range is None else jaw_wedge_range
        carry = defaults["carry"] if carry is None else carry
        if not isinstance(carry, (bool, np.bool_)):
            raise ValueError(f"carry must be a bool (or None: the task's default), got {carry!r}")
        try:
            a_lo, a_hi = (float(v) for v in approach_range)
        except (TypeError, ValueError):
            raise ValueError(f"approach_range must be (min, max) distances in m, got {approach_range!r}") from None
        if not (math.isfinite(a_lo) and math.isfinite(a_hi) and 0.0 <= a_lo <= a_hi <= 0.14):
            raise ValueError(f"approach_range must be 0 <= min <= max <= 0.14 m (the grip's workspace is +-0.15 m), got {approach_range!r}")
        if fingers is None:
            fingers = "tissue" if soft else "rigid"
        elif not soft and fingers == "tissue":
            raise ValueError("soft=False asks for rigid-only fingers, but fingers='tissue': give one of the two")
        if reward_type not in ("dense", "sparse"):
            raise ValueError(f"reward_type must be 'dense' or 'sparse', got {reward_type!r}")
        _check("control_frequency", control_frequency, 0.5, 240.0)
        _check("gripper_speed", gripper_speed, 0.0, 2.0, lo_open=True)
        _check("success_height", success_height, 0.0, 0.15, lo_open=True)
        _check("reach_weight", reach_weight, 0.0, 10.0)
        _check("max_tilt", max_tilt, 0.0, math.pi, lo_open=True)
        _check("carry_start", carry_start, 0.0, 600.0)
        _check("carry_duration", carry_duration, 0.0, 600.0, lo_open=True)
        _check("carry_amplitude", carry_amplitude, 0.0, 0.05)
        _check("carry_frequency", carry_frequency, 0.0, 10.0, lo_open=True)
        _check("cylinder_position_range", cylinder_position_range, 0.0, 0.08)
        _check("lateral_offset_range", lateral_offset_range, 0.0, 0.05)
        _check("yaw_range", yaw_range, 0.0, math.pi / 4)
        _check("jaw_wedge_range", jaw_wedge_range, 0.0, math.pi / 6)
        _check("friction_range", friction_range, 0.0, 0.9)
        _check("cylinder_radius_range", cylinder_radius_range, 0.0, 0.02)
        _check("cylinder_mass_range", cylinder_mass_range, 0.0, 0.9)
        for name, val in (("render_width", render_width), ("render_height", render_height)):
            if isinstance(val, bool) or not isinstance(val, (int, np.integer)) or not 16 <= val <= 4096:
                raise ValueError(f"{name} must be an integer in [16, 4096], got {val!r}")

        if preset not in presets.PRESETS:
            raise ValueError(f"preset must be one of {tuple(presets.PRESETS)}, got {preset!r}")
        p_cfg = presets.scene_config(preset)
        p_tissue, p_sim = p_cfg.tissue, p_cfg.sim
        tissue_faces = tissue_faces if tissue_faces is not None else p_cfg.tissue_faces
        tissue = tissue if tissue is not None else p_tissue
        if not isinstance(tissue, TissueConfig):
            raise ValueError(f"tissue must be a TissueConfig, got {type(tissue).__name__}")
        overrides = {k: v for k, v in (("density", tissue_density), ("friction_static", friction_static),
                                       ("friction_dynamic", friction_dynamic)) if v is not None}  # fmt: skip
        tissue = replace(tissue, **overrides)  # validated by TissueConfig
        sim = sim if sim is not None else p_sim
        if not isinstance(sim, SimConfig):
            raise ValueError(f"sim must be a SimConfig, got {type(sim).__name__}")
        ratio = 1.0 / (sim.dt * control_frequency)
        self._substeps = int(round(ratio))
        if abs(ratio - self._substeps) > 1e-9 * ratio or self._substeps < 1:
            raise ValueError(f"control_frequency must divide the physics rate 1/sim.dt = {1.0 / sim.dt:g} Hz, "
                             f"got {control_frequency!r}")  # fmt: skip
        # The arm's target moves gripper_speed * dt per physics step (MAX_ARM_STEP).
        if gripper_speed * sim.dt > MAX_ARM_STEP + 1e-12:
            raise ValueError(f"gripper_speed={gripper_speed:g} m/s with sim.dt={sim.dt:g} s moves the arm "
                             f"{gripper_speed * sim.dt * 100:.2f} cm per physics step, more than {MAX_ARM_STEP * 100:.2f} "
                             f"cm; at this dt gripper_speed must be at most {MAX_ARM_STEP / sim.dt:.3g} m/s")  # fmt: skip
        # The carry moves the arm's target by at most 2 pi f A dt per physics step (MAX_ARM_STEP, as above).
        carry_step = 2.0 * math.pi * carry_frequency * carry_amplitude * sim.dt
        if carry and carry_step > MAX_ARM_STEP + 1e-12:
            raise ValueError(f"the carry (carry_amplitude={carry_amplitude:g} m at carry_frequency={carry_frequency:g} Hz) "
                             f"moves the arm up to {carry_step * 100:.2f} cm per physics step at sim.dt={sim.dt:g} s, "
                             f"more than {MAX_ARM_STEP * 100:.2f} cm")  # fmt: skip
        # The base scene, validated now so that bad sizes fail at construction, not at reset.
        # The start height of the task: reach starts the fingertips above the cylinder's top.
        _check("cylinder_height", cylinder_height, 0.01, 0.5)
        fh_z = SceneConfig.__dataclass_fields__["finger_half_extents"].default[2]
        # The cores' tips start 2 cm above the top; a pad thicker than 1.5 cm would reach the top
        # (the cylinder may stand right under the start), so it keeps 5 mm of clearance instead.
        clearance = max(REACH_CLEARANCE, pad_thickness(fingers, tissue) + 0.005)
        start_height = 0.5 * cylinder_height + fh_z + clearance if task == "reach" else 0.05
        base_kwargs = dict(fingers=fingers, tissue_faces=tissue_faces, fem_resolution=fem_resolution,
                           cylinder_radius=cylinder_radius, cylinder_height=cylinder_height, cylinder_mass=cylinder_mass,
                           finger_force=finger_force, tissue=tissue, sim=sim)  # fmt: skip
        # The scene's own checks first, from a start well above the cylinder: a pad too thick to
        # fit is named as such, not as a cylinder too tall for the start it raises.
        SceneConfig(**base_kwargs, start_height=min(0.3, 0.5 * cylinder_height + fh_z + clearance))
        grip_z = 0.5 * cylinder_height + start_height
        if grip_z > GRIP_TOP - 0.01:
            tallest = GRIP_TOP - 0.01 - fh_z - clearance if task == "reach" else 2.0 * (GRIP_TOP - 0.01 - 0.05)
            raise ValueError(f"cylinder_height={cylinder_height:g} m is too tall for task={task!r}: the grip would start "
                             f"{grip_z:.3f} m up, too near the top of the arm's workspace ({GRIP_TOP:g} m); at most "
                             f"{tallest:.3f} m")  # fmt: skip
        self._base = SceneConfig(**base_kwargs, start_height=start_height)
        if cylinder_radius - cylinder_radius_range < 0.005:
            raise ValueError(f"cylinder_radius - cylinder_radius_range must be >= 0.005 m, got "
                             f"{cylinder_radius} - {cylinder_radius_range}")  # fmt: skip

        self.render_mode = render_mode
        self.soft = self._base.soft
        self.fingers = self._base.fingers
        self.reward_type = reward_type
        self.control_frequency = float(control_frequency)
        self.gripper_speed = float(gripper_speed)
        self.success_height = float(success_height)
        self.reach_weight = float(reach_weight)
        self.max_tilt = float(max_tilt)
        self.task = task
        self.carry = bool(carry)
        self.carry_start = float(carry_start)
        self.carry_duration = float(carry_duration)
        self.carry_amplitude = float(carry_amplitude)
        self.carry_frequency = float(carry_frequency)
        self.obs_names = CARRY_OBS_NAMES if self.carry else OBS_NAMES
        """The observation's entries, in order (``OBS_NAMES``, and ``time`` with the carry test)."""
        self.approach_range = (a_lo, a_hi)
        self.ranges = {
            "cylinder_position": float(cylinder_position_range),
            "lateral_offset": float(lateral_offset_range),
            "yaw": float(yaw_range),
            "jaw_wedge": float(jaw_wedge_range),
            "friction": float(friction_range),
            "cylinder_radius": float(cylinder_radius_range),
            "cylinder_mass": float(cylinder_mass_range),
        }
        self.render_width = int(render_width)
        self.render_height = int(render_height)
        # The instance lists the render modes that work on this machine: without a display the GUI
        # cannot open (pybullet would end the process), so checkers must not try "human" there.
        modes = [m for m in type(self).metadata["render_modes"] if m != "human" or _display_available()]
        self.metadata = {**type(self).metadata, "render_modes": modes, "render_fps": self.control_frequency}

        self.action_space = spaces.Box(-1.0, 1.0, shape=(4,), dtype=np.float32)
        self.observation_space = spaces.Box(-np.inf, np.inf, shape=(len(self.obs_names),), dtype=np.float32)

        self._check_range_extremes()

        fh = self._base.finger_half_extents
        # Workspace of the grip point: the fingertips may come down to 3 mm above the ground
        # (the tissue's depth included, for both twins alike) and up to 20 cm.
        self._grip_low = np.array([-0.15, -0.15, fh[2] + tissue.extrude + 0.003])
        self._grip_high = np.array([0.15, 0.15, GRIP_TOP])
        self._max_lead = 0.02
        self.scene: GraspScene | None = None
        self._renderer = None
        self._last_obs: np.ndarray | None = None
        self._forces = np.zeros(2)
        self._reset_record: tuple[dict, dict] | None = None
        self._actions: list[np.ndarray] = []
        self._episode_over, self._divergence = False, None
        self._physics_steps = 0
        self._carry_anchor: np.ndarray | None = None

    # --- gym API -----------------------------------------------------------------------------------

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        if options is not None and not isinstance(options, dict):
            raise TypeError(f"reset options must be a dict (or None), got {type(options).__name__}: {options!r}")
        options = dict(options or {})
        unknown = set(options) - set(RESET_OPTIONS)
        if unknown:
            raise ValueError(f"unknown reset option(s) {sorted(unknown)}; allowed: {RESET_OPTIONS}")
        options = {k: _option_value(k, v) for k, v in options.items()}
        # What a copy needs to rebuild this episode exactly: the generator before the draws.
        self._reset_record = (self.np_random.bit_generator.state, options)
        self._actions = []
        self._build(options)
        obs = self._observe()
        self._last_obs = obs
        self._episode_over, self._divergence = False, None
        if self.render_mode == "human":
            self.render()
        return self._format_obs(obs), self._info(obs, diverged=False, clipped=False)

    def step(self, action):
        if self.scene is None:
            raise RuntimeError("call reset() before step()")
        raw = np.asarray(action)
        if raw.dtype.kind not in "biuf":  # complex (numpy would drop the imaginary part), text, None
            raise TypeError(f"action must be real numbers, got dtype {raw.dtype} ({action!r})")
        act = raw.astype(np.float64)
        if act.shape != (4,):
            raise ValueError(f"action must have shape (4,), got {act.shape}")
        if not np.isfinite(act).all():
            raise ValueError(f"action must be finite, got {act.tolist()}")
        clipped = bool((act < -1.0).any() or (act > 1.0).any())
        act = np.clip(act, -1.0, 1.0)
        self._actions.append(act.copy())
        diverged = self._apply_and_simulate(act)
        if diverged:
            obs = self._last_obs
            reward, terms = 0.0, {"lift": 0.0, "reach": 0.0}
            terminated = True
        else:
            obs = self._observe()
            self._last_obs = obs
            reward, terms = self._reward(obs)
            terminated = self._knocked_over_or_gone(obs)
        info = self._info(obs, diverged=diverged, clipped=clipped)
        info["reward_terms"] = terms
        if self.render_mode == "human":
            self.render()
        return self._format_obs(obs), self._final_reward(obs, info, reward), terminated, False, info

    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() called with render_mode=None; pass render_mode='rgb_array' or 'human' to make")
            return None
        if self.scene is None:
            raise RuntimeError("call reset() before render()")
        from .render import SceneRenderer

        if self._renderer is None:
            self._renderer = SceneRenderer(self.render_width, self.render_height, human=self.render_mode == "human")
        return self._renderer.render(self.scene)

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        if self.scene is not None:
            self.scene.close()
            self.scene = None

    # --- copies: replay the episode (bit-exact; see the env card) ----------------------------------

    def __getstate__(self) -> dict:
        return {"kwargs": self._init_kwargs, "reset_record": self._reset_record, "actions": list(self._actions),
                "np_random": None if self._np_random is None else self.np_random.bit_generator.state,
                "np_random_seed": self._np_random_seed}  # fmt: skip

    def __setstate__(self, state: dict) -> None:
        self.__init__(**state["kwargs"])
        if state["reset_record"] is not None:
            rng_state, options = state["reset_record"]
            self._np_random = np.random.Generator(np.random.PCG64())
            self._np_random.bit_generator.state = rng_state
            self._reset_record = (rng_state, options)
            self._build(options)
            self._last_obs = self._observe()
            for a in state["actions"]:
                self._actions.append(a.copy())
                if self._apply_and_simulate(a):
                    break
                self._last_obs = self._observe()
        if state["np_random"] is not None:
            self._np_random = np.random.Generator(np.random.PCG64())
            self._np_random.bit_generator.state = state["np_random"]
        self._np_random_seed = state["np_random_seed"]

    # --- internals ---------------------------------------------------------------------------------

    def _check_range_extremes(self) -> None:
        """Every corner of the randomisation ranges must be a scene that starts without overlap
        (SceneConfig's geometry check): the largest cylinder with the widest wedge, at each corner
        of its square, against each extreme of lateral offset and yaw. A clash is a ValueError
        naming the ranges, raised when the env is made, not at some later reset."""
        rg, b = self.ranges, self._base
        p, lo, yw, w = rg["cylinder_position"], rg["lateral_offset"], rg["yaw"], rg["jaw_wedge"]
        r = b.cylinder_radius + rg["cylinder_radius"]
        for sx, sy, so, syaw, sw in itertools.product((-1.0, 1.0), repeat=5):
            try:
                replace(b, cylinder_radius=r, cylinder_xy=(sx * p, sy * p), lateral_offset=so * lo, yaw=syaw * yw,
                        jaw_wedge=sw * w)  # fmt: skip
            except ValueError as e:
                raise ValueError(
                    f"the randomisation ranges reach a scene that cannot start (cylinder_position_range={p:g}, "
                    f"lateral_offset_range={lo:g}, yaw_range={yw:g}, jaw_wedge_range={w:g}, cylinder_radius_range="
                    f"{rg['cylinder_radius']:g}, task={self.task!r}): {e}") from None  # fmt: skip
        # The scaled quantities at their extremes stay inside SceneConfig's and TissueConfig's own
        # ranges (a 9 kg cylinder with cylinder_mass_range=0.9 used to fail at some reset, 17 kg).
        for sign in (-1.0, 1.0):
            try:
                _with_friction_scale(replace(b, cylinder_mass=b.cylinder_mass * (1.0 + sign * rg["cylinder_mass"])),
                                     1.0 + sign * rg["friction"])  # fmt: skip
            except ValueError as e:
                raise ValueError(
                    f"the randomisation ranges reach a scene that cannot be built (friction_range={rg['friction']:g}, "
                    f"cylinder_mass_range={rg['cylinder_mass']:g}, cylinder_mass={b.cylinder_mass:g}): {e}") from None  # fmt: skip

    def _draw(self, options: dict[str, Any]) -> SceneConfig:
        """The episode's scene: fixed options, else draws from np_random (always the same number
        of draws in the same order, so options do not shift the other quantities' draws)."""
        rng = self.np_random
        rg = self.ranges
        b = self._base
        u = rng.uniform(-1.0, 1.0, size=10)
        vals = {
            "cylinder_xy": (float(u[0] * rg["cylinder_position"]), float(u[1] * rg["cylinder_position"])),
            "lateral_offset": float(u[2] * rg["lateral_offset"]),
            "yaw": float(u[3] * rg["yaw"]),
            "jaw_wedge": float(u[4] * rg["jaw_wedge"]),
            "friction_scale": float(1.0 + u[5] * rg["friction"]),
            "cylinder_radius": float(b.cylinder_radius + u[6] * rg["cylinder_radius"]),
            "cylinder_mass": float(b.cylinder_mass * (1.0 + u[7] * rg["cylinder_mass"])),
            "gripper_xy": (0.0, 0.0),
        }
        if self.task == "reach":  # the grip starts above the cylinder's top, a random way off
            lo, hi = self.approach_range
            # uniform over the annulus' area, not over r: a uniform r crowds the starts near the
            # inner radius, where one constant move finds the cylinder far more often
            r = math.sqrt(lo * lo + 0.5 * (u[8] + 1.0) * (hi * hi - lo * lo))
            phi = math.pi * float(u[9])
            vals["gripper_xy"] = (r * math.cos(phi), r * math.sin(phi))
        for k, v in options.items():
            vals[k] = v  # checked and converted by _option_value
        fs = vals.pop("friction_scale")
        if not 0.0 < fs <= 10.0:
            raise ValueError(f"friction_scale must be in (0, 10], got {fs!r}")
        return _with_friction_scale(replace(b, **vals), fs)  # the task's start height is b's

    def _build(self, options: dict[str, Any]) -> None:
        cfg = self._draw(options)
        client = None if self.scene is None else self.scene.client
        self.scene = GraspScene(cfg, gui=self.render_mode == "human", client=client)
        if self._renderer is not None:
            self._renderer.invalidate()
        self._forces = np.zeros(2)
        self._physics_steps = 0
        self._carry_anchor = None

    def _apply_and_simulate(self, act: np.ndarray) -> bool:
        """Set the arm and finger targets from ``act`` and run one control interval; True if the
        simulation diverged."""
        sc = self.scene
        if self._episode_over:
            # Stepping on after a divergence: the bodies are poisoned; nothing more is simulated.
            return True
        col = sc.world.colliders
        palm = col.rigid_x[_PALM]
        grip_to_palm = palm - 0.5 * (col.rigid_x[_LEFT] + col.rigid_x[_RIGHT])
        target_grip = (sc.palm_target - grip_to_palm) + act[:3] * (self.gripper_speed / self.control_frequency)
        target_grip = np.clip(target_grip, self._grip_low, self._grip_high)
        target = np.clip(target_grip + grip_to_palm, palm - self._max_lead, palm + self._max_lead)
        sc.set_palm_target(target)
        sc.set_finger_target(0.5 * (float(act[3]) + 1.0) * sc.config.finger_max_opening)
        forces = np.zeros(2)
        try:
            for _ in range(self._substeps):
                if self.carry:
                    self._carry_target()
                sc.step()
                self._physics_steps += 1
                forces += sc.finger_forces()
        except SimulationDiverged:
            self._episode_over, self._divergence = True, "non-finite tissue solve"
            return True
        self._forces = forces / self._substeps
        self._divergence = self.scene.divergence()
        if self._divergence is not None:
            self._episode_over = True
            return True
        return False

    def _carry_phase(self, physics_steps: int) -> float | None:
        """Seconds into the carry at the end of physics step ``physics_steps`` (counted from
        reset), or None outside it."""
        t = physics_steps * self.scene.config.sim.dt - self.carry_start
        return t if -1e-9 < t <= self.carry_duration + 1e-9 else None

    def _carry_over(self) -> bool:
        return (not self.carry) or self._physics_steps * self.scene.config.sim.dt >= self.carry_start + self.carry_duration - 1e-9

    def _carry_target(self) -> None:
        """During the carry test the arm, not the policy, moves the palm: a sideways sway
        ``A sin(2 pi f t)`` about where the palm's target was when the carry began, horizontal and
        across the jaw (perpendicular to the fingers' closing axis, the direction a grasp held at
        two contact points is weakest in: it swings about the line through them). The policy's
        finger command still acts. Set before each physics step, so the sway is smooth at 240 Hz."""
        sc = self.scene
        t = self._carry_phase(self._physics_steps + 1)
        if t is None:
            return
        if self._carry_anchor is None:
            self._carry_anchor = sc.palm_target.copy()
        yaw = sc.config.yaw
        across = np.array([-math.sin(yaw), math.cos(yaw), 0.0])
        target = self._carry_anchor + across * (self.carry_amplitude * math.sin(2.0 * math.pi * self.carry_frequency * t))
        col = sc.world.colliders
        grip_to_palm = col.rigid_x[_PALM] - 0.5 * (col.rigid_x[_LEFT] + col.rigid_x[_RIGHT])
        sc.set_palm_target(np.clip(target - grip_to_palm, self._grip_low, self._grip_high) + grip_to_palm)

    def _observe(self) -> np.ndarray:
        sc = self.scene
        col = sc.world.colliders
        grip = 0.5 * (col.rigid_x[_LEFT] + col.rigid_x[_RIGHT])
        x, y, z, w = col.rigid_q[_CYL]
        axis = np.array([2.0 * (x * z + y * w), 2.0 * (y * z - x * w), 1.0 - 2.0 * (x * x + y * y)])
        px, py, pz, pw = col.rigid_q[_PALM]
        yaw = math.atan2(2.0 * (pw * pz + px * py), 1.0 - 2.0 * (py * py + pz * pz))
        closing = sc.finger_closing()
        gap = 2.0 * sc.config.finger_max_opening - float(closing.sum())
        obs = np.concatenate([
            grip, col.rigid_v[_PALM], [gap], col.rigid_x[_CYL] - grip, axis, col.rigid_v[_CYL], col.rigid_w[_CYL],
            self._forces, [col.rigid_x[_CYL, 2] - sc.cylinder_rest_z], [yaw],
        ])  # fmt: skip
        if self.carry:
            obs = np.append(obs, self._physics_steps * sc.config.sim.dt)
        return obs

    def _reward(self, obs: np.ndarray) -> tuple[float, dict[str, float]]:
        lift = float(np.clip(obs[21] / self.success_height, 0.0, 1.0))
        d = float(np.linalg.norm(obs[7:10]))
        reach = -self.reach_weight * min(d / 0.1, 1.0)  # exactly -reach_weight from 10 cm on
        terms = {"lift": lift, "reach": reach}
        if self.reward_type == "sparse":
            return float(self._held(obs)), terms
        return lift + reach, terms

    def _held(self, obs: np.ndarray) -> bool:
        """Lifted to the success height, both fingers pressing, not tilted beyond max_tilt."""
        upright = math.acos(float(np.clip(obs[12], -1.0, 1.0))) <= self.max_tilt
        return bool(obs[21] >= self.success_height and obs[19] >= 0.05 and obs[20] >= 0.05 and upright)

    def _success(self, obs: np.ndarray) -> bool:
        return self._held(obs) and self._carry_over()

    def _knocked_over_or_gone(self, obs: np.ndarray) -> bool:
        sc = self.scene
        cyl = sc.world.colliders.rigid_x[_CYL]
        if math.hypot(cyl[0], cyl[1]) > 0.15 or cyl[2] < -0.01 or cyl[2] > 0.5:
            return True
        tilt = math.acos(float(np.clip(obs[12], -1.0, 1.0)))
        return tilt > self.max_tilt

    def _info(self, obs: np.ndarray, *, diverged: bool, clipped: bool) -> dict[str, Any]:
        return {
            "is_success": (not diverged) and self._success(obs),
            "held": (not diverged) and self._held(obs),
            "carrying": self.carry and self._carry_phase(self._physics_steps) is not None and not self._carry_over(),
            "lift_height": float(obs[21]),
            "diverged": diverged,
            "divergence": self._divergence if diverged else None,
            "action_clipped": clipped,
        }

    def _format_obs(self, obs: np.ndarray):
        return obs.astype(np.float32)

    def _final_reward(self, obs: np.ndarray, info: dict[str, Any], reward: float) -> float:
        return float(reward)


class SoftGraspGoalEnv(SoftGraspEnv):
    """Goal-conditioned SoftGrasp (``SoftGraspGoal-v1``) for hindsight experience replay.

    As :class:`SoftGraspEnv` (same actions, physics, starting state and episode end), with:

    - Observation: ``Dict(observation=Box(23), achieved_goal=Box(3), desired_goal=Box(3))``:
      ``observation`` is SoftGraspEnv's vector, ``achieved_goal`` the cylinder centre [m],
      ``desired_goal`` the target for it: above the cylinder's start, at its resting height plus
      U(goal_height_range) (default 5-8 cm).
    - Reward: ``compute_reward(achieved_goal, desired_goal, info)`` = -1 while the cylinder centre
      is farther than ``distance_threshold`` (2 cm) from the goal, else 0 (vectorised over leading
      batch dimensions, as HER needs); -1 on a diverged step. ``info["is_success"]`` is exactly
      ``compute_reward(...) == 0``.

    Extra arguments: ``distance_threshold`` (0.02 m), ``goal_height_range`` ((0.05, 0.08) m).
    """

    def __init__(self, render_mode: str | None = None, *, distance_threshold: float = 0.02,
                 goal_height_range: tuple[float, float] = (0.05, 0.08), **kwargs: Any) -> None:  # fmt: skip
        if "reward_type" in kwargs:
            raise ValueError("SoftGraspGoalEnv's reward is the goal reward (compute_reward); do not pass reward_type")
        if kwargs.get("carry"):
            raise ValueError("SoftGraspGoalEnv has no carry test (carry=True): its reward and success are the goal's "
                             "alone (compute_reward), which a time-bound test would break for HER's relabelling")  # fmt: skip
        kwargs["carry"] = False
        super().__init__(render_mode, reward_type="sparse", **kwargs)
        del self._init_kwargs["reward_type"]
        _check("distance_threshold", distance_threshold, 0.0, 0.1, lo_open=True)
        if len(goal_height_range) != 2 or not 0.0 <= goal_height_range[0] <= goal_height_range[1] <= 0.15:
            raise ValueError(f"goal_height_range must be (lo, hi) with 0 <= lo <= hi <= 0.15 m, got {goal_height_range!r}")
        self._init_kwargs.update(distance_threshold=distance_threshold, goal_height_range=tuple(goal_height_range))
        self.distance_threshold = float(distance_threshold)
        self.goal_height_range = (float(goal_height_range[0]), float(goal_height_range[1]))
        self._goal = np.zeros(3)
        box = spaces.Box(-np.inf, np.inf, shape=(3,), dtype=np.float32)
        self.observation_space = spaces.Dict({
            "observation": spaces.Box(-np.inf, np.inf, shape=(len(OBS_NAMES),), dtype=np.float32),
            "achieved_goal": box,
            "desired_goal": box,
        })  # fmt: skip

    def _build(self, options: dict[str, Any]) -> None:
        super()._build(options)
        sc = self.scene
        h = float(self.np_random.uniform(*self.goal_height_range))
        self._goal = np.array([sc.config.cylinder_xy[0], sc.config.cylinder_xy[1], sc.cylinder_rest_z + h])

    def compute_reward(self, achieved_goal, desired_goal, info) -> np.ndarray | float:
        d = np.linalg.norm(np.asarray(achieved_goal, dtype=np.float64) - np.asarray(desired_goal, dtype=np.float64),
                           axis=-1)  # fmt: skip
        r = -(d > self.distance_threshold).astype(np.float32)
        return float(r) if np.ndim(r) == 0 else r

    def _format_obs(self, obs: np.ndarray):
        return {
            "observation": obs.astype(np.float32),
            "achieved_goal": (obs[7:10] + obs[0:3]).astype(np.float32),
            "desired_goal": self._goal.astype(np.float32),
        }

    def _info(self, obs: np.ndarray, *, diverged: bool, clipped: bool) -> dict[str, Any]:
        info = super()._info(obs, diverged=diverged, clipped=clipped)
        # Success is exactly "compute_reward gives 0" on the goals the agent sees, so relabelled
        # (HER) and online rewards agree.
        fo = self._format_obs(obs)
        info["is_success"] = (not diverged) and self.compute_reward(fo["achieved_goal"], fo["desired_goal"], info) == 0.0
        return info

    def _final_reward(self, obs: np.ndarray, info: dict[str, Any], reward: float) -> float:
        if info["diverged"]:
            return -1.0
        fo = self._format_obs(obs)
        return float(self.compute_reward(fo["achieved_goal"], fo["desired_goal"], info))


def _with_friction_scale(cfg: SceneConfig, scale: float) -> SceneConfig:
    """``cfg`` with every friction coefficient (the tissue's static and kinetic, the ground's)
    scaled by ``scale``: the one place the env's ``friction_range`` / ``friction_scale`` acts."""
    tissue = replace(cfg.tissue, friction_static=cfg.tissue.friction_static * scale,
                     friction_dynamic=cfg.tissue.friction_dynamic * scale)  # fmt: skip
    return replace(cfg, tissue=tissue, ground_friction=cfg.ground_friction * scale)


def _real(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def _option_value(name: str, value):
    """A reset option as the scene takes it: ``cylinder_xy`` / ``gripper_xy`` two finite numbers
    (a tuple), every other option one finite number; else a TypeError / ValueError naming it."""
    if name in ("cylinder_xy", "gripper_xy"):
        if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__len__") or len(value) != 2 \
                or not all(_real(x) for x in value):  # fmt: skip
            raise TypeError(f"reset option {name!r} must be two numbers (x, y) in m, got {value!r}")
        out = tuple(float(x) for x in value)
        if not all(math.isfinite(x) for x in out):
            raise ValueError(f"reset option {name!r} must be finite, got {value!r}")
        return out
    if not _real(value):
        raise TypeError(f"reset option {name!r} must be a number, got {type(value).__name__}: {value!r}")
    if not math.isfinite(float(value)):
        raise ValueError(f"reset option {name!r} must be finite, got {value!r}")
    return float(value)


def _check(name: str, value: float, lo: float, hi: float, *, lo_open: bool = False) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    if (value <= lo if lo_open else value < lo) or value > hi:
        raise ValueError(f"{name} must be in {'(' if lo_open else '['}{lo}, {hi}], got {value!r}")
