"""Finger kind 'fem': pybullet's own FEM soft bodies as the fingers' pads
(softgrasp_env/fingers/fem.py).

The pad mesh is checked against geometry (volume, surface, orientation, conformity, symmetry, the
anchors on the core), the scene is built, stepped and rebuilt, and the grasp is measured: with the
default 8 substeps it lifts and holds the default cylinder (slow test); with 1 substep (pybullet at
the scene's own 1/240 s) it fails at first contact, as recorded in FemConfig.substeps. What
every kind shares (validated fields, scripted hold, determinism, rendering, divergence) is in
tests/fingers/test_contract.py."""

from __future__ import annotations

from collections import Counter
from dataclasses import replace

import numpy as np
import pytest

from softgrasp_env.accuracy import GraspPlan, run_grasp
from softgrasp_env.fingers import FemConfig
from softgrasp_env.fingers.fem import FEM_CELLS_THROUGH, neo_hookean_parameters, pad_mesh, vtk_file
from softgrasp_env.scene import GraspScene, SceneConfig

FEM_RESOLUTIONS = tuple(FEM_CELLS_THROUGH)
CFG = SceneConfig(fingers="fem")
HX, HY, HZ = CFG.finger_half_extents
T = CFG.tissue.extrude
FACES = ((0, 1, 2), (0, 3, 1), (0, 2, 3), (1, 3, 2))
"""A tet's faces, each wound outward for a positively oriented tet (a, b, c, d)."""


def signed_volumes(x: np.ndarray, tets: np.ndarray) -> np.ndarray:
    e = x[tets]
    return np.einsum("ij,ij->i", np.cross(e[:, 1] - e[:, 0], e[:, 2] - e[:, 0]), e[:, 3] - e[:, 0]) / 6.0


def _bullet_piola(f: np.ndarray, mu: float, lam: float) -> np.ndarray:
    """btDeformableNeoHookeanForce::firstPiola (bullet 3.2), written out: the stress pybullet uses."""
    ic, j = float(np.sum(f * f)), float(np.linalg.det(f))
    return mu * (1.0 - 1.0 / (ic + 1.0)) * f + (lam * (j - 1.0) - 0.75 * mu) * j * np.linalg.inv(f).T


def test_the_pads_are_the_tissues_material_at_small_strain():
    """pybullet's stable Neo-Hookean with neo_hookean_parameters(G) is, linearised about the rest
    state, Hooke's law with Lame mu = G and lambda = 0 (Poisson's ratio 0): the tissue's continuum
    energy and its finite-element reference. Rest is stress-free."""
    g = CFG.tissue.shear_modulus
    mu, lam = neo_hookean_parameters(g)
    assert np.abs(_bullet_piola(np.eye(3), mu, lam)).max() < 1e-9 * g
    rng = np.random.default_rng(0)
    eps = 1e-6
    for _ in range(5):
        grad = rng.normal(size=(3, 3))
        strain = 0.5 * (grad + grad.T)
        stress = (_bullet_piola(np.eye(3) + eps * grad, mu, lam) - _bullet_piola(np.eye(3) - eps * grad, mu, lam)) / (2 * eps)
        hooke = 2.0 * g * strain  # + lambda tr(eps) I with lambda 0; the rotation's part is stress-free
        assert np.abs(stress - hooke).max() < 1e-6 * g * np.abs(grad).max()


@pytest.mark.parametrize("resolution", FEM_RESOLUTIONS)
@pytest.mark.parametrize("side", (+1, -1))
def test_pad_mesh_is_a_conforming_positively_oriented_l_shaped_block(resolution, side):
    m = pad_mesh((HX, HY, HZ), T, FEM_CELLS_THROUGH[resolution], side=side)
    vol = signed_volumes(m.node_x, m.tets)
    assert (vol > 0).all()
    # the L: the slab over the inner face (down to the tip layer) plus the slab under the core
    section = T * (2 * HZ + T) + 2 * HX * T
    assert m.volume == pytest.approx(2 * HY * section, rel=1e-12)
    # conforming: every triangle is shared by two tets wound opposite ways, or is on the boundary;
    # the boundary is closed (outward areas sum to zero) and has the L prism's area
    oriented = Counter()
    for t in m.tets:
        for f in FACES:
            tri = tuple(t[list(f)])
            k = int(np.argmin(tri))
            oriented[tri[k:] + tri[:k]] += 1  # rotate, keep the winding
    assert max(oriented.values()) == 1  # no triangle twice with the same winding
    boundary = [f for f in oriented if (f[0], f[2], f[1]) not in oriented]
    a = m.node_x[[f[0] for f in boundary]]
    b, c = m.node_x[[f[1] for f in boundary]], m.node_x[[f[2] for f in boundary]]
    area_vec = 0.5 * np.cross(b - a, c - a)
    assert np.abs(area_vec.sum(axis=0)).max() < 1e-15
    perimeter = 4 * HX + 4 * HZ + 4 * T
    assert np.linalg.norm(area_vec, axis=1).sum() == pytest.approx(2 * section + 2 * HY * perimeter, rel=1e-12)
    # every node is used and the pad is mirror symmetric along the face (no chiral drift)
    assert set(np.unique(m.tets)) == set(range(m.node_count))
    key = lambda x: set(map(tuple, np.round(x * 1e9).astype(np.int64)))  # noqa: E731
    assert key(m.node_x) == key(m.node_x * [1, -1, 1])
    # the pad sits on the inner face of this side's core
    assert (side * m.node_x[:, 0] >= -HX - 1e-12).all() and (side * m.node_x[:, 0]).max() == pytest.approx(HX + T)


