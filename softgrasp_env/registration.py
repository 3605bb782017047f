"""The registered environment ids (``gym.make(id)`` after ``import softgrasp_env``)."""

from __future__ import annotations

import math

import gymnasium as gym
from gymnasium.envs.registration import WrapperSpec

from . import presets
from .fingers import TorsionalRigidConfig

MAX_EPISODE_STEPS = 100
"""5 s at the default 20 Hz control frequency."""

SQUEEZE_WEIGHT_LEAST = 0.3
"""The charge per env step of a squeeze of one least force (:data:`GRIP_TASK_LEAST`)."""
GRIP_TASK = {"finger_action": "force", "finger_force": 6.0, "cylinder_mass": 0.17, "cylinder_mass_range": 0.75,
             "friction_range": 0.45, "squeeze_weight": 0.5, "squeeze_factor": 2.0, "tactile": (4, 4),
             "observe_object": False}
"""The grip-force task's settings (softgrasp_env/tasks/grip.py): the squeeze as the action (0 to 6
N per finger), mass 0.04-0.30 kg and mu_s 0.50-1.31 drawn per episode (the least force that holds
spans 0.16-3.0 N, 18-fold), the squeeze charged in the reward and bounded at twice the least in the
success, a 4 x 4 taxel grid on each pad, and the cylinder's pose and motion left out of the
observation (a gripper's own sensors do not give them; the documentation's Tactile pads page says
what a learner does with them)."""
GRIP_TASK_LEAST: dict[str, object] = {**GRIP_TASK, "squeeze_reference": "least", "squeeze_weight": SQUEEZE_WEIGHT_LEAST,
                                      "tactile_history": 3}  # fmt: skip
"""The grip-force task of the rigid kinds' v4 (and of the retired SoftGraspGrip-v5): the squeeze
charged in least forces, ``SQUEEZE_WEIGHT_LEAST`` x F / (m g / (2 mu_s)) per env step, so a margin
costs the same on every cylinder, and the taxels of the last three env steps in the observation (a slip is a change:
one frame does not show it). Over constant grips the expected return peaks at 1.2-1.5 x the least
on the tissue, at 1.1 on the rigid kinds, which hold from there (the package's documentation,
Results: where the grip reward peaks). The charge is paid from the first step, though, and on the
rigid twin a hand held open returns more than a carried grasp: :data:`GRIP_TASK_CARRY` mends that."""
GRIP_TASK_CARRY: dict[str, object] = {**GRIP_TASK_LEAST, "squeeze_charge_steps": "carry", "squeeze_free": 1.0,
                                      "squeeze_weight": 1.0}  # fmt: skip
"""The grip-force task whose best policy is to carry the cylinder through on a grip just above the
least force (SoftGraspGrip-v7 and -v6, and the rigid kinds' v5): only the carry's steps pay, and they pay
for the margin over the least alone, ``max(0, F / (m g / (2 mu_s)) - 1)`` per env step (a grip at
1.2 x the least costs 0.2 a step against the lift's reward of at most 1). Under
:data:`GRIP_TASK_LEAST`'s charge, paid from the first step on the whole squeeze, the closing, the
probing and the lift cost more than the carry pays: on the rigid twin a hand held open returns
more than the grip script's successful grasps, and a learner is right to leave the cylinder alone.
Here carrying through pays 14-16 more than letting go when the carry begins, and over constant
grips the tissue's expected return still peaks at 1.2-1.5 x the least (the package's
documentation, Results: where the grip reward peaks, "What a learner compares")."""
_ENV, _GOAL = "softgrasp_env.env:SoftGraspEnv", "softgrasp_env.env:SoftGraspGoalEnv"

OBJECT_SET: tuple[str, ...] = ("cylinder", "rod", "sphere", "cube", "slab", "capsule", "cone", "elliptic", "pebble-0",
                               "pebble-1", "pebble-2")  # fmt: skip
