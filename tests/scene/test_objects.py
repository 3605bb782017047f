"""The grasp objects beyond the cylinder: their mass properties against independent computations,
their resting poses in pybullet, the errors a bad shape gets, and the default cylinder untouched."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from softgrasp_env.scene import SceneConfig
from softgrasp_env.scene.config import grasp_height
from softgrasp_env.scene.objects import (
    MESHES,
    PRESETS,
    ObjectShape,
    load_mesh,
    mesh_mass_properties,
    mesh_planes,
    object_geometry,
    object_shape,
)
from softgrasp_env.scene.scene import GraspScene


def _prism(bottom: np.ndarray, top: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A closed triangle mesh between two rings of n points (counter-clockwise seen from +z),
    outward triangles: the side quads and a fan on each cap."""
    n = len(bottom)
    v = np.vstack((bottom, top, bottom.mean(axis=0), top.mean(axis=0)))
    cb, ct = 2 * n, 2 * n + 1
    tris = []
    for i in range(n):
        j = (i + 1) % n
        tris += [(i, j, n + j), (i, n + j, n + i), (cb, j, i), (ct, n + i, n + j)]
    return v, np.array(tris)


def _ring(rx: float, ry: float, z: float, n: int) -> np.ndarray:
    t = np.arange(n) * 2 * np.pi / n
    return np.column_stack((rx * np.cos(t), ry * np.sin(t), np.full(n, z)))


def test_mesh_mass_properties_of_a_box_are_exact():
    """A 2 x 3 x 4 cm box as 12 triangles, shifted off the origin: volume, centroid and inertia
    match the closed forms to rounding."""
    x, y, z = 0.02, 0.03, 0.04
    pts = np.array([[sx * x / 2, sy * y / 2, sz * z] for sz in (0, 1) for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1))])
    bottom, top = pts[:4], pts[4:]
    v, t = _prism(bottom, top)
    shift = np.array([0.1, -0.2, 0.3])
    vol, c, inertia = mesh_mass_properties(v + shift, t)
    assert vol == pytest.approx(x * y * z, rel=1e-12)
    np.testing.assert_allclose(c, shift + [0, 0, z / 2], atol=1e-14)
    expect = vol * np.diag([(y * y + z * z) / 12, (x * x + z * z) / 12, (x * x + y * y) / 12])
    np.testing.assert_allclose(inertia, expect, rtol=1e-10, atol=1e-18)
    # inward triangles are refused, not turned into a negative mass
    with pytest.raises(ValueError, match="counter-clockwise"):
        mesh_mass_properties(v, t[:, ::-1])


@pytest.mark.parametrize("name", ["cone", "elliptic"])
def test_round_kinds_mass_properties_match_a_fine_mesh(name):
    """The cone's and elliptic cylinder's closed forms (Gauss-Legendre in z, the ellipse's moments)
    against the mass properties of a 2,048-sided polygonal mesh of the same solid: the polygon's
    sag is 1.2e-6 of the radius, so they agree to about 1e-5."""
    geo = object_geometry(PRESETS[name])
    s = PRESETS[name].size
    n = 2048
    if name == "cone":
        r0, r1, h = s
        v, t = _prism(_ring(r0, r0, 0.0, n), _ring(r1, r1, h, n))
        base_to_com = geo.rest_height
    else:
        a, b, h = s
        v, t = _prism(_ring(a, b, 0.0, n), _ring(a, b, h, n))
        base_to_com = h / 2
    vol, c, inertia = mesh_mass_properties(v, t)
    assert geo.volume == pytest.approx(vol, rel=2e-5)
    assert base_to_com == pytest.approx(c[2], rel=2e-5)
    np.testing.assert_allclose(geo.inertia_per_mass, np.diag(inertia) / vol, rtol=5e-5)
    assert abs(inertia[0, 1]) < 1e-9 * inertia[0, 0]


def test_capsule_inertia_against_sampling():
    """The capsule's moments (a cylinder and two hemispheres moved past their centroids) against a
    seeded Monte Carlo over its bounding box: 1e6 points, so within about 0.3 %."""
    geo = object_geometry(PRESETS["capsule"])
    r, length = PRESETS["capsule"].size
    rng = np.random.default_rng(0)
    h = length / 2 + r
    p = rng.uniform([-r, -r, -h], [r, r, h], size=(1_000_000, 3))
    zc = np.clip(p[:, 2], -length / 2, length / 2)
    inside = p[(p[:, 0] ** 2 + p[:, 1] ** 2 + (p[:, 2] - zc) ** 2) <= r * r]
    vol = len(inside) / len(p) * (2 * r) ** 2 * 2 * h
    assert geo.volume == pytest.approx(vol, rel=3e-3)
    ixx = float((inside[:, 1] ** 2 + inside[:, 2] ** 2).mean())
    izz = float((inside[:, 0] ** 2 + inside[:, 1] ** 2).mean())
    assert geo.inertia_per_mass[0] == pytest.approx(ixx, rel=3e-3)
    assert geo.inertia_per_mass[2] == pytest.approx(izz, rel=3e-3)


