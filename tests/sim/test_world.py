"""Tissue and pybullet together: free fall, the grasp scene, squeezing, determinism."""

from __future__ import annotations

import math

import numpy as np
import pybullet as p
import pytest

from softgrasp_env.accuracy import GraspPlan, coulomb_hold_bound, run_grasp
from softgrasp_env.config import SimConfig, TissueConfig, replace
from softgrasp_env.fingers import TissueFingerConfig
from softgrasp_env.scene import GraspScene, SceneConfig
from softgrasp_env.sim.bullet import RigidRef, connect
from softgrasp_env.sim.world import ShapeSpec, TissueSpec, World
from softgrasp_env.tissue.builder import build_combined_body, core_shape_from_bullet
from softgrasp_env.tissue.compliant import world_substeps


def falling_box_world(coupling: str):
    """A 50 g box in tissue on every face, falling freely: in the world steps its tissue needs
    (compliant.world_substeps; 2 at the defaults, where 1 grew a mode from round-off)."""
    client = connect()
    sim = SimConfig(coupling=coupling)
    client.setGravity(0, 0, -sim.gravity)
    col = client.createCollisionShape(p.GEOM_BOX, halfExtents=[0.01, 0.02, 0.03])
    body = client.createMultiBody(baseMass=0.05, baseCollisionShapeIndex=col, basePosition=[0, 0, 1.0])
    client.changeDynamics(body, -1, linearDamping=0.0, angularDamping=0.0)
    core, offset, _ = core_shape_from_bullet(client, body)
    model = build_combined_body(core, TissueConfig(), shape_offset=offset)
    n = world_substeps(model, np.array([0.05]), sim.dt)
    client.setPhysicsEngineParameter(fixedTimeStep=sim.dt / n, numSubSteps=0)
    world = World(
        client,
        sim,
        [RigidRef(body, -1, gravity=True, in_solve=False, free_base=True, core=True)],
        [ShapeSpec("box", core.half_extents, rigid=0)],
        [TissueSpec(model, 0)],
        substeps=n,
    )
    return client, body, world


def test_world_refuses_fewer_steps_than_its_tissue_needs():
    client = connect()
    try:
        col = client.createCollisionShape(p.GEOM_BOX, halfExtents=[0.01, 0.02, 0.03])
        body = client.createMultiBody(baseMass=0.05, baseCollisionShapeIndex=col)
        core, offset, _ = core_shape_from_bullet(client, body)
        spec = TissueSpec(build_combined_body(core, TissueConfig(), shape_offset=offset), 0)
        refs = [RigidRef(body, -1, gravity=True, in_solve=False, free_base=True, core=True)]
        with pytest.raises(ValueError, match=r"World\(substeps=1\) .* at least 2 world steps .* 0\.05 kg"):
            World(client, SimConfig(), refs, [ShapeSpec("box", core.half_extents, rigid=0)], [spec])
    finally:
        client.disconnect()


@pytest.mark.parametrize("coupling", ["thesis", "consistent"])
def test_combined_body_free_fall_matches_semi_implicit_euler(coupling):
    client, body, world = falling_box_world(coupling)
    try:
        z0 = client.getBasePositionAndOrientation(body)[0][2]
        rest = world.state.particle_x - np.asarray(client.getBasePositionAndOrientation(body)[0])
        h, g = world.sim.dt / world.substeps, world.sim.gravity
        n = 240 * world.substeps
        for _ in range(240):
            world.step()
        pos = np.asarray(client.getBasePositionAndOrientation(body)[0])
        assert abs(pos[2] - (z0 - g * h * h * n * (n + 1) / 2)) < 1e-6
        sag = np.abs((world.state.particle_x - pos) - rest).max()
        assert sag < 5e-4
    finally:
        client.disconnect()


# Deepest penetration (every step) at the defaults, measured: thesis 0.095 mm, consistent 0.122 mm
# (the moment the fingers meet the cylinder at their full 0.1 m/s). Outer particles into their own
# core: 0.000 mm both (checked to 1 um).
PENETRATION_BOUND = {"thesis": (0.25e-3, 0.001e-3), "consistent": (0.3e-3, 0.001e-3)}