"""The object-set ids' objects (softgrasp_env.scene.objects.PRESETS, all of them), one drawn per
episode, each as likely."""
OBJECTS_TASK: dict[str, object] = {"object": OBJECT_SET, "object_scale_range": 0.15, "cylinder_mass_range": 0.5,
                                   "friction_range": 0.2}  # fmt: skip
"""The object-set task's draws on top of the carry task's start: the object, its size x U(1 +-
0.15), its mass 0.05-0.15 kg, every friction coefficient x U(1 +- 0.2); the observation names its
kind and extents (``observe_shape``)."""
PATCH_TORSION = TorsionalRigidConfig(spinning_friction="patch")
"""The object-set ids' torsional peer: its lever the tissue's own patch on each object, following
the load (softgrasp_env.fingers.rigid.PATCH_LEVERS), not the cylinder's 16.7 mm."""
OBJECTS_GRIP_TASK: dict[str, object] = {"object": OBJECT_SET}
"""The object-set grip-force task: the grip-force task's draws (:data:`GRIP_TASK`: mass and friction)
on every object at its own size (the gentle start's open fingers leave the cone and the elliptic
cylinder about a millimetre: a larger one would not fit between them)."""

TISSUE_V4: dict[str, object] = dict(presets.TISSUE_V4)
"""The v4 tissue, as the soft ids' ``gym.make`` keywords (softgrasp_env.presets.TISSUE_V4): the
continuum group energy (a shear modulus that means the same pad at every particle density) with
hourglass control, Coulomb's law in every contact's own cone, and an element layer through the pad
about as thick as the particle spacing. The resolution stays the caller's (``preset=``,
``particle_density=``): ``preset="converged"`` is the cheapest pad whose rows of the package's
spatial convergence table are within 5 % of the finite-element reference and Coulomb's law (the
hold bound and the lowest friction within 10 %, as at every resolution measured; Results:
convergence in space)."""

TISSUE_GLOBAL: dict[str, object] = {**TISSUE_V4, "material_solve": "global"}
"""The soft ids' latest physics (SoftGrasp-v5 and its family), as ``gym.make`` keywords: the v4
tissue (:data:`TISSUE_V4`) with its material solved across all of its groups at once each pass
(``material_solve="global"``, softgrasp_env/tissue/global_step.py: a quasi-Newton step of the
implicit step with the material's stiffness at rest, prefactored once) in place of a Gauss-Seidel
sweep over the groups. The same material and the same contact law: the rows of the spatial convergence table
stay within the sweep's own spread at every density measured, while the pads come closer to the
converged implicit step in the same three passes (half the sweep's pose error at the default
density, a fifth at 4 x) and the world takes the coupling's steps alone, about twice the sweep's
speed (the package's documentation, Results: methods, speed against accuracy)."""

TISSUE_V3: dict[str, object] = {"group_energy": "shape_matching", "friction_law": "patch", "hourglass_stiffness": 0.0,
                                "layers": 1}  # fmt: skip
"""The thesis tissue as ``gym.make`` keywords over the v4 soft ids: shape matching with a stiffness
per group (Mueller & Chentanez 2011 sec. 4), one friction bound per patch, one element layer. With
them SoftGrasp-v4 (and its family's v4) is the retired SoftGrasp-v3 step for step, to the bit
(:data:`RETIRED_AS`)."""