@pytest.mark.parametrize("mesh", MESHES)
def test_pebbles_are_convex_closed_and_stand_on_their_base(mesh):
    """A shipped mesh: every vertex inside every face plane (convex), the base a face at z = 0,
    the centroid above the base; its principal frame turns the inertia diagonal and the rest pose
    puts the body back where the mesh was."""
    v, t = load_mesh(mesh)
    planes = mesh_planes(v, t)
    assert (v @ planes[:, :3].T - planes[:, 3]).max() < 1e-12
    assert any(np.allclose(q, [0, 0, -1, 0], atol=1e-12) for q in planes)
    geo = object_geometry(PRESETS[mesh])
    vol, c, inertia = mesh_mass_properties(v, t)
    assert geo.volume == pytest.approx(vol, rel=1e-12)
    assert geo.rest_height == pytest.approx(c[2], rel=1e-12)
    # rotate the body-frame vertices by the rest pose: the mesh about its centroid again
    x, y, z, w = geo.rest_q
    m = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])  # fmt: skip
    np.testing.assert_allclose(geo.vertices @ m.T, v - c, atol=1e-12)
    body_inertia = m.T @ (inertia / vol) @ m
    np.testing.assert_allclose(body_inertia, np.diag(geo.inertia_per_mass), atol=1e-12 * np.trace(body_inertia))
    np.testing.assert_allclose(m @ np.array(geo.up), [0, 0, 1], atol=1e-12)


@pytest.mark.parametrize("name", [n for n in PRESETS if PRESETS[n].kind not in ("cone", "elliptic", "hull")])
def test_objects_rest_where_the_scene_puts_them(name):
    """Each object stands 2 s on the ground beside the open rigid fingers: its centre of mass stays
    at its rest height (pybullet's contact settles by 0.010-0.013 mm), it does not tip, and
    pybullet holds the exact inertia."""
    sc = GraspScene(SceneConfig(fingers="rigid", object=name))
    try:
        geo = sc.object_geometry
        info = sc.client.getDynamicsInfo(sc.cylinder, -1)
        if geo is not None:  # the cylinder kinds (the rod) stay pybullet's own cylinder
            np.testing.assert_allclose(info[2], [0.1 * i for i in geo.inertia_per_mass], rtol=1e-12)
        for _ in range(480):
            sc.step()
        x, _ = sc.cylinder_pose()
        assert abs(sc.lift_height()) < 3e-5
        assert sc.cylinder_tilt() < math.radians(0.03)
        assert np.hypot(x[0], x[1]) < 3e-4  # a box creeps 0.09 mm on pybullet's ground in 2 s
    finally:
        sc.close()


def test_bad_shapes_get_clear_errors():
    with pytest.raises(ValueError, match="object must be one of"):
        object_shape("donut")
    with pytest.raises(TypeError, match="object must be a name"):
        object_shape(3)
    with pytest.raises(ValueError, match="a sphere takes size=\\(radius\\)"):
        ObjectShape("sphere", (0.03, 0.02))
    with pytest.raises(ValueError, match="the box's y must be in"):
        ObjectShape("box", (0.03, -0.02, 0.05))
    with pytest.raises(ValueError, match="finite number"):
        ObjectShape("sphere", (math.nan,))
    with pytest.raises(ValueError, match="stands on its wider face"):
        ObjectShape("cone", (0.02, 0.03, 0.08))
    with pytest.raises(ValueError, match="needs mesh="):
        ObjectShape("hull", (1.0,))
    with pytest.raises(ValueError, match="for kind='hull' only"):
        ObjectShape("box", (0.03, 0.03, 0.03), mesh="pebble-0")
    with pytest.raises(ValueError, match="kind must be one of"):
        ObjectShape("torus", (0.03,))
    # a sphere wider than the open fingers
    with pytest.raises(ValueError, match="does not fit between the open fingers"):
        SceneConfig(object=ObjectShape("sphere", (0.06,)))
    # the cylinder's size keywords do not describe another object
    with pytest.raises(ValueError, match="give its size in the object"):
        SceneConfig(object="sphere", cylinder_radius=0.02)
    with pytest.raises(ValueError, match="both describe the cylinder"):
        SceneConfig(object="rod", cylinder_height=0.08)
    # the FEM pads grasp any object (their penetration measure is the object's own shape)
    assert SceneConfig(fingers="fem", object="sphere").object == PRESETS["sphere"]
    SceneConfig(fingers="fem", object="rod")  # a cylinder is a cylinder


