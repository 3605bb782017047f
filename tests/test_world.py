"""Tissue and pybullet together: free fall, the grasp scene, squeezing, determinism."""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest

from softgrasp_env.config import SceneConfig, SimConfig, TissueConfig
from softgrasp_env.demo import ScriptTimes, run_scripted_grasp
from softgrasp_env.scene import GraspScene
from softgrasp_env.sim.bullet import RigidRef, connect
from softgrasp_env.sim.world import ShapeSpec, TissueSpec, World
from softgrasp_env.tissue.builder import build_combined_body, core_shape_from_bullet


def falling_box_world(coupling: str):
    client = connect()
    sim = SimConfig(coupling=coupling)
    client.setGravity(0, 0, -sim.gravity)
    client.setPhysicsEngineParameter(fixedTimeStep=sim.dt, numSubSteps=0)
    col = client.createCollisionShape(p.GEOM_BOX, halfExtents=[0.01, 0.02, 0.03])
    body = client.createMultiBody(baseMass=0.05, baseCollisionShapeIndex=col, basePosition=[0, 0, 1.0])
    client.changeDynamics(body, -1, linearDamping=0.0, angularDamping=0.0)
    core, offset, _ = core_shape_from_bullet(client, body)
    world = World(
        client,
        sim,
        [RigidRef(body, -1, gravity=True, in_solve=False, free_base=True, core=True)],
        [ShapeSpec("box", core.half_extents, rigid=0)],
        [TissueSpec(build_combined_body(core, TissueConfig(), shape_offset=offset), 0)],
    )
    return client, body, world


@pytest.mark.parametrize("coupling", ["thesis", "consistent"])
def test_combined_body_free_fall_matches_semi_implicit_euler(coupling):
    client, body, world = falling_box_world(coupling)
    try:
        z0 = client.getBasePositionAndOrientation(body)[0][2]
        rest = world.state.particle_x - np.asarray(client.getBasePositionAndOrientation(body)[0])
        dt, g = world.sim.dt, world.sim.gravity
        n = 240
        for _ in range(n):
            world.step()
        pos = np.asarray(client.getBasePositionAndOrientation(body)[0])
        assert abs(pos[2] - (z0 - g * dt * dt * n * (n + 1) / 2)) < 1e-6
        sag = np.abs((world.state.particle_x - pos) - rest).max()
        assert sag < 5e-4
    finally:
        client.disconnect()


def test_scripted_lift_with_soft_fingers():
    scene = GraspScene(SceneConfig())
    try:
        res = run_scripted_grasp(scene, ScriptTimes())
    finally:
        scene.close()
    assert res.finite
    assert res.held(ScriptTimes()), f"lift {res.lift_height:.4f} m, min during hold {res.min_lift_during_hold:.4f} m"
    assert res.max_penetration < 0.002, f"max penetration {res.max_penetration * 1000:.2f} mm"
    # inner collisions: outer particles stay outside their own core
    assert res.max_core_intrusion < 5e-4, f"core intrusion {res.max_core_intrusion * 1000:.2f} mm"


def test_world_is_deterministic():
    """Two worlds built alike and driven alike stay bit-identical (their own pybullet clients)."""

    def run(scene, steps):
        scene.set_finger_target(scene.config.finger_max_opening)
        for _ in range(steps):
            scene.world.step()
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


def test_restore_returns_bodies_and_tissue_to_the_snapshot():
    scene = GraspScene(SceneConfig())
    try:
        snap = scene.world.save()
        x0 = scene.world.state.particle_x.copy()
        c0 = scene.cylinder_pose()[0]
        scene.set_finger_target(scene.config.finger_max_opening)
        for _ in range(60):
            scene.world.step()
        assert np.abs(scene.world.state.particle_x - x0).max() > 1e-3
        scene.world.restore(snap)
        assert np.array_equal(scene.world.state.particle_x, x0)
        assert np.array_equal(scene.cylinder_pose()[0], c0)
        assert scene.world.step_count == 0
    finally:
        scene.close()


@pytest.mark.parametrize("mu", [0.5, 0.9])
def test_squeezed_cylinder_obeys_coulomb_bound(mu):
    """Two fingers squeezing with N each hold the cylinder iff 2 mu N >= m g: held at 1.2 times the
    threshold squeeze, slipping at 0.8 times (the motors' force limit sets N)."""
    cylinder_mass = 0.1
    threshold = cylinder_mass * 9.81 / (2.0 * mu)
    outcome = {}
    for factor in (1.2, 0.8):
        cfg = SceneConfig(
            finger_force=factor * threshold,
            cylinder_mass=cylinder_mass,
            tissue=TissueConfig(friction_static=mu, friction_dynamic=mu),
        )
        scene = GraspScene(cfg)
        try:
            res = run_scripted_grasp(scene, ScriptTimes())
        finally:
            scene.close()
        outcome[factor] = res
    assert outcome[1.2].held(ScriptTimes())
    assert outcome[0.8].lift_height < 0.005, f"slipped cylinder rose {outcome[0.8].lift_height:.4f} m"