@pytest.mark.parametrize("coupling", ["thesis", "consistent"])
def test_scripted_lift_with_soft_fingers(coupling):
    plan = GraspPlan()
    scene = GraspScene(SceneConfig(sim=SimConfig(coupling=coupling)))
    try:
        res = run_grasp(scene, plan)
    finally:
        scene.close()
    assert res.held(plan), f"lift {res.lift_height:.4f} m, min during hold {res.min_lift_during_hold:.4f} m"
    pen, intrusion = PENETRATION_BOUND[coupling]
    assert res.max_penetration < pen, f"max penetration {res.max_penetration * 1000:.3f} mm"
    assert res.max_core_intrusion < intrusion, f"core intrusion {res.max_core_intrusion * 1000:.3f} mm"


@pytest.mark.parametrize("kind", ["thesis", "consistent", "rigid"])
def test_held_cylinder_stays_held_for_a_minute(kind):
    """The scripted grasp, then 60 s of holding at the defaults (longer than any episode): the
    cylinder neither turns nor slips in the fingers. Measured over the 60 s: slip 0.012 / 0.021 /
    0.001 mm, tilt at most 0.041 / 0.033 / 0.006 deg (before anchored friction it tilted 13 deg after 22 s and fell
    out after 29 s; the rigid pair drifted 2.5 cm sideways before the fingers were geared)."""
    plan = GraspPlan(hold=60.0)
    cfg = SceneConfig(fingers="rigid") if kind == "rigid" else SceneConfig(sim=SimConfig(coupling=kind))
    scene = GraspScene(cfg)
    try:
        res = run_grasp(scene, plan)
        closing = scene.finger_closing()
    finally:
        scene.close()
    assert res.held(plan)
    assert res.hold_slip < 0.05e-3, f"slipped {res.hold_slip * 1000:.3f} mm"
    assert math.degrees(res.max_tilt) < 0.15, f"tilted {math.degrees(res.max_tilt):.2f} deg"
    assert abs(closing[0] - closing[1]) < 1e-4  # the geared fingers stay centred


def test_world_is_deterministic():
    """Two worlds built alike and driven alike stay bit-identical (their own pybullet clients)."""

    def run(scene, steps):
        close = replace(scene.control, finger_closing=scene.config.finger_stroke)
        for _ in range(steps):
            scene.step(close)
        return scene.world.state.particle_x.copy(), scene.cylinder_pose()[0]

    a = GraspScene(SceneConfig())
    b = GraspScene(SceneConfig())
    try:
        xa, ca = run(a, 120)
        xb, cb = run(b, 120)
        assert np.array_equal(xa, xb) and np.array_equal(ca, cb)
        assert np.abs(xa - a.world.save()[1].particle_x).max() == 0.0
    finally:
        a.close()
        b.close()


@pytest.mark.parametrize("fingers", ["rigid", "segmented"])
def test_a_world_without_tissue_reads_rigid_states_when_asked(fingers):
    """Without tissue nothing needs the rigid states between physics steps: the world reads them
    when ``colliders`` is asked. What it reads then is exactly what the eager read after
    every step gave: the same numbers as a fresh read, and ``position`` (the palm, every physics
    step) the same as its row."""
    from softgrasp_env.scene.scene import PALM

    scene = GraspScene(SceneConfig(fingers=fingers))
    try:
        world = scene.world
        assert world.solver is None
        close = replace(scene.control, finger_closing=scene.config.finger_stroke)
        for _ in range(30):
            scene.step(close)
        assert world._stale  # nothing read since the last step
        palm = np.array(world.position(PALM))
        col = world.colliders  # read now
        assert not world._stale
        assert np.array_equal(palm, col.rigid_x[PALM]) and np.array_equal(np.array(world.position(PALM)), palm)
        lazy = [a.copy() for a in (col.rigid_x, col.rigid_q, col.rigid_v, col.rigid_w)]
        for a in (col.rigid_x, col.rigid_q, col.rigid_v, col.rigid_w):
            a[...] = np.nan
        world.refresh()
        for a, b in zip(lazy, (col.rigid_x, col.rigid_q, col.rigid_v, col.rigid_w), strict=True):
            assert np.array_equal(a, b)
        assert np.isfinite(lazy[0]).all()
    finally:
        scene.close()