def test_a_cylinder_given_as_object_is_the_cylinder():
    """object='rod' (a cylinder kind) becomes cylinder_radius/height: one description, the
    default cylinder's code path."""
    cfg = SceneConfig(object="rod")
    assert cfg.object is None and (cfg.cylinder_radius, cfg.cylinder_height) == PRESETS["rod"].size
    assert SceneConfig(object="cylinder") == SceneConfig()
    assert replace(SceneConfig(object="sphere"), yaw=0.1).object == PRESETS["sphere"]


def test_low_objects_are_gripped_above_the_ground():
    """A sphere's centre (3 cm) is below the lowest grip point (the fingertip pads 3 mm off the
    ground): it is gripped there; the cube's centre too; the cylinder at its middle."""
    for kind in ("tissue", "rigid"):
        cfg = SceneConfig(fingers=kind, object="sphere")
        low = cfg.finger_half_extents[2] + cfg.tissue.extrude + 0.003
        assert grasp_height(cfg) == pytest.approx(low)
        assert grasp_height(SceneConfig(fingers=kind)) == 0.05


@pytest.mark.parametrize("name", ["cone", "elliptic"])
def test_the_drawn_mesh_is_closed_and_outward(name):
    """pybullet's mesh of a round kind: its triangles close the solid outward (positive volume,
    the 64-gon's, within its sag of the smooth shape's)."""
    geo = object_geometry(PRESETS[name])
    vol, c, _ = mesh_mass_properties(geo.vertices, geo.triangles)
    assert vol == pytest.approx(geo.volume, rel=2e-3)
    np.testing.assert_allclose(c, 0.0, atol=1e-6)  # the body frame sits at the centre of mass


def _quat_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz)  # fmt: skip


def _about(axis, angle):
    s = math.sin(angle / 2)
    return (axis[0] * s, axis[1] * s, axis[2] * s, math.cos(angle / 2))


@pytest.mark.parametrize("name", ["capsule", "sphere", "cone", "pebble-1"])
def test_tilt_is_the_objects_own(name):
    """At rest every object's tilt is 0. Turned 30 deg about the world x axis, a standing object
    (the cone, a pebble) and the capsule (its axis now 30 deg from the horizontal) tilt by 30 deg;
    rolled about its own axis the capsule does not tilt, and a sphere never does."""
    sc = GraspScene(SceneConfig(fingers="rigid", object=name))
    try:
        rest = sc.object_geometry.rest_q
        assert sc.object_tilt(np.array(rest)) == pytest.approx(0.0, abs=1e-7)
        turned = _quat_mul(_about((1, 0, 0), math.radians(30)), rest)
        expect = 0.0 if name == "sphere" else math.radians(30)
        assert sc.object_tilt(np.array(turned)) == pytest.approx(expect, abs=1e-9)
        if name == "capsule":  # roll about its own axis (world y at rest)
            rolled = _quat_mul(_about((0, 1, 0), math.radians(70)), rest)
            assert sc.object_tilt(np.array(rolled)) == pytest.approx(0.0, abs=1e-9)
    finally:
        sc.close()


def test_a_scene_config_names_its_preset_and_the_scale_it_is_drawn_at():
    """SceneConfig.preset_scale: a named object itself (by value, whatever it is called), a preset
    scaled alike in every dimension (its name kept by ObjectShape.scaled), and None for any other
    shape; object_geometry is the object's (None for the cylinder)."""
    assert SceneConfig().preset_scale() == ("cylinder", 1.0) and SceneConfig().object_geometry is None
    assert SceneConfig(object="rod").preset_scale() == ("rod", 1.0)
    assert SceneConfig(object=ObjectShape("box", (0.05, 0.05, 0.05))).preset_scale() == ("cube", 1.0)
    name, factor = SceneConfig(object=PRESETS["pebble-1"].scaled(0.9)).preset_scale()
    assert name == "pebble-1" and factor == pytest.approx(0.9, rel=1e-12)
    assert SceneConfig(object=ObjectShape("box", (0.05, 0.05, 0.06), label="cube")).preset_scale() is None
    assert SceneConfig(object=ObjectShape("sphere", (0.02,))).preset_scale() == ("sphere", pytest.approx(2 / 3))
    assert SceneConfig(object="cone").object_geometry.tissue_kind == "cone"
