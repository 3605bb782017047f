"""The FEM pads (``fingers="fem"``) on objects other than the cylinder: the pads' penetration measure
(softgrasp_env.fingers.fem.object_depth, FemPads.penetration) against hand-computed depths, and a
scripted grasp that lifts one (slow)."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.fingers.fem import object_depth
from softgrasp_env.observation import OBS_NAMES
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.registration import TISSUE_V3
from softgrasp_env.scene import GraspScene, SceneConfig
from softgrasp_env.tissue.collision import hull_params


def _rot_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rot_x(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


POS = np.array([0.1, -0.05, 0.04])
ROT = _rot_z(0.7) @ _rot_x(-0.3)
"""An object's pose: somewhere, turned about two axes (body to world)."""


def _world(body: np.ndarray) -> np.ndarray:
    return POS + np.atleast_2d(body) @ ROT.T


def test_a_node_3_mm_inside_a_sphere_is_3_mm_deep():
    r = 0.03
    u = np.array([0.2, -0.5, 0.7])
    u /= np.linalg.norm(u)
    inside, outside = (r - 0.003) * u, (r + 0.002) * u
    assert object_depth(_world(inside), POS, ROT, "sphere", (r, 0.0, 0.0)) == pytest.approx(0.003, abs=1e-12)
    assert object_depth(_world(np.vstack([outside, 0.9 * outside, inside])), POS, ROT, "sphere",
                        (r, 0.0, 0.0)) == pytest.approx(0.003, abs=1e-12)  # fmt: skip
    assert object_depth(_world(outside), POS, ROT, "sphere", (r, 0.0, 0.0)) == 0.0
    assert object_depth(np.zeros((0, 3)), POS, ROT, "sphere", (r, 0.0, 0.0)) == 0.0


def test_a_node_in_a_box_is_as_deep_as_its_nearest_face():
    """A 5 cm cube turned about two axes: a node 2 mm inside the +x face (and farther from the
    others) is 2 mm deep; the nearest face decides, the deepest node counts; outside is 0."""
    half = (0.025, 0.025, 0.025)
    node = np.array([0.023, -0.01, 0.015])  # 2 mm from +x, 15 mm from -y, 10 mm from +z
    assert object_depth(_world(node), POS, ROT, "box", half) == pytest.approx(0.002, abs=1e-12)
    nodes = np.array([[0.0, 0.0, -0.019], node, [0.03, 0.0, 0.0], [0.0, 0.026, 0.0]])
    assert object_depth(_world(nodes), POS, ROT, "box", half) == pytest.approx(0.006, abs=1e-12)  # -z face, 6 mm
    assert object_depth(_world(nodes[2:]), POS, ROT, "box", half) == 0.0
    # the same cube as a hull (its whole params row): the same depths
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half
    row = hull_params(corners)
    assert object_depth(_world(node), POS, ROT, "hull", row) == pytest.approx(0.002, abs=1e-12)
    assert object_depth(_world(nodes), POS, ROT, "hull", row) == pytest.approx(0.006, abs=1e-12)


def test_the_shape_sits_at_its_local_offset_in_the_body_frame():
    """A cone's shape is centred tissue_local_x above its centre of mass: a node 2 mm above the
    bottom face on the axis is 2 mm deep only with that offset applied."""
    r0, r1, hh, dz = 0.035, 0.02, 0.045, 0.006
    node = np.array([0.0, 0.0, -hh + dz + 0.002])  # body frame: the bottom face is at -hh + dz
    params = (r0, r1, hh)
    assert object_depth(_world(node), POS, ROT, "cone", params, (0.0, 0.0, dz)) == pytest.approx(0.002, abs=1e-12)
    assert object_depth(_world(node), POS, ROT, "cone", params) == pytest.approx(0.002 + dz, abs=1e-12)


def test_the_pads_penetration_measures_the_sphere_it_is_given():
    """In a scene: the sphere moved so that the left pad's innermost node is 3 mm inside it gives a
    penetration of 3 mm (that node is the deepest); at rest, out of reach, none."""
    sc = GraspScene(SceneConfig(fingers="fem", object="sphere"))
    try:
        pads = sc.fingers.pads
        assert pads.penetration() == (0.0, 0.0)
        x = pads.node_positions()[0]
        node = x[np.argmax(x[:, 0])]  # the left pad's inner face points along +x
        r = sc.object_geometry.tissue_params[0]
        sc.client.resetBasePositionAndOrientation(sc.cylinder, (node + [r - 0.003, 0.0, 0.0]).tolist(), [0, 0, 0, 1])
        pen, intrusion = pads.penetration()
        assert pen == pytest.approx(0.003, abs=1e-9) and intrusion == 0.0
    finally:
        sc.close()


def test_the_fem_fingers_take_any_named_object():
    for obj in ("sphere", "cube", "cone", "capsule", "pebble-1"):
        assert SceneConfig(fingers="fem", object=obj).object.name == obj


INDEX = {n: k for k, n in enumerate(OBS_NAMES)}


@pytest.mark.slow
def test_scripted_fem_grasp_lifts_and_holds_the_sphere():
    """The scripted policy on the gentle start (SoftGraspEasy-v4 with the thesis tissue's keywords,
    TISSUE_V3, as measured) with the coarse FEM pads, seed 0: the sphere is lifted to the success
    height and held; no pad node deeper than 2 mm in it or the ground."""
    env = gym.make("SoftGraspEasy-v4", fingers="fem", object="sphere", **TISSUE_V3)
    try:
        policy = ScriptedGraspPolicy.for_env(env)
        obs, _ = env.reset(seed=0)
        scene = env.unwrapped.scene
        pen, done = 0.0, False
        while not done:
            obs, _, term, trunc, info = env.step(policy(obs))
            done = term or trunc
            pen = max(pen, scene.penetration()[0])
    finally:
        env.close()
    assert info["is_success"]
    assert obs[INDEX["lift"]] > 0.03
    assert pen < 0.002