_SPECS: dict[str, tuple[str, dict]] = {
    # the soft ids: v5 (the goal's v6, the grip's v7, the object set's v2 and its grip's v3) solve the
    # v4 tissue globally (TISSUE_GLOBAL); the version before, the same tissue swept group by group
    "SoftGrasp-v5": (_ENV, {"fingers": "tissue", "reward_type": "dense", "carry": True, **TISSUE_GLOBAL}),
    "SoftGrasp-v4": (_ENV, {"fingers": "tissue", "reward_type": "dense", "carry": True, **TISSUE_V4}),
    "SoftGraspRigid-v3": (_ENV, {"fingers": "rigid", "reward_type": "dense", "carry": True}),
    "SoftGraspSparse-v5": (_ENV, {"fingers": "tissue", "reward_type": "sparse", "carry": True, **TISSUE_GLOBAL}),
    "SoftGraspSparse-v4": (_ENV, {"fingers": "tissue", "reward_type": "sparse", "carry": True, **TISSUE_V4}),
    # a knocked-over cylinder does not end the goal's episode (tasks/goal.py says why)
    "SoftGraspGoal-v6": (_GOAL, {"fingers": "tissue", "end_when_knocked_over": False, **TISSUE_GLOBAL}),
    "SoftGraspGoal-v5": (_GOAL, {"fingers": "tissue", "end_when_knocked_over": False, **TISSUE_V4}),
    "SoftGraspEasy-v5": (_ENV, {"fingers": "tissue", "reward_type": "dense", "start": "easy", **TISSUE_GLOBAL}),
    "SoftGraspEasy-v4": (_ENV, {"fingers": "tissue", "reward_type": "dense", "start": "easy", **TISSUE_V4}),
    "SoftGraspEasyRigid-v3": (_ENV, {"fingers": "rigid", "reward_type": "dense", "start": "easy"}),
    "SoftGraspRigidTorsion-v3": (_ENV, {"fingers": "rigid_torsion", "reward_type": "dense", "carry": True}),
    "SoftGraspEasyRigidTorsion-v3": (_ENV, {"fingers": "rigid_torsion", "reward_type": "dense", "start": "easy"}),
    # the grip-force task: the soft v7 and v6 (the rigid kinds' v5) charge the margin over the least
    # force on the carry's steps alone; the rigid kinds' v4 the whole squeeze in least forces from
    # the first step. All keep three taxel frames.
    "SoftGraspGrip-v7": (_ENV, {"fingers": "tissue", "reward_type": "dense", "start": "easy", "carry": True,
                                **GRIP_TASK_CARRY, **TISSUE_GLOBAL}),
    "SoftGraspGrip-v6": (_ENV, {"fingers": "tissue", "reward_type": "dense", "start": "easy", "carry": True,
                                **GRIP_TASK_CARRY, **TISSUE_V4}),
    **{f"SoftGraspGrip{name}-v5": (_ENV, {"fingers": kind, "reward_type": "dense", "start": "easy", "carry": True,
                                          **GRIP_TASK_CARRY})
       for name, kind in (("Rigid", "rigid"), ("RigidTorsion", "rigid_torsion"))},
    **{f"SoftGraspGrip{name}-v4": (_ENV, {"fingers": kind, "reward_type": "dense", "start": "easy", "carry": True,
                                          **GRIP_TASK_LEAST})
       for name, kind in (("Rigid", "rigid"), ("RigidTorsion", "rigid_torsion"))},
    # the object-set family: the carry task and the grip-force task on every object
    "SoftGraspObjects-v2": (_ENV, {"fingers": "tissue", "reward_type": "dense", "carry": True, **OBJECTS_TASK,
                                   **TISSUE_GLOBAL}),
    "SoftGraspObjects-v1": (_ENV, {"fingers": "tissue", "reward_type": "dense", "carry": True, **OBJECTS_TASK,
                                   **TISSUE_V4}),
    "SoftGraspObjectsRigid-v1": (_ENV, {"fingers": "rigid", "reward_type": "dense", "carry": True, **OBJECTS_TASK}),
    "SoftGraspObjectsRigidTorsion-v1": (_ENV, {"fingers": PATCH_TORSION, "reward_type": "dense", "carry": True,
                                               **OBJECTS_TASK}),
    # the grip-force variants: the soft v3 and v2 and the rigid kinds' v2 take the grip ids' latest
    # charge (GRIP_TASK_CARRY), the rigid kinds' v1 the first (GRIP_TASK)
    "SoftGraspObjectsGrip-v3": (_ENV, {"fingers": "tissue", "reward_type": "dense", "start": "easy", "carry": True,
                                       **GRIP_TASK_CARRY, **OBJECTS_GRIP_TASK, **TISSUE_GLOBAL}),
    "SoftGraspObjectsGrip-v2": (_ENV, {"fingers": "tissue", "reward_type": "dense", "start": "easy", "carry": True,
                                       **GRIP_TASK_CARRY, **OBJECTS_GRIP_TASK, **TISSUE_V4}),
    **{f"SoftGraspObjectsGrip{name}-v2": (_ENV, {"fingers": kind, "reward_type": "dense", "start": "easy",
                                                 "carry": True, **GRIP_TASK_CARRY, **OBJECTS_GRIP_TASK})
       for name, kind in (("Rigid", "rigid"), ("RigidTorsion", PATCH_TORSION))},
    **{f"SoftGraspObjectsGrip{name}-v1": (_ENV, {"fingers": kind, "reward_type": "dense", "start": "easy",
                                                 "carry": True, **GRIP_TASK, **OBJECTS_GRIP_TASK})
       for name, kind in (("Rigid", "rigid"), ("RigidTorsion", PATCH_TORSION))},
}

