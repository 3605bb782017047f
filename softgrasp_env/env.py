"""Gymnasium environments: two fingers pick up a cylinder. A thin composition of the scene
(softgrasp_env/scene/), a finger kind (softgrasp_env/fingers/) and a task (softgrasp_env/tasks/),
made from ``gym.make``'s keywords by softgrasp_env/arguments.py. The class docstrings are the env
cards; ``softgrasp_env/registration.py`` lists the registered ids; the package's documentation
(Architecture) follows one step through it all.
"""

from __future__ import annotations

import math
import os
import sys
from dataclasses import replace
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from ._jit_cache import ensure_compiled
from .arguments import EnvArguments, EnvPlan, GoalConfig, argument_table, check_reset_options
from .observation import CARRY_OBS_NAMES, OBS_GROUPS, OBS_NAMES, Reading, privileged, read
from .scene import GraspScene
from .sim.world import SimulationDiverged
from .tasks import GoalTask, Outcome
from .tasks.goal import DISTANCE_THRESHOLD, GOAL_HEIGHT_RANGE

OBS_BOUNDS: dict[str, tuple[float, float]] = {
    "cyl_axis": (-1.0, 1.0),  # a unit vector's components, from a unit quaternion
    "force": (0.0, np.inf),  # normal forces only push (pybullet's normalForce, the tissue's lambda >= 0)
    "gripper_yaw": (-np.pi, np.pi),  # atan2
    "time": (0.0, np.inf),
    "shape_kind": (0.0, 1.0),  # one-hot
    "shape_extent": (0.0, np.inf),
}
"""The observation groups whose bounds hold whatever happens; every other entry is unbounded.
Not bounded though they look it: ``finger_gap`` (pybullet's joint limits are soft: 1.2e-8 m past
fully open was measured, so ``[0, 2 * finger_stroke]`` would not contain every observation),
``lift`` (a cylinder pushed into the ground goes below its resting height), the grip point and the
cylinder (the arm's target is kept in the workspace, the palm and a thrown cylinder are not)."""


def observation_box(names: tuple[str, ...]) -> spaces.Box:
    """The Box of an observation of ``names``: the bounds of :data:`OBS_BOUNDS`, else infinite."""
    group_of = {n: g for g, members in OBS_GROUPS.items() for n in members}  # the taxels are in none
    low = np.array([OBS_BOUNDS.get(group_of.get(n), (-np.inf, np.inf))[0] for n in names])
    high = np.array([OBS_BOUNDS.get(group_of.get(n), (-np.inf, np.inf))[1] for n in names])
    return spaces.Box(low.astype(np.float32), high.astype(np.float32), dtype=np.float32)


def _display_available() -> bool:
    if sys.platform.startswith("linux"):
        return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    return True


