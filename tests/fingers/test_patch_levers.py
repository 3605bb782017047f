"""The torsional rigid peer's load-following lever (softgrasp_env/fingers/rigid.py,
``spinning_friction="patch"``): the tissue's measured table is sane, the lever reaches pybullet and
follows each core's normal force, only named objects have one, the fixed default is untouched,
and the peer holds a carried sphere with it."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.fingers import PATCH_SPINNING_FRICTION, RigidConfig, TorsionalRigidConfig
from softgrasp_env.fingers.rigid import LEVER_QUANTUM, PATCH_LEVERS, RigidFingers
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.scene import GraspScene, SceneConfig
from softgrasp_env.scene.objects import PRESETS, ObjectShape
from tests.helpers import run_episode

PATCH = TorsionalRigidConfig(spinning_friction="patch")


# --- the table --------------------------------------------------------------------------------------


def test_every_named_object_has_a_sane_table():
    """Loads positive and increasing (the interpolation's abscissa), levers positive and within the
    default face's half diagonal (RigidFingers.check: no patch on the face has a longer lever)."""
    assert set(PATCH_LEVERS) == set(PRESETS)
    fh = SceneConfig().finger_half_extents
    reach = float(np.hypot(fh[1], fh[2]))
    for name, table in PATCH_LEVERS.items():
        loads = np.array([n for n, _ in table])
        levers = np.array([lv for _, lv in table])
        assert len(table) >= 2, name
        assert (loads > 0.0).all() and (np.diff(loads) > 0.0).all(), name
        assert (levers > 0.0).all() and (levers <= reach).all(), name
        # the table's own resolution is the quantum the lever is rounded to
        assert np.allclose(levers / LEVER_QUANTUM, np.round(levers / LEVER_QUANTUM)), name
    # the measured cylinder brackets the fixed default's lever, measured on it at the default squeeze
    cyl = [lv for _, lv in PATCH_LEVERS["cylinder"]]
    assert min(cyl) <= PATCH_SPINNING_FRICTION <= max(cyl)


def test_the_fixed_default_stays_a_float():
    """The registered ids replay bit for bit on the fixed lever (tests/test_trajectories.py)."""
    assert TorsionalRigidConfig().spinning_friction == PATCH_SPINNING_FRICTION == 0.0167
    assert type(TorsionalRigidConfig().spinning_friction) is float
    assert RigidConfig().spinning_friction == 0.0


# --- the keyword ------------------------------------------------------------------------------------


def test_patch_is_taken_and_other_strings_are_refused():
    RigidConfig(spinning_friction="patch")
    for bad in ("Patch", "0.01", ""):
        with pytest.raises(ValueError, match=r"spinning_friction must be a finite number, got .*or 'patch'"):
            TorsionalRigidConfig(spinning_friction=bad)


def test_an_object_without_a_measured_lever_is_refused_at_construction():
    custom = ObjectShape("sphere", (0.02,))
    names = r"'cylinder', 'rod', 'sphere'.*'pebble-2'"
    with pytest.raises(ValueError, match=r"TorsionalRigidConfig\.spinning_friction='patch'.*" + names):
        SceneConfig(fingers=PATCH, object=custom)
    with pytest.raises(ValueError, match=r"spinning_friction='patch'.*has none"):
        SceneConfig(fingers=PATCH, cylinder_radius=0.02)  # a cylinder that is no preset
    # a preset scaled within +-15 % (the object-set ids' draw) takes its own table; further, none
    sphere = RigidFingers(SceneConfig(fingers=PATCH, object=PRESETS["sphere"].scaled(1.15)))
    assert sphere.lever(3.0) == RigidFingers(SceneConfig(fingers=PATCH, object="sphere")).lever(3.0)
    with pytest.raises(ValueError, match=r"scaled by at most 0.15 either way; the scene's object .* has none"):
        SceneConfig(fingers=PATCH, object=PRESETS["sphere"].scaled(1.2))
    with pytest.raises(ValueError, match=r"has none"):  # the same kind, another shape, the name kept
        SceneConfig(fingers=PATCH, object=ObjectShape("box", (0.05, 0.05, 0.06), label="cube"))
    with pytest.raises(ValueError, match=r"spinning_friction='patch'"):
        gym.make("SoftGraspEasyRigidTorsion-v3", fingers=PATCH, object=custom)
    # the named ones are taken, the rod given as the cylinder's own size too
    SceneConfig(fingers=PATCH, object="rod")
    SceneConfig(fingers=PATCH, cylinder_radius=PRESETS["rod"].size[0])


def test_the_lever_is_linear_in_the_table_and_holds_its_ends():
    kind = RigidFingers(SceneConfig(fingers=PATCH, object="sphere"))
    table = PATCH_LEVERS["sphere"]
    for n, lv in table:
        assert kind.lever(n) == pytest.approx(lv, abs=1e-12)
    (n0, l0), (n1, l1) = table[1], table[2]
    assert kind.lever(0.5 * (n0 + n1)) == pytest.approx(0.5 * (l0 + l1), abs=LEVER_QUANTUM)
    # outside the measured loads: the end values (the model's choice), at no load too
    assert kind.lever(0.0) == kind.lever(0.5 * table[0][0]) == pytest.approx(table[0][1], abs=1e-12)
    assert kind.lever(100.0) == pytest.approx(table[-1][1], abs=1e-12)


# --- in pybullet ------------------------------------------------------------------------------------


def test_before_contact_the_cores_carry_the_lowest_loads_lever():
    """At mount, before any contact, both cores have mu_core * l(lowest load) (the end value held
    below it), the palm and the object none."""
    sc = GraspScene(SceneConfig(fingers=PATCH, object="cone"))
    try:
        c, g = sc.client, sc.gripper.body
        want = SceneConfig().tissue.friction_static * PATCH_LEVERS["cone"][0][1]
        for link in sc.gripper.core_links:
            assert c.getDynamicsInfo(g, link)[7] == pytest.approx(want, rel=1e-9)
        assert c.getDynamicsInfo(g, -1)[7] == c.getDynamicsInfo(sc.cylinder, -1)[7] == 0.0
    finally:
        sc.close()


def _squeeze(force: float, obj: str = "sphere") -> tuple[list[float], list[float], list[float], int]:
    """The scripted grasp of ``obj`` by the patch peer with the squeeze ``force`` as the action,
    40 env steps (lifted and held). Returns, per core, pybullet's spinning coefficient, the core's
    normal force on the object now and mu_core * l(that force), and the changeDynamics calls the
    kind made over the hold's last 20 env steps."""
    env = gym.make("SoftGraspEasyRigidTorsion-v3", object=obj, fingers=PATCH, finger_action="force",
                   finger_force=force)  # fmt: skip
    try:
        policy = ScriptedGraspPolicy.for_env(env, grip_force=min(0.5, 0.5 * force))
        obs, _ = env.reset(seed=0)
        scene = env.unwrapped.scene
        kind, c, g = scene.fingers, scene.client, scene.gripper.body
        calls = []
        real = c.changeDynamics

        def counted(*a, **kw):
            calls.append(kw)
            return real(*a, **kw)

        for k in range(40):
            if k == 20:
                c.changeDynamics = counted
            obs, *_ = env.step(policy(obs))
        assert scene.lift_height() > 0.03
        # the kind sets the coefficient from the last step's contacts before the next step: take
        # the contacts as they are now through that same hook
        kind.before_step()
        spin, load, want = [], [], []
        for link in scene.gripper.core_links:
            n = sum(pt[9] for pt in c.getContactPoints(bodyA=scene.cylinder, bodyB=g, linkIndexB=link))
            spin.append(c.getDynamicsInfo(g, link)[7])
            load.append(n)
            want.append(c.getDynamicsInfo(g, link)[1] * kind.lever(n))
        return spin, load, want, len(calls)
    finally:
        env.close()


def test_the_patch_lever_reaches_pybullet_and_follows_the_load():
    """Squeezed at 1 and at 6 N the sphere's cores carry mu_core * l(N) of their own normal force;
    the sphere's patch grows with the squeeze (a disc of the chord's radius), so the coefficient
    does too. changeDynamics runs only on a change of the rounded lever: fewer calls than steps in
    a steady hold."""
    lo, hi = _squeeze(1.0), _squeeze(6.0)
    for spin, load, want, calls in (lo, hi):
        assert spin == pytest.approx(want, rel=1e-9)
        assert min(load) > 0.5
        assert calls < 2 * 20 * 12  # two cores, 20 env steps of 12 physics steps
    assert min(hi[1]) > 3.0 * max(lo[1])
    assert min(hi[0]) > max(lo[0]) * 1.1


@pytest.mark.parametrize("obj", ["sphere", "cone"])
def test_the_patch_peer_carries_the_object(obj):
    """The carry (the misaligned reach, the lift, the sway) of the sphere and the cone with the
    load-following lever: held to the end."""
    env = gym.make("SoftGraspRigidTorsion-v3", object=obj, fingers=PATCH)
    try:
        ep = run_episode(env, ScriptedGraspPolicy.for_env(env), seed=0)
        assert ep.info["is_success"]
    finally:
        env.close()