ENV_IDS: tuple[str, ...] = tuple(_SPECS)
"""The registered ids, per family the latest version and the one before it. The task: the reach
with the carry test (approach from above and away, misaligned fingers, lift, then the arm sways the
cylinder for the last 1.5 s, a sway drawn per episode; success means held through all of it) with
soft fingers and the dense lift reward, its rigid-only twin, the torsional rigid peer, the
sparse-reward variant, the goal-conditioned variant (dict observations, ``compute_reward`` for HER;
a knocked-over cylinder does not end its episode) and the gentle start (``start="easy"``: the open
fingers around the cylinder's top, aligned) for debugging a policy or the physics; the grip-force
task (SoftGraspGrip, soft / rigid / torsional: the gentle start with the carry, the squeeze as the
action, mass and friction drawn and not observed, the squeeze charged and success within 2 x the
least that holds, 4 x 4 taxels per pad and three taxel frames, the cylinder's pose and motion not
observed: softgrasp_env/tasks/grip.py; the soft v7 and v6 and the rigid kinds' v5 charge the margin
over the least force on the carry's steps, :data:`GRIP_TASK_CARRY`, the rigid kinds' v4 the whole
squeeze in least forces from the first step, :data:`GRIP_TASK_LEAST`); the object set
(SoftGraspObjects, soft / rigid / torsional, and its grip-force variants, whose rigid v1 keeps the
grip ids' first charge: one of :data:`OBJECT_SET` drawn per episode, at a drawn size, mass and
friction, its kind and extents observed). The arm moves the palm at the action's velocity along a
smooth path (at most 0.15 m/s and 1.5 m/s^2).

The soft ids' latest version (SoftGrasp-v5, the goal's v6, the grip's v7, the object set's v2, its
grip's v3) solves the v4 tissue globally (:data:`TISSUE_GLOBAL`); the version before sweeps the same
tissue group by group (:data:`TISSUE_V4`). The rigid kinds have no tissue and stay as they were.
Older versions live in the tagged release that last registered them (:data:`RETIRED`); the thesis
tissue's are the v4 ids with :data:`TISSUE_V3`."""