class SoftGraspEnv(gym.Env):
    """Two fingers pick up a cylinder and hold it while the arm carries it: soft fingers, each a
    rigid core wrapped in oriented-particle tissue (``SoftGrasp-v5``, solved globally;
    ``SoftGrasp-v4``, swept group by group; the thesis' shape matching with ``TISSUE_V3``'s
    keywords), or the same cores touching the cylinder through pybullet's rigid contacts
    (``SoftGraspRigid-v3``; with the torsional friction of the tissue's contact patch,
    ``SoftGraspRigidTorsion-v3``). Older versions live in the release that last registered them
    (Version history).

    ## Description
    A gripper hangs above a cylinder (radius 3 cm, height 10 cm, 0.1 kg) standing on the ground.
    The gripper is a palm pulled by a force-limited arm (40 N) along a smooth path (at most
    0.15 m/s and 1.5 m/s^2, the same at every dt) and two finger cores that close along the palm's
    x axis, each driven by a force-limited motor (3 N): squeezing is a force, not a teleport. The
    finger surface has one friction coefficient, mu 0.9, for every finger kind. The task is to
    reach the cylinder, close on it, lift it at least 5 cm and keep it through the carry test, the
    episode's last 1.5 s, in which the arm sways it as a transport would: per episode a sway of
    1.2-3.0 Hz (around the two-point grasp's ~1.9 Hz pendulum frequency), 0.5-1.0 m/s^2 peak, in
    any horizontal direction. The gripper starts above the cylinder's top and
    4-14 cm away from the origin, the cylinder anywhere within 7 cm of it, and the fingers are
    only approximately aligned (thesis: "only approximate orientation of the fingers relative to
    the object"): a jaw wedge, a yaw and a lateral offset. Physics runs at 240 Hz; one env step
    holds the action for ``240 / control_frequency`` physics steps. The package's documentation
    (Results: the env's design, measured) has the measurements behind these choices.

    ``object=`` grasps another shape instead of the cylinder, or draws one per episode from a list
    (a sphere, a cube, a slab, a capsule, a cone, a rod, an elliptic cylinder, convex pebbles: the
    documentation's Objects page); the observation then describes it (``observe_shape``).

    ## Action space
    ``Box(-1, 1, (4,), float32)``:

    | index | meaning | scaling |
    |---|---|---|
    | 0, 1, 2 | palm velocity x, y, z (world frame; ignored during the carry test) | ``a * arm_speed`` m/s (0.15 at full action; the vector capped at that speed), reached with the arm's acceleration limit ``arm_acceleration`` |
    | 3 | finger closing | target travel ``(a + 1) / 2 * travel`` from fully open: -1 fully open, +1 closed to the stop, where the pads meet; the force limit sets the squeeze. With ``finger_action="force"``: the squeeze itself, ``(a + 1) / 2 * finger_force`` N, the fingers closing until they meet resistance (they never open) |

    The arm brakes before the workspace's walls (x, y within ±15 cm of the origin, fingertip
    height between just above the ground and 20 cm) and waits for a palm that is blocked 2 cm
    behind it. Peak palm acceleration under any action sequence, at every physics step: 1.5 m/s^2
    (the package's tests bound it by 2).
    Out-of-range actions are clipped to [-1, 1] and ``info["action_clipped"]`` says so; a NaN/inf
    action or one of the wrong shape raises ``ValueError``, one that is not real numbers
    ``TypeError``.

    ## Observation space
    ``Box(low, high, (24,), float32)`` (23 without the carry test, the Easy ids; the grip ids, with
    ``observe_object=False``, leave out the cylinder's rows 7-18 and 21 and add their taxels: 171),
    SI units, world frame (z up); ``env.obs_names`` names the entries, ``softgrasp_env.observation.obs_slice``
    finds a group. The bounds are finite where they hold whatever happens - the cylinder axis in
    [-1, 1], the forces and the time at least 0, the yaw in [-π, π] - and infinite elsewhere
    (``softgrasp_env.env.OBS_BOUNDS`` says why the others are not bounded):

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
    | then | shape_<kind> | only with ``observe_shape`` (on when ``object=`` or ``object_scale_range`` is given): the object's kind, one-hot over cylinder, sphere, box, capsule, cone, elliptic, hull |
    | then | shape_extent_x/y/z | only with ``observe_shape``: the object's half extents at rest (half its bounding box) [m] |
    | then | tactile_<left/right>_r<row>_c<col>_<channel> | only with ``tactile=(rows, cols)``: each pad's taxels over its core's inner face, row 0 at the top, columns from -y to +y, five channels per taxel - pressure, traction_y, traction_z [Pa] and the tissue's shear_y, shear_z [m] (0 for rigid pads; core frame); ``softgrasp_env.observation.tactile_view`` gives the (2, rows, cols, 5) grid; unbounded |
    | then | tactile_past<d>_<left/right>_r<row>_c<col>_<channel> | only with ``tactile_history=k`` > 1 (the grip ids' v5: 3): the taxels of d env steps before, d = 1 .. k - 1, as above (a new episode's first observation repeats its own); ``softgrasp_env.observation.tactile_frames`` gives the (k, 2, rows, cols, 5) frames; unbounded |

    The forces are reported, not capped: the arm (40 N) can press a finger onto
    the cylinder far harder than the motors squeeze.

    ## Rewards
    ``reward_type="dense"`` (default): ``lift + reach``, ``lift = clip(lift_height /
    success_height, 0, 1)`` (1 once the cylinder is 5 cm up) and ``reach = -reach_weight *
    min(d, 0.1 m) / 0.1 m`` with ``d`` the grip point's distance to the cylinder centre; both terms
    are in ``info["reward_terms"]``. ``reward_type="sparse"`` (``SoftGraspSparse-v5``): 1 on steps
    where ``info["held"]``, else 0. The grip ids add a squeeze term (Grip-force task).

    ## Starting state
    ``start="reach"``: fingers fully open, the fingertips 2 cm above the cylinder's top, the grip
    point uniformly over the annulus ``approach_range`` (4-14 cm) around the origin; the cylinder
    at U(±cylinder_position_range) (7 cm) in x and y; a jaw wedge U(±jaw_wedge_range) (0.15 rad;
    positive opens the gap at the top) and a yaw U(±yaw_range) (π/4); the palm offset along the
    faces by U(±lateral_offset_range). ``start="easy"`` (the Easy ids): the open fingers around the
    cylinder's top over the origin, no wedge, yaw U(±5°), the cylinder at U(±1 cm). Friction,
    cylinder radius and mass are randomised too if their ranges are non-zero (the grip ids, on the
    easy start: mass 0.17 kg × U(1 ± 0.75), every friction × U(1 ± 0.45), neither observed: the
    least force that holds spans 0.16-3.0 N). Every draw comes from
    the env's ``np_random``; ``reset(options=...)`` fixes any of them (``cylinder_xy``,
    ``lateral_offset``, ``yaw``, ``jaw_wedge``, ``friction_scale``, ``cylinder_radius``,
    ``cylinder_mass``, ``gripper_xy``; with the carry test also ``carry_frequency`` [Hz],
    ``carry_acceleration`` [m/s^2] and ``carry_direction`` [rad from across the jaw], each checked
    against the arm's limits).

    ## Episode end
    - ``info["is_success"]``: ``info["held"]`` - lifted ≥ ``success_height``, both fingers pressing
      (≥ 0.05 N each), tilted no more than ``max_tilt`` - and, with the carry test, the carry over
      (``info["carrying"]`` while it runs) with the cylinder held at every env step of it and its
      in-hand slide at most ``carry_slide_limit`` (5 mm). The grip ids also bound the squeeze
      (Grip-force task).
    - Terminated: the cylinder tilts more than ``max_tilt`` (knocked over), leaves the workspace
      (more than 15 cm from the origin horizontally, below the ground or above 50 cm), or the
      simulation diverges (non-finite numbers, a body faster than 20 m/s, tissue torn more than
      3 cm from its core, a finger segment turning faster than 90 rad/s): then
      ``info["diverged"]`` is True and ``info["divergence"]`` says why, the reward is 0 (the goal
      ids: -1, their failure reward) and the observation the last finite one, never a NaN.
    - Truncated: by the registered time limit (100 steps = 5 s at 20 Hz).

    ## Arguments
    ``gym.make("SoftGrasp-v4", **kwargs)``, every one keyword-only but ``render_mode``
    (softgrasp_env/arguments.py checks them all; a bad value or a combination that would not run
    is a ``ValueError`` naming it and the limit):

    <arguments>

    Deprecated spellings that keep working with a ``DeprecationWarning``: ``soft=True/False``
    (``fingers="tissue"/"rigid"``), ``tissue_density=`` (``particle_density=``), ``gripper_speed=``
    (``arm_speed=``), ``friction_dynamic=`` (``friction_kinetic=``), ``task=`` (``start=``), and the only
    choice left of an argument removed after 0.6.0 (``arm="smooth"``,
    ``tissue_material="compliant"``, ``carry_direction="any"``). Its retired choices
    (``arm="jump"``, ``tissue_material="per_step"``, ``carry_direction="across"``,
    ``carry_amplitude=``, ``carry_slide_limit=None``) are a ``ValueError`` naming release 0.6.0,
    which has them.

    ## The tissue and its resolution
    The soft ids' v4 tissue (``registration.TISSUE_V4``) is a material that means the same at every
    resolution: each particle group's energy is the continuum's, ``G V ||F - R||^2`` (F the group's
    least-squares deformation gradient, G = 4,000 Pa the shear modulus; Poisson's ratio 0), with
    hourglass control, and Coulomb's law holds in every contact's own cone (mu_s = mu_k = 0.9 by
    default), each contact sticking or sliding on its own, so the strip's edges slide before its
    centre. The v3 ids keep the thesis' shape matching, whose stiffness changes with the particle
    density, and a friction law per pad patch, which lets the patch's self-equilibrated friction
    grow without bound. The resolution is the ``preset``: the default (4,000 particles per m² of
    core face, one element layer) is the cheapest; ``preset="fine"`` (16,000 per m²) and
    ``preset="converged"`` (64,000 per m², two layers) are the same material refined. Against a
    finite-element model of the pad (pressed by a rigid 3 cm cylinder) and Coulomb's law, the
    default's errors beside the converged pad's:

    | row | reference | default | fine | converged |
    |---|---|---|---|---|
    | compression under 1 / 3 / 6 N | 1.34 / 2.87 / 4.60 mm | -1 / -24 / -24 % | -2 / -4 / -2 % | +2 / -0 / -1 % |
    | contact strip's RMS half-width, 3 N | 5.56 mm | +78 % | +13 % | +7 % |
    | tangential compliance, 2-4 N (mean) | 1.2-1.5 mm/N | -34 % | +1 % | +1 % |
    | first contact / whole strip slides at Q / mu P | 0 / 1 | 0.55 / 1.03 | 0.04 / 1.02 | 0.04 / 1.02 |
    | share of the normal load sticking at Q / mu P 0.5 / 0.9 | 0.85 / 0.42 | 1.00 / 0.51 | 0.97 / 0.47 | 0.96 / 0.46 |
    | heaviest cylinder held, over Coulomb's | 1 | 1.05 | 1.04 | 1.05 |
    | squeeze at which a grip lowered from 4 N lets go, over Coulomb's least | 1 | 1.00-1.19 | 1.02-1.18 | 1.02-1.16 |
    | env steps/s (SoftGraspEasy, random actions) | | 102 | 47 | 6.2 |

    The last row was measured on one core of an Intel Xeon (2 cores, AVX-512), the other free; the
    grip-lowering row over five grip-force episodes (seeds 1000-1003, 1013; the
    squeeze falls 10 % every other step, so a drop lands up to about 1.1 times late); the stick
    share's reference is the finite-element pad with Coulomb's law at every node. At the default,
    the pad is too coarse for the strip (three particle columns across it): it is stiffer than the
    continuum under load and in shear, and slides as one until about half its slip load, where
    the continuum's edges have already let 15 % of the load slip. The package's documentation
    (Results: convergence in space) has every row at every level, with its observed order.

    ``threads=2`` runs each pad on a thread of its own, with the same result to the bit: x1.3-1.4
    env steps/s at ``converged`` and x1.6 at 256,000 per m² on two cores of the same Intel Xeon
    (the tissue kernel alone x1.6 at ``converged``: pybullet, contacts and friction stay serial). No run tore: 10^5 env steps of
    uniform random actions and 10^5 of the noisy scripted grasp at the default, and 10^4 of each
    at ``converged`` (the package's documentation: Finger kinds, the tissue's settings).

    ## Grip-force task
    The grip ids (``SoftGraspGrip-v7``, ``SoftGraspGripRigid-v5``, ``SoftGraspGripRigidTorsion-v5``;
    the versions before: ``SoftGraspGrip-v6``, ``SoftGraspGripRigid-v4``, ``SoftGraspGripRigidTorsion-v4``)
    ask for the least squeeze that holds. They take the easy start with the carry test; the
    action's last entry is the squeeze itself (``finger_action="force"``, up to ``finger_force`` =
    6 N); the cylinder's mass (0.17 kg × U(1 ± 0.75)) and every friction (× U(1 ± 0.45)) are drawn
    per episode and not observed, so the least force that holds spans 0.16-3.0 N; the observation
    leaves out the cylinder (``observe_object=False``) and adds a 4 × 4 taxel grid on each pad
    (``tactile=(4, 4)``). The reward adds a squeeze charge, its own term in
    ``info["reward_terms"]``, on the carry's steps alone: on v6 (the rigid kinds' v5) ``squeeze =
    -max(0, mean(force_left, force_right) / F_least - 1)`` with ``F_least = m g / (2 mu_s)`` of the
    episode's cylinder (``squeeze_reference="least"``, ``squeeze_charge_steps="carry"``,
    ``squeeze_free=1``, ``squeeze_weight=1``): the margin over the least, the same on a light
    cylinder as on a heavy one, and nothing for the closing and the lift, so carrying through pays
    more than letting go. The observation keeps the taxels of the last three env steps
    (``tactile_history=3``: a slip is a change, one frame does not show it). Over constant grips the
    expected return is highest from 1.2 to 1.5 times the least on the tissue (the package's
    documentation: where the grip reward peaks). The versions before (v5, the rigid kinds' v4)
    charge ``0.3 * mean(force_left, force_right) / F_least`` on every step, under which a hand held
    open returns more than a carried grasp on the rigid twin. Success also needs the carry's mean squeeze ``info["carry_squeeze"]``
    at most ``squeeze_factor`` (2) times ``info["least_squeeze"]``, the least force per finger that
    holds this cylinder through this carry: Coulomb, ``m max|a - g| / (2 mu_s)`` across the jaw axis
    with the cylinder's accelerations over each env step of the carry (both 0 before it;
    :mod:`softgrasp_env.tasks.grip`). :mod:`softgrasp_env.policies.grip` has tactile scripted
    policies (``grip_script(env)`` picks the fingers' better one: on tissue pads the script that
    feels slip coming in the pads' shear) and a force-blind one.

    ## Object set
    The object-set ids draw what is grasped per episode from eleven objects, each as likely: the
    cylinder, a 6 mm rod, a 3 cm sphere, a 5 cm cube, a 2.5 cm slab, a capsule lying along the
    faces, a cone frustum, an elliptic cylinder and three convex pebbles
    (``softgrasp_env.registration.OBJECT_SET``; the documentation's Objects page). On the carry
    task (``SoftGraspObjects-v1`` on the tissue, ``SoftGraspObjectsRigid-v1``,
    ``SoftGraspObjectsRigidTorsion-v1``) each object's size is drawn too (every dimension × U(1 ±
    0.15), ``object_scale_range``), its mass (0.1 kg × U(1 ± 0.5)) and every friction (× U(1 ±
    0.2)). The grip-force variants (``SoftGraspObjectsGrip-v2``, ``SoftGraspObjectsGripRigid-v2``,
    ``SoftGraspObjectsGripRigidTorsion-v2``, with the grip ids' latest charge; their v1 with the
    first) are the grip-force task on every object at its own size: the gentle start's open fingers leave the cone and the elliptic cylinder about a
    millimetre. The observation adds the object's kind one-hot and its half extents
    (``observe_shape``), which is all a policy is told of it; ``info["object"]`` names it and the
    reset option ``object_scale`` fixes its size. The scripted grasp (``ScriptedGraspPolicy``)
    carries every object 10 times in 10 seeds on the tissue, and 59 of 110 on the bare rigid
    fingers; on the grip-force variants the tactile grip (``TactileGripPolicy``, made for the
    cylinder) holds 86 of 110 on the tissue, 40 of them within twice the least squeeze (the
    documentation's Objects page has the tables per object). The torsional peer of this family
    takes its lever from the tissue's own patch on each object, following the load
    (``TorsionalRigidConfig(spinning_friction="patch")``), where the other torsional ids keep
    the cylinder's 16.7 mm.

    ## Rendering
    ``render_mode="rgb_array"`` draws the scene with pybullet's CPU renderer in a viewer server of
    its own (every finger kind's bodies: cores, tissue particles, segments, FEM pad nodes), with
    shadows, on a checkerboard ground of 5 cm squares, headless; ``render_mode="human"`` runs the
    simulation in the pybullet GUI (needs a display; without one it is a ``ValueError`` and
    ``metadata["render_modes"]`` lists only ``rgb_array``). The camera follows the gripper and the
    cylinder (``render_camera="follow"``) or looks at the cylinder's start (``"fixed"``);
    ``camera_distance``, ``camera_yaw``, ``camera_pitch`` and ``camera_target`` set it.
    ``gymnasium.wrappers.RecordVideo`` writes videos of ``rgb_array`` frames with moviepy (the
    ``[video]`` extra).

    ## Determinism and copies
    Reset rebuilds the simulation (pybullet's restoreState is not bit-exact), so two envs with the
    same seed and actions give bit-identical trajectories. Pickling or deep-copying an env records
    its reset draw and the actions since its last reset, and the copy replays them: exact, at the
    cost of re-simulating that episode (bounded by the time limit: 0.54 s soft, 0.29 s rigid at
    step 99).

    ## Version history
    - v5 (the soft ids; the goal id's v6, the grip id's v7, the object set's v2 and its grip id's
      v3): the v4 tissue with its material solved across all of its groups at once each pass
      (``material_solve="global"``: a quasi-Newton step of the implicit step with the material's
      stiffness at rest, prefactored once) in place of a Gauss-Seidel sweep over them. The same material and contact law (the spatial convergence
      table's rows within the sweep's own spread), nearer the converged implicit step in the same
      three passes, and the world in the coupling's steps alone (2 a physics step at the default
      density where the sweep takes 6): about twice the speed. The thesis tissue's v3 (and the
      goal's v4) was retired after 0.8.0: the v4 ids with ``TISSUE_V3``'s keywords are it, step
      for step.
    - v6 of SoftGraspGrip (v5 of its rigid kinds): only the carry's steps pay the squeeze charge,
      for the margin over the least force alone (``squeeze_charge_steps="carry"``,
      ``squeeze_free=1``, weight 1), under which carrying through pays more than letting go. The
      soft grip's v5 was retired after 0.8.0.
    - v5 of SoftGraspGrip (v4 of its rigid kinds): the squeeze charged in least forces
      (``squeeze_reference="least"``, weight 0.3) and three taxel frames in the observation
      (``tactile_history=3``); the physics is v4's (and v3's for the rigid kinds).
    - v4 (the soft ids; the goal id's v5): the v3 task on the v4 tissue - the continuum group
      energy with hourglass control, Coulomb's law per contact, element layers as thick as the
      particle spacing (The tissue and its resolution). The rigid kinds have no tissue and stay v3.
    - v3: the smooth arm and velocity actions, 40 N; the carry test
      drawn per episode over a band and success held through it; the tissue's mu_k = mu_s (one
      friction law for every kind); the torsional rigid peer. Since 0.5.0 the tissue is the
      compliant material (a shear modulus in Pa, the pad compressing ~4.4 mm under 3 N at every dt,
      a 2 cm strain limit) and the peer's lever is its patch's 16.7 mm; 0.4.0's v3 (the per-step
      material, 17.7 mm) replays bit for bit in release 0.6.0.
    - v2: the carry test (the soft, rigid and sparse ids; the observation gains the time); the jump
      arm (the action moved a target the palm's constraint chased), 200 N, a 1 cm / 2 Hz carry
      across the jaw with success at its end, mu_k 0.7 and the per-step material. Retired after
      0.6.0 (``pip install softgrasp-env==0.6.0`` reproduces it, and v1).
    - v1: the reach task for every id; the gentle start as the Easy ids; the contact-face tissue
      preset (4,000 particles per m²). Retired after 0.6.0.
    - v0: initial release (gone: its physics cannot be reproduced by this code).
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 20}

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        self._init_kwargs = {"render_mode": render_mode, **kwargs}
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']} or None, got {render_mode!r}")
        if render_mode == "human" and not _display_available():
            raise ValueError("render_mode='human' opens the pybullet GUI and needs a display (DISPLAY is not set); "
                             "use render_mode='rgb_array' headless")  # fmt: skip
        self.args = args = EnvArguments.from_kwargs(**kwargs)
        """The validated arguments, grouped into configs (softgrasp_env.arguments)."""
        self.plan = plan = EnvPlan.of(args)
        """What the env is made of, derived from the arguments: the base scene, the physics steps per
        env step, the observation's names, the taxel grid."""
        self.task = self._make_task(plan)
        self.actions = plan.make_actions()
        self.render_mode = render_mode
        self.fingers = args.physics.fingers.kind
        self.soft = plan.scene.soft
        self.carry = bool(args.carry_test.on)
        self.control_frequency = float(args.control.frequency)
        self.obs_names = plan.obs_names
        """The observation's entries, in order (``OBS_NAMES``, and ``time`` with the carry test)."""
        # info["object"] names the episode's object wherever one is given or drawn
        self._names_object = bool(args.ranges.objects or args.ranges.object_scale or plan.scene.object is not None
                                  or plan.scene.object_name != "cylinder")  # fmt: skip
        # The instance lists the render modes that work where it runs: without a display the GUI
        # cannot open (pybullet would end the process), so checkers must not try "human" there.
        modes = [m for m in type(self).metadata["render_modes"] if m != "human" or _display_available()]
        self.metadata = {**type(self).metadata, "render_modes": modes, "render_fps": self.control_frequency}
        self.action_space = spaces.Box(-1.0, 1.0, shape=(4,), dtype=np.float32)
        self.observation_space = observation_box(self.obs_names)
        self.scene: GraspScene | None = None
        self._renderer = None
        self._forces = np.zeros(2)
        self._taxel_frames: np.ndarray | None = None
        """(tactile_history, 2, rows, cols, channels) the last taxel frames, this env step's first."""
        self._last: Reading | None = None
        self._reset_record: tuple[dict, dict] | None = None
        self._actions: list[np.ndarray] = []
        self._episode_over, self._divergence = False, None
        # A cold numba cache compiles here, with a line before and after, not silently in the
        # first reset and step (about a minute); a warm one costs a scene build, once per process.
        ensure_compiled(plan.scene)

    def _make_task(self, plan: EnvPlan):
        return plan.make_task()

    # --- gym API -----------------------------------------------------------------------------------

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = check_reset_options(options, self.task.reset_options)
        # What a copy needs to rebuild this episode exactly: the generator before the draws.
        self._reset_record = (self.np_random.bit_generator.state, options)
        self._actions = []
        self._build(options)
        reading = self._last = self._read()
        self._episode_over, self._divergence = False, None
        if self.render_mode == "human":
            self.render()
        return self._format_obs(reading), self._info(reading, self.task.evaluate(reading, self.scene), clipped=False)

    def step(self, action):
        if self.scene is None:
            raise RuntimeError("call reset() before step()")
        act, clipped = self._check_action(action)
        self._actions.append(act.copy())
        if self._simulate(act):
            reading, outcome = self._last, None
        else:
            reading = self._last = self._read()
            outcome = self.task.evaluate(reading, self.scene)
        info = self._info(reading, outcome, clipped=clipped)
        info["reward_terms"] = dict.fromkeys(self.task.reward_terms, 0.0) if outcome is None else dict(outcome.terms)
        if self.render_mode == "human":
            self.render()
        reward = self.task.diverged_reward if outcome is None else outcome.reward
        terminated = True if outcome is None else outcome.terminated
        return self._format_obs(reading), float(reward), terminated, False, info

    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() called with render_mode=None; pass render_mode='rgb_array' or 'human' to make")
            return None
        if self.scene is None:
            raise RuntimeError("call reset() before render()")
        from .render import Camera, SceneRenderer

        if self._renderer is None:
            c = self.args.camera
            camera = Camera(c.mode, c.distance, c.yaw, c.pitch, c.target)
            self._renderer = SceneRenderer(c.width, c.height, human=self.render_mode == "human", camera=camera)
        return self._renderer.render(self.scene)

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        if self.scene is not None:
            self.scene.close()
            self.scene = None

    # --- one env step ------------------------------------------------------------------------------

    @staticmethod
    def _check_action(action) -> tuple[np.ndarray, bool]:
        raw = np.asarray(action)
        if raw.dtype.kind not in "biuf":  # complex (numpy would drop the imaginary part), text, None
            raise TypeError(f"action must be real numbers, got dtype {raw.dtype} ({action!r})")
        act = raw.astype(np.float64)
        if act.shape != (4,):
            raise ValueError(f"action must have shape (4,), got {act.shape}")
        # four numbers: checked and clipped in Python floats (numpy's reductions cost ~1 us each)
        vals = act.tolist()
        if not all(map(math.isfinite, vals)):
            raise ValueError(f"action must be finite, got {vals}")
        clipped = False
        for k, v in enumerate(vals):
            if v < -1.0 or v > 1.0:
                clipped = True
                act[k] = -1.0 if v < -1.0 else 1.0
        return act, clipped

    def _build(self, options: dict[str, Any]) -> None:
        """The episode's scene: the task's draw, built (in the same physics server after the first
        reset), and the task told it begins."""
        cfg = self.task.draw(self.np_random, options, self.plan.scene)
        client = None if self.scene is None else self.scene.client
        self.scene = GraspScene(cfg, gui=self.render_mode == "human", client=client)
        if self._renderer is not None:
            self._renderer.invalidate()
        self._forces = np.zeros(2)
        self._taxel_frames = None  # a new episode's first reading fills them (_read)
        self.task.begin(self.scene, self.np_random)

    def _simulate(self, act: np.ndarray) -> bool:
        """The action as the gripper's control, then one control interval of physics steps, the
        task steering each; True if the simulation diverged."""
        if self._episode_over:
            # Stepping on after a divergence: the bodies are poisoned; nothing more is simulated.
            return True
        sc = self.scene
        control = self.actions.control(act, sc)
        left = right = 0.0  # the sums a zeros(2) += forces would make, in Python floats
        steer, step, finger_forces = self.task.steer, sc.step, sc.finger_forces
        try:
            for _ in range(self.plan.substeps):
                step(steer(sc, control))
                f = finger_forces()
                left += float(f[0])
                right += float(f[1])
        except SimulationDiverged:
            self._episode_over, self._divergence = True, "non-finite tissue solve"
            return True
        self._forces = np.array([left, right]) / self.plan.substeps
        self._divergence = sc.divergence()
        if self._divergence is not None:
            self._episode_over = True
            return True
        return False

    def privileged_state(self) -> np.ndarray:
        """The scene's state at the last observation that a gripper's own sensors do not give,
        float64 in the order of ``softgrasp_env.observation.PRIVILEGED_NAMES``: the object's pose
        and motion, its mass [kg] and the finger surface's friction coefficients as this episode
        drew them. For a critic that learns from what the simulator knows while the actor reads
        only the observation (``softgrasp_env.wrappers.PrivilegedObservation``); after a diverged
        step, the last finite reading's."""
        if self.scene is None:
            raise RuntimeError("call reset() before privileged_state()")
        return privileged(self._last, self.scene.config)

    def _read(self) -> Reading:
        """The scene now; with ``tactile_history`` k > 1 the reading carries the k - 1 taxel frames
        before it (each env step reads once: reset, every step that did not diverge, and the replay
        of a copy, so the frames follow the env steps)."""
        reading = read(self.scene, self._forces, self.plan.taxel_grid)
        frames = self.args.observation.tactile_history
        if frames > 1:
            if self._taxel_frames is None:  # an episode's first frame stands for the ones before it
                self._taxel_frames = np.repeat(reading.tactile[None], frames, axis=0)
            else:
                self._taxel_frames = np.concatenate((reading.tactile[None], self._taxel_frames[:-1]))
            reading = replace(reading, tactile_past=self._taxel_frames[1:].copy())
        return reading

    def _info(self, reading: Reading, outcome: Outcome | None, *, clipped: bool) -> dict[str, Any]:
        """``outcome`` None: the step diverged (nothing held, no reward, the last finite reading)."""
        diverged = outcome is None
        info = {
            "is_success": (not diverged) and outcome.success,
            "held": (not diverged) and outcome.held,
            "carrying": self.task.carrying(self.scene.steps),
            "lift_height": float(reading.lift),
            "diverged": diverged,
            "divergence": self._divergence if diverged else None,
            "action_clipped": clipped,
        }
        if self._names_object:
            info["object"] = self.scene.config.object_name
        if self.task.info_keys:  # the task's measurements (0 on a diverged step: infos compare by equality)
            info.update(dict.fromkeys(self.task.info_keys, 0.0) if diverged else outcome.info)
        return info

    def _format_obs(self, reading: Reading):
        return reading.vector(self.obs_names).astype(np.float32)

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
            self._last = self._read()
            for a in state["actions"]:
                self._actions.append(a.copy())
                if self._simulate(a):
                    break
                self._last = self._read()
        if state["np_random"] is not None:
            self._np_random = np.random.Generator(np.random.PCG64())
            self._np_random.bit_generator.state = state["np_random"]
        self._np_random_seed = state["np_random_seed"]