@pytest.mark.parametrize("resolution", FEM_RESOLUTIONS)
def test_anchors_are_exactly_the_nodes_on_the_core_surface(resolution):
    for side in (+1, -1):
        m = pad_mesh((HX, HY, HZ), T, FEM_CELLS_THROUGH[resolution], side=side)
        x = m.node_x
        eps = 1e-9
        on_face = (np.abs(side * x[:, 0] - HX) < eps) & (x[:, 2] >= -HZ - eps)
        on_tip = (np.abs(x[:, 2] + HZ) < eps) & (np.abs(x[:, 0]) <= HX + eps)
        assert (m.node_anchored == (on_face | on_tip)).all()
        assert (np.abs(x[m.node_anchored, 1]) <= HY + eps).all()
        # nothing inside the core
        inside = (np.abs(x[:, 0]) < HX - eps) & (np.abs(x[:, 1]) < HY - eps) & (np.abs(x[:, 2]) < HZ - eps)
        assert not inside.any()
        assert m.node_anchored.sum() > 0.15 * m.node_count


def test_vtk_file_is_cached_by_content(tmp_path, monkeypatch):
    monkeypatch.setenv("SOFTGRASP_FEM_CACHE", str(tmp_path))
    m = pad_mesh((HX, HY, HZ), T, 1)
    path = vtk_file(m)
    assert path.startswith(str(tmp_path)) and vtk_file(m) == path
    text = open(path).read().split("\n")
    assert f"POINTS {m.node_count} double" in text and f"CELLS {len(m.tets)} {5 * len(m.tets)}" in text
    assert vtk_file(pad_mesh((HX, HY, HZ), T, 2)) != path


@pytest.mark.parametrize("resolution", FEM_RESOLUTIONS)
def test_scene_builds_with_the_pads_on_the_cores_and_they_hang_still(resolution):
    sc = GraspScene(replace(CFG, fingers=FemConfig(resolution=resolution), cylinder_xy=(0.1, 0.1)))  # out of reach
    try:
        c = sc.client
        assert c.getNumBodies() == 5  # ground, cylinder, gripper, two pads
        for _ in range(3):
            sc.step()
        pads = sc.fingers.pads
        for link, mesh, x in zip(pads.links, pads.meshes, pads.node_positions(), strict=True):
            assert len(x) == mesh.node_count
            pos, orn = c.getLinkState(sc.gripper.body, link)[4:6]
            rest = mesh.node_x @ np.asarray(c.getMatrixFromQuaternion(orn)).reshape(3, 3).T + pos
            assert np.linalg.norm(x - rest, axis=1).max() < 5e-4  # anchored, sagging well under 0.5 mm
        assert sc.penetration() == (0.0, 0.0)
        assert np.all(sc.finger_forces() == 0.0)
    finally:
        sc.close()


def test_one_substep_fails_at_first_contact_as_recorded():
    """The failure that FemConfig.substeps is there for: pybullet's deformable world integrates the
    elastic forces explicitly, and at the scene's 1/240 s the pads' nodes went 9 mm into the
    cylinder at the first squeeze and set it spinning at 2.4 rad/s (measured; 8 substeps: 0 mm,
    0.013 rad/s; over the whole grasp one substep knocks the cylinder over). The scene's
    penetration sees it through the fem hook."""
    sc = GraspScene(replace(CFG, fingers=FemConfig(substeps=1)))
    try:
        rec = run_grasp(sc, GraspPlan(approach=0.5, squeeze=0.4, lift=0.0, hold=0.0))
        assert rec.max_penetration > 0.005
        assert np.linalg.norm(sc.client.getBaseVelocity(sc.cylinder)[1]) > 1.0  # spun by the pads
    finally:
        sc.close()


def test_no_substeps_is_refused_naming_the_field():
    """At least one pybullet step per world step (the contract test gives every field a non-number)."""
    with pytest.raises(ValueError, match=r"FemConfig\.substeps"):
        FemConfig(substeps=0)


@pytest.mark.slow
def test_scripted_grasp_lifts_and_holds_the_default_cylinder():
    """Measured (coarse, 8 substeps): lift 49.5 mm, hold slip 0.11 mm, no penetration. With 4
    substeps the same grasp slid 17 mm in the hold (FemConfig.substeps)."""
    plan = GraspPlan()
    sc = GraspScene(CFG)
    try:
        rec = run_grasp(sc, plan)
    finally:
        sc.close()
    assert rec.held(plan) and rec.holds_without_slip(plan)
    assert rec.lift_height > 0.045 and rec.max_penetration < 1e-3