RETIRED: dict[str, str] = {
    **{f"SoftGrasp{family}-{v}": "0.6.0" for family in ("", "Rigid", "Sparse") for v in ("v1", "v2")},
    **{f"SoftGrasp{family}-v1": "0.6.0" for family in ("Goal", "Easy", "EasyRigid")},
    "SoftGraspGoal-v3": "0.6.0",
    "SoftGraspGrip-v3": "0.6.0",
    **{f"SoftGraspGrip{kind}-{v}": "0.7.0" for kind, v in (("", "v4"), ("Rigid", "v3"), ("RigidTorsion", "v3"))},
    **{env_id: "0.8.0" for env_id in ("SoftGrasp-v3", "SoftGraspSparse-v3", "SoftGraspGoal-v4", "SoftGraspEasy-v3",
                                      "SoftGraspGrip-v5", "SoftGraspObjectsGrip-v1")},
}
"""Retired id -> the last release that registers it. ``gym.make`` of one raises
:class:`gymnasium.error.DeprecatedEnv` naming that release (:func:`retired_env`), and the registered
id with the keywords that are it where there is one (:data:`RETIRED_AS`); they are not in
:data:`ENV_IDS`."""

RETIRED_AS: dict[str, tuple[str, dict[str, object]]] = {
    "SoftGrasp-v3": ("SoftGrasp-v4", TISSUE_V3),
    "SoftGraspSparse-v3": ("SoftGraspSparse-v4", TISSUE_V3),
    "SoftGraspGoal-v4": ("SoftGraspGoal-v5", TISSUE_V3),
    "SoftGraspEasy-v3": ("SoftGraspEasy-v4", TISSUE_V3),
    "SoftGraspGrip-v5": ("SoftGraspGrip-v6", {"squeeze_charge_steps": "all", "squeeze_free": 0.0,
                                              "squeeze_weight": SQUEEZE_WEIGHT_LEAST}),
    "SoftGraspObjectsGrip-v1": ("SoftGraspObjectsGrip-v2", {"squeeze_reference": "finger_force",
                                                            "squeeze_weight": GRIP_TASK["squeeze_weight"],
                                                            "squeeze_charge_steps": "all", "squeeze_free": 0.0,
                                                            "tactile_history": 1}),
}  # fmt: skip
"""Retired id -> a registered id and the ``gym.make`` keywords with which it is the retired one,
step for step: the thesis tissue's ids are their v4 successors with :data:`TISSUE_V3`; the grip
ids' first charges are the latest grip ids with the charge's keywords (the same physics)."""


def registered_as(env_id: str, kwargs: dict[str, object] | None = None, *,
                  table: dict[str, tuple[str, dict[str, object]]] | None = None) -> tuple[str, dict[str, object]]:
    """The registered id and ``gym.make`` keywords that are ``env_id`` made with ``kwargs``: a retired
    id of ``table`` (default :data:`RETIRED_AS`) as its registered twin, the twin's keywords under
    ``kwargs``; any other id as itself. Nothing is checked here: ``gym.make`` checks the result."""
    made, keywords = (RETIRED_AS if table is None else table).get(env_id, (env_id, {}))
    return made, {**keywords, **(kwargs or {})}


def make_as(env_id: str, **kwargs: object) -> gym.Env:
    """``gym.make(env_id, **kwargs)``, except that a retired id with a registered twin
    (:data:`RETIRED_AS`, e.g. the thesis tissue's ``SoftGrasp-v3`` = ``SoftGrasp-v4`` with
    :data:`TISSUE_V3`) is made as that twin, step for step the retired id. For results measured on a
    retired id, reproduced on this release; a retired id without a twin raises as ``gym.make`` does."""
    made, keywords = registered_as(env_id, kwargs)
    return gym.make(made, **keywords)


def retired_message(env_id: str) -> str:
    """What ``gym.make(env_id)`` says for a retired id: the release (and its git tag) that has it."""
    release = RETIRED[env_id]
    current = [i for i in ENV_IDS if i.rsplit("-", 1)[0] == env_id.rsplit("-", 1)[0]]
    message = f"{env_id} was retired; `pip install softgrasp-env=={release}` (git tag v{release}) reproduces its results"
    if env_id in RETIRED_AS:
        made, kwargs = RETIRED_AS[env_id]
        keywords = ", ".join(f"{k}={v!r}" for k, v in kwargs.items())
        message += f", and so does gym.make({made!r}, {keywords}), step for step"
    return message + (f". This release registers {', '.join(current)}" if current else "")