class SoftGraspGoalEnv(SoftGraspEnv):
    """Goal-conditioned SoftGrasp (``SoftGraspGoal-v6``, ``-v5``) for hindsight experience replay.

    ## Description
    As :class:`SoftGraspEnv` - the same actions, physics, starting state and time limit, with soft
    fingers - but with the goal task (:mod:`softgrasp_env.tasks.goal`) and no carry test: bring the
    cylinder centre to a goal above the cylinder's start. HER relabels goals alone, so reward and
    success are the goal's and nothing else (a time-bound test would break the relabelling).

    ## Action space
    As SoftGraspEnv's.

    ## Observation space
    ``Dict(observation=Box(23), achieved_goal=Box(3), desired_goal=Box(3))``: ``observation`` is
    SoftGraspEnv's vector without the carry test's time, ``achieved_goal`` the cylinder centre [m],
    ``desired_goal`` the target for it [m].

    ## Rewards
    ``compute_reward(achieved_goal, desired_goal, info)``: -1 while the cylinder centre is farther
    than ``distance_threshold`` (2 cm) from the goal, else 0, vectorised over leading batch
    dimensions (as HER needs); -1 on a diverged step. ``info["is_success"]`` is exactly
    ``compute_reward(...) == 0``.

    ## Starting state
    As SoftGraspEnv's (the reach start unless ``start=`` says otherwise); the goal is drawn with
    it, above the cylinder's start at its resting height plus U(goal_height_range) (default 5-8 cm).

    ## Episode end
    ``SoftGraspGoal-v6`` (``end_when_knocked_over=False``): only a physics failure ends an episode
    early - the cylinder below the ground or flung above the workspace, a diverged step; a
    knocked-over or pushed-away cylinder runs on to the time limit at -1 per step (an early end
    would pay less, and a learner would learn to end it). ``SoftGraspGoal-v3``
    (``end_when_knocked_over=True``) keeps the lift task's ends. Truncated by the time limit (100
    steps).

    ## Arguments
    SoftGraspEnv's, but ``reward_type`` (the reward is the goal's) and ``carry=True`` (no carry
    test), each a ``ValueError``; and its own: ``distance_threshold`` (0.02 m), ``goal_height_range``
    ((0.05, 0.08) m), ``end_when_knocked_over`` (False; True on ``SoftGraspGoal-v3``).

    ## Version history
    - v6: v5's goal on the soft ids' v5 physics (the v4 tissue solved globally).
    - v5: v4's goal on the v4 tissue.
    - v4: v3's physics and goal; a knocked-over or pushed-away cylinder no longer ends the episode
      (only a physics failure does). HER + SAC on v3 learned to topple the cylinder to end its
      episodes early; v4's episodes run to the time limit. Retired after 0.8.0 (v5 with
      ``TISSUE_V3``'s keywords is it, step for step).
    - v3: the v3 physics (SoftGraspEnv's v3) with the lift task's ends: a knocked-over cylinder or
      one that leaves the workspace ends the episode.
    - v1: retired after 0.6.0 (``pip install softgrasp-env==0.6.0`` reproduces it).
    """

    def __init__(self, render_mode: str | None = None, *, distance_threshold: float = DISTANCE_THRESHOLD,
                 goal_height_range: tuple[float, float] = GOAL_HEIGHT_RANGE, end_when_knocked_over: bool = False,
                 **kwargs: Any) -> None:  # fmt: skip
        if "reward_type" in kwargs:
            raise ValueError("SoftGraspGoalEnv's reward is the goal reward (compute_reward); do not pass reward_type")
        if kwargs.get("carry"):
            raise ValueError("SoftGraspGoalEnv has no carry test (carry=True): its reward and success are the goal's "
                             "alone (compute_reward), which a time-bound test would break for HER's relabelling")  # fmt: skip
        goal = GoalConfig.of(distance_threshold=distance_threshold, goal_height_range=goal_height_range,
                             end_when_knocked_over=end_when_knocked_over)  # fmt: skip
        self._goal_kwargs = {"distance_threshold": goal.distance_threshold,
                             "goal_height_range": goal.goal_height_range,
                             "end_when_knocked_over": goal.end_when_knocked_over}  # fmt: skip
        super().__init__(render_mode, **{**kwargs, "carry": False, "reward_type": "sparse"})
        self._init_kwargs = {"render_mode": render_mode, **self._goal_kwargs, **kwargs}
        box = spaces.Box(-np.inf, np.inf, shape=(3,), dtype=np.float32)
        self.observation_space = spaces.Dict({
            "observation": observation_box(self.obs_names),
            "achieved_goal": box,
            "desired_goal": box,
        })  # fmt: skip

    def _make_task(self, plan: EnvPlan) -> GoalTask:
        return GoalTask(plan.make_task(), **self._goal_kwargs)

    @property
    def distance_threshold(self) -> float:
        return self.task.distance_threshold

    @property
    def goal_height_range(self) -> tuple[float, float]:
        return self.task.goal_height_range

    def compute_reward(self, achieved_goal, desired_goal, info) -> np.ndarray | float:
        return self.task.compute_reward(achieved_goal, desired_goal, info)

    def _format_obs(self, reading: Reading):
        return {
            "observation": reading.vector(self.obs_names).astype(np.float32),
            "achieved_goal": self.task.achieved_goal(reading).astype(np.float32),
            "desired_goal": self.task.goal.astype(np.float32),
        }


SoftGraspEnv.__doc__ = SoftGraspEnv.__doc__.replace("<arguments>", argument_table().replace("\n", "\n    "))

__all__ = ["CARRY_OBS_NAMES", "OBS_BOUNDS", "OBS_NAMES", "SoftGraspEnv", "SoftGraspGoalEnv", "observation_box"]