def test_restore_returns_bodies_and_tissue_to_the_snapshot():
    scene = GraspScene(SceneConfig())
    try:
        snap = scene.world.save()
        x0 = scene.world.state.particle_x.copy()
        c0 = scene.cylinder_pose()[0]
        close = replace(scene.control, finger_closing=scene.config.finger_stroke)
        for _ in range(60):
            scene.step(close)
        assert np.abs(scene.world.state.particle_x - x0).max() > 1e-3
        scene.world.restore(snap)
        assert np.array_equal(scene.world.state.particle_x, x0)
        assert np.array_equal(scene.cylinder_pose()[0], c0)
        assert scene.world.step_count == 0
    finally:
        scene.close()


@pytest.mark.parametrize("kind", ["thesis", "consistent", "rigid"])
def test_hold_bound_is_coulombs(kind):
    """The heaviest cylinder the fingers hold at 3 N each is within 5 % of 2 mu_s F / g: held
    without slipping at 0.95 of it, slipping at 1.05, at the default mu_k = mu_s 0.9. The lift is
    slow (4 s) so that the test is of the static bound. Bisection measured
    (benchmarks/accuracy_defaults.py): thesis -3.8 %, consistent -4.2 %, rigid twin -0.0 % (release
    0.6.0's v1/v2 arm and mu_k 0.7: -3.0 / -2.6 / -0.0 %; before the accuracy work: -14.5 %, +37 %,
    -45 %)."""
    plan = GraspPlan(lift=4.0, hold=3.0)
    base = SceneConfig(fingers="rigid" if kind == "rigid" else "tissue", sim=SimConfig(coupling="consistent" if kind == "consistent" else "thesis"))
    bound = coulomb_hold_bound(base.tissue.friction_static, base.finger_force, base.sim.gravity)
    outcome = {}
    for factor in (0.95, 1.05):
        scene = GraspScene(replace(base, cylinder_mass=factor * bound))
        try:
            outcome[factor] = run_grasp(scene, plan)
        finally:
            scene.close()
    assert outcome[0.95].holds_without_slip(plan), f"slipped {outcome[0.95].hold_slip * 1000:.2f} mm at 0.95 of the bound"
    assert not outcome[1.05].holds_without_slip(plan), "held 1.05 times the Coulomb bound"


def test_tissue_on_every_face_still_grasps():
    """SceneConfig(fingers=TissueFingerConfig(faces='all')): tissue on every face of each core (152 particles instead of
    the default's 60 on the inner face and tip); the scripted grasp holds. Measured: penetration
    0.098 mm, slip in a 5 s hold 0.006 mm."""
    plan = GraspPlan(hold=5.0)
    scene = GraspScene(SceneConfig(fingers=TissueFingerConfig(faces="all")))
    try:
        res = run_grasp(scene, plan)
        count = scene.world.model.particle_count
    finally:
        scene.close()
    assert count == 152
    assert res.held(plan) and res.hold_slip < 0.02e-3
    assert res.max_penetration < 0.25e-3


def test_presets_build_and_the_env_takes_them():
    from softgrasp_env import presets

    counts = {}
    for name in presets.PRESETS:
        cfg = presets.scene_config(name)
        scene = GraspScene(cfg)
        try:
            counts[name] = scene.world.model.particle_count
        finally:
            scene.close()
    assert counts == {"fast": 32, "default": 60, "accurate": 60, "fine": 200, "converged": 1140}
    assert presets.scene_config("default") == SceneConfig()
    for name, layers in (("fine", 1), ("converged", 2)):  # the v4 tissue, its layers as thick as the spacing
        tissue = presets.scene_config(name).tissue
        assert (tissue.group_energy, tissue.friction_law, tissue.hourglass_stiffness, tissue.layers) == (
            "continuum", "contact", 1.0, layers)
    assert presets.scene_config("accurate").sim.dt == pytest.approx(1 / 480)
    with pytest.raises(ValueError, match="preset must be one of"):
        presets.scene_config("slow")