def retired_env(*, env_id: str, **kwargs: object) -> gym.Env:
    """The entry point of every id in :data:`RETIRED`: raises :class:`gymnasium.error.DeprecatedEnv`
    naming the release that has ``env_id`` (any other keyword is ignored)."""
    raise gym.error.DeprecatedEnv(retired_message(env_id))


def steps_to_succeed(env: gym.Env) -> int | None:
    """The fewest env steps after which ``env`` (a SoftGrasp env, wrapped or not) can report success:
    with the carry test, the step at which the carry is over (``carry_start + carry_duration``,
    100 steps at the defaults); None without it (a lift can succeed at any step)."""
    from .tasks import CarryTest, TaskWrapper

    base = env.unwrapped
    task, plan = getattr(base, "task", None), getattr(base, "plan", None)
    if isinstance(task, TaskWrapper):  # the carry under what wraps it (the grip-force task)
        task = task.find(CarryTest)
    if not isinstance(task, CarryTest) or plan is None:
        return None
    per_step = plan.substeps
    n = max(1, math.floor((task.start_time + task.duration) / (task.dt * per_step)) - 1)
    while not task.over(n * per_step):  # the task's own rule decides, rounding included
        n += 1
    return n


def check_time_limit(env: gym.Env) -> gym.Env:
    """The last step of ``gym.make`` for every id (registered as an additional wrapper, so it runs
    after the TimeLimit is on and ``env.spec.max_episode_steps`` is the episode's length; the env
    itself only ever sees a spec without it): warn when the time limit ends every episode before
    success is possible, e.g. ``max_episode_steps=60`` with the carry test ending at 5 s. Returns
    ``env`` itself: it adds no wrapper."""
    limit = env.spec.max_episode_steps if env.spec is not None else None
    needed = steps_to_succeed(env)
    if limit is not None and needed is not None and limit < needed:
        base = env.unwrapped
        gym.logger.warn(
            f"{env.spec.id}: max_episode_steps={limit} ends every episode at {limit / base.control_frequency:g} s, "
            f"before the carry test is over at {needed / base.control_frequency:g} s (step {needed}): no episode can "
            f"succeed. Give max_episode_steps >= {needed}, or carry=False / an earlier carry_start.")  # fmt: skip
    return env


CHECK_TIME_LIMIT = WrapperSpec("CheckTimeLimit", f"{__name__}:check_time_limit", {})
"""``check_time_limit`` as gym.make applies it: after the TimeLimit (it wraps nothing)."""


def register_envs() -> None:
    """Register every id in :data:`ENV_IDS`, and every id in :data:`RETIRED` with :func:`retired_env`
    as its entry point (idempotent: ids already registered are left alone)."""
    for env_id in RETIRED:
        if env_id not in gym.registry:
            gym.register(id=env_id, entry_point=f"{__name__}:retired_env", kwargs={"env_id": env_id},
                         disable_env_checker=True)  # fmt: skip
    for env_id, (entry_point, kwargs) in _SPECS.items():
        if env_id not in gym.registry:
            # disable_env_checker: gymnasium 1.4.0's PassiveEnvChecker, when the first reset raises
            # (a mistyped reset option), keeps None as that reset's result and fails every later
            # step with "cannot unpack non-iterable NoneType". Our ids are checked in full by
            # gymnasium's and SB3's check_env in tests/test_env.py instead.
            gym.register(id=env_id, entry_point=entry_point, kwargs=dict(kwargs), max_episode_steps=MAX_EPISODE_STEPS,
                         disable_env_checker=True, additional_wrappers=(CHECK_TIME_LIMIT,))  # fmt: skip
