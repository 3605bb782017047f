"""Tissue building: surface sampling, extrusion, implicit groups and pybullet shape import."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from softgrasp_env.config import TissueConfig
from softgrasp_env.tissue.builder import (
    CoreShape,
    build_combined_body,
    build_free_block,
    build_groups,
    core_shape_from_bullet,
    quat_z_to,
    sample_surface,
)
from softgrasp_env.tissue.collision import SHAPE_CODES, shape_distance_array
from softgrasp_env.tissue.rotation import quat_to_matrix

SHAPES = {
    "box": CoreShape("box", half_extents=(0.008, 0.02, 0.03)),
    "cube": CoreShape("box", half_extents=(0.025, 0.025, 0.025)),
    "cylinder": CoreShape("cylinder", radius=0.03, half_height=0.05),
    "capsule": CoreShape("capsule", radius=0.02, half_height=0.03),
    "sphere": CoreShape("sphere", radius=0.04),
}


def exact_area(shape: CoreShape) -> float:
    """Independent surface-area formulas."""
    if shape.kind == "box":
        x, y, z = (2.0 * h for h in shape.half_extents)
        return 2.0 * (x * y + y * z + x * z)
    r, h = shape.radius, 2.0 * shape.half_height
    if shape.kind == "sphere":
        return 4.0 * math.pi * r**2
    if shape.kind == "cylinder":
        return 2.0 * math.pi * r * h + 2.0 * math.pi * r**2  # wall + two discs
    return 2.0 * math.pi * r * h + 4.0 * math.pi * r**2  # wall + two hemispheres


def shape_params(shape: CoreShape) -> tuple[int, np.ndarray]:
    if shape.kind == "box":
        params = np.array(shape.half_extents, dtype=np.float64)
    elif shape.kind == "sphere":
        params = np.array([shape.radius, 0.0, 0.0])
    else:
        params = np.array([shape.radius, shape.half_height, 0.0])
    return SHAPE_CODES[shape.kind], params


def distances(shape: CoreShape, pts: np.ndarray) -> np.ndarray:
    """(N, 4) rows [signed distance, normal] of each point from the shape."""
    kind, params = shape_params(shape)
    return np.array([shape_distance_array(kind, params, np.ascontiguousarray(p)) for p in pts])


# --- CoreShape -----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(SHAPES))
def test_core_shape_area(name):
    shape = SHAPES[name]
    assert shape.area == pytest.approx(exact_area(shape), rel=1e-12)


def test_core_shape_area_known_values():
    assert CoreShape("box", half_extents=(0.5, 0.5, 0.5)).area == pytest.approx(6.0)
    assert CoreShape("sphere", radius=1.0).area == pytest.approx(4.0 * math.pi)
    assert CoreShape("cylinder", radius=1.0, half_height=0.5).area == pytest.approx(4.0 * math.pi)
    assert CoreShape("capsule", radius=1.0, half_height=0.5).area == pytest.approx(6.0 * math.pi)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(kind="cone", radius=1.0), "kind"),
        (dict(kind="box", half_extents=(0.0, 1.0, 1.0)), "half_extents"),
        (dict(kind="box", half_extents=(1.0, -1.0, 1.0)), "half_extents"),
        (dict(kind="box", half_extents=(1.0, 1.0)), "half_extents"),
        (dict(kind="box"), "half_extents"),
        (dict(kind="sphere", radius=0.0), "radius"),
        (dict(kind="sphere", radius=float("nan")), "radius"),
        (dict(kind="cylinder", radius=-0.1, half_height=1.0), "radius"),
        (dict(kind="cylinder", radius=0.1, half_height=0.0), "half_height"),
        (dict(kind="capsule", radius=0.1), "half_height"),
        (dict(kind="capsule", radius=0.1, half_height=float("nan")), "half_height"),
    ],
)
def test_core_shape_rejects_bad_input(kwargs, field):
    with pytest.raises(ValueError, match=field):
        CoreShape(**kwargs)


@pytest.mark.parametrize("half_extents", [(float("nan"), 1.0, 1.0), (1.0, float("nan"), 1.0)])
def test_core_shape_rejects_nan_half_extents(half_extents):
    with pytest.raises(ValueError, match="half_extents"):
        CoreShape("box", half_extents=half_extents)


def test_core_shape_ignores_fields_of_other_kinds():
    # a sphere does not look at half_extents, a box does not look at radius
    CoreShape("sphere", radius=0.1, half_extents=(-1.0, 0.0, 0.0))
    CoreShape("box", half_extents=(0.1, 0.1, 0.1), radius=-1.0)
    CoreShape("sphere", radius=0.1, half_height=-1.0)


# --- sample_surface ------------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(SHAPES))
@pytest.mark.parametrize("spacing", [0.004, 0.01, 0.037])
def test_sample_surface_areas_sum_to_exact_area(name, spacing):
    shape = SHAPES[name]
    pts, nrm, area = sample_surface(shape, spacing)
    assert pts.shape == nrm.shape == (area.size, 3)
    assert (area > 0.0).all()
    assert area.sum() == pytest.approx(exact_area(shape), rel=1e-9)


@pytest.mark.parametrize("name", list(SHAPES))
@pytest.mark.parametrize("spacing", [0.005, 0.013])
def test_sample_surface_points_on_surface_with_outward_unit_normals(name, spacing):
    shape = SHAPES[name]
    pts, nrm, _ = sample_surface(shape, spacing)
    d = distances(shape, pts)
    assert np.abs(d[:, 0]).max() < 1e-9
    assert np.abs(np.linalg.norm(nrm, axis=1) - 1.0).max() < 1e-12
    # The sampled normal is the shape's normal there (no sample sits on an edge) ...
    assert np.abs(nrm - d[:, 1:]).max() < 1e-9
    # ... it points away from the (convex) shape's centre, and a step along it leaves the shape.
    assert ((pts * nrm).sum(axis=1) > 0.0).all()
    step = 1e-4
    assert np.abs(distances(shape, pts + step * nrm)[:, 0] - step).max() < 1e-9
    assert np.abs(distances(shape, pts - step * nrm)[:, 0] + step).max() < 1e-9


@pytest.mark.parametrize("name", list(SHAPES))
def test_sample_surface_points_are_distinct_and_spread(name):
    shape = SHAPES[name]
    spacing = 0.006
    pts, _, area = sample_surface(shape, spacing)
    d2 = ((pts[:, None, :] - pts[None, :, :]) ** 2).sum(axis=2)
    np.fill_diagonal(d2, np.inf)
    nearest = np.sqrt(d2.min(axis=1))
    assert nearest.min() > 0.4 * spacing
    assert nearest.max() < 1.5 * spacing
    # about one point per spacing^2 of area, each standing for a similar area
    assert 0.7 < pts.shape[0] * spacing**2 / shape.area < 1.4
    assert area.min() > 0.5 * area.max()


@pytest.mark.parametrize("name", list(SHAPES))
def test_sample_surface_count_scales_with_density(name):
    """Rounding to whole rows quantises coarse samplings, so this uses several points per edge."""
    shape = SHAPES[name]
    for density in (20_000.0, 40_000.0, 80_000.0):
        n1 = sample_surface(shape, TissueConfig(particle_density=density).spacing)[0].shape[0]
        n2 = sample_surface(shape, TissueConfig(particle_density=2.0 * density).spacing)[0].shape[0]
        assert 1.6 <= n2 / n1 <= 2.4, (density, n1, n2)


def test_sample_surface_sphere_and_cylinder_are_symmetric():
    """Even spread: the samples' area-weighted centroid is the shape's centre."""
    for name in ("sphere", "cylinder", "capsule", "box"):
        pts, _, area = sample_surface(SHAPES[name], 0.007)
        centroid = (area[:, None] * pts).sum(axis=0) / area.sum()
        assert np.abs(centroid).max() < 0.05 * 0.007, name


@pytest.mark.parametrize("spacing", [0.0, -0.01, float("nan")])
def test_sample_surface_rejects_bad_spacing(spacing):
    with pytest.raises(ValueError, match="spacing"):
        sample_surface(SHAPES["box"], spacing)


# --- quat_z_to -----------------------------------------------------------------------------------


def test_quat_z_to_maps_z_onto_targets():
    rng = np.random.default_rng(5)
    special = np.array([[0, 0, 1], [0, 0, -1], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]], dtype=np.float64)
    rand = rng.normal(size=(200, 3))
    n = np.concatenate([special, rand / np.linalg.norm(rand, axis=1, keepdims=True)])
    q = quat_z_to(n)
    assert q.shape == (n.shape[0], 4)
    assert np.abs(np.linalg.norm(q, axis=1) - 1.0).max() < 1e-12
    for qi, ni in zip(q, n, strict=True):
        r = quat_to_matrix(qi)
        assert np.abs(r @ [0.0, 0.0, 1.0] - ni).max() < 1e-12
        assert abs(np.linalg.det(r) - 1.0) < 1e-12
    # +z needs no turn at all
    assert np.abs(q[0] - [0.0, 0.0, 0.0, 1.0]).max() < 1e-15


def test_quat_z_to_is_the_shortest_arc():
    """Shortest arc: the turn axis is perpendicular to z (q_z = 0) and the angle is acos(z . n)."""
    rng = np.random.default_rng(6)
    n = rng.normal(size=(100, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    q = quat_z_to(n)
    assert np.abs(q[:, 2]).max() < 1e-15
    angle = 2.0 * np.arctan2(np.linalg.norm(q[:, :3], axis=1), q[:, 3])
    assert np.abs(angle - np.arccos(np.clip(n[:, 2], -1.0, 1.0))).max() < 1e-9


def test_quat_z_to_is_accurate_next_to_minus_z():
    s = 1e-5
    n = np.array([[s, 0.0, -math.sqrt(1.0 - s * s)]])
    r = quat_to_matrix(quat_z_to(n)[0])
    assert np.abs(r[:, 2] - n[0]).max() < 1e-9


# --- build_combined_body -------------------------------------------------------------------------


def check_groups(model, group_size: int) -> None:
    n = model.particle_count
    offsets, members = model.group_offsets, model.group_members
    assert offsets.dtype == np.int32 and members.dtype == np.int32
    assert offsets.shape == (n + 1,)
    assert offsets[0] == 0 and offsets[-1] == members.shape[0]
    assert (np.diff(offsets) == group_size).all()
    assert model.group_rest_offset.shape == (members.shape[0], 3)
    m = model.particle_mass
    x = model.particle_rest_x
    for i in range(n):
        g = members[offsets[i] : offsets[i + 1]]
        assert g[0] == i
        assert len(set(g.tolist())) == group_size
        assert ((g >= 0) & (g < n)).all()
        if model.particle_partner[i] >= 0:
            assert model.particle_partner[i] in g
        off = model.group_rest_offset[offsets[i] : offsets[i + 1]]
        assert np.abs((m[g, None] * off).sum(axis=0)).max() < 1e-15
        com = (m[g, None] * x[g]).sum(axis=0) / m[g].sum()
        assert np.abs(off - (x[g] - com)).max() < 1e-15


def check_nearest(model) -> None:
    """Each group holds the nearest non-partner particles: none left out is closer than one taken."""
    x = model.particle_rest_x
    offsets, members = model.group_offsets, model.group_members
    for i in range(model.particle_count):
        g = members[offsets[i] : offsets[i + 1]]
        others = [j for j in g[1:] if j != model.particle_partner[i]]
        if not others:
            continue
        taken = np.linalg.norm(x[others] - x[i], axis=1).max()
        mask = np.ones(model.particle_count, bool)
        mask[g] = False
        if mask.any():
            assert np.linalg.norm(x[mask] - x[i], axis=1).min() >= taken - 1e-15


@pytest.mark.parametrize("name", ["box", "cylinder", "capsule", "sphere"])
def test_combined_body_normal_extrusion(name):
    shape = SHAPES[name]
    tissue = TissueConfig()
    model = build_combined_body(shape, tissue)
    n = model.particle_count
    k = n // 2
    assert n == 2 * k and k > 20
    att = model.particle_attached
    assert att.dtype == np.bool_
    assert att[:k].all() and not att[k:].any()

    x = model.particle_rest_x
    d = distances(shape, x[att])
    assert np.abs(d[:, 0]).max() < 1e-9  # attached particles sit on the core surface

    partner = model.particle_partner
    assert (partner[partner] == np.arange(n)).all()  # symmetric
    assert (partner != np.arange(n)).all()
    assert (att[partner] != att).all()  # every pair is one attached, one outer
    outer = partner[np.flatnonzero(att)]
    ext = x[outer] - x[att]
    assert np.abs(np.linalg.norm(ext, axis=1) - tissue.extrude).max() < 1e-12
    assert np.abs(ext - tissue.extrude * d[:, 1:]).max() < 1e-12  # along the outward normal
    assert np.abs(distances(shape, x[outer])[:, 0] - tissue.extrude).max() < 1e-12

    # mass: the layer (area x extrude) split evenly between the pair
    assert model.particle_mass.sum() == pytest.approx(tissue.mass_density * shape.area * tissue.extrude, rel=1e-9)
    assert np.abs(model.particle_mass[att] - model.particle_mass[outer]).max() == 0.0
    assert np.abs(model.particle_inv_mass * model.particle_mass - 1.0).max() < 1e-14

    # orientation: local z along the extrusion direction, the same for both partners
    for i in range(k):
        r = quat_to_matrix(model.particle_rest_q[i])
        assert np.abs(r[:, 2] - d[i, 1:]).max() < 1e-12
    assert np.abs(model.particle_rest_q[att] - model.particle_rest_q[outer]).max() == 0.0
    # radii: tangential from the spacing, flat along the normal
    assert np.abs(model.particle_radii[:, 2] - tissue.normal_radius).max() == 0.0
    assert (model.particle_radii[:, 0] == model.particle_radii[:, 1]).all()
    assert model.particle_radii[:, 0].mean() == pytest.approx(tissue.radius_scale * tissue.spacing, rel=0.1)

    check_groups(model, tissue.group_size)


@pytest.mark.parametrize("name", ["box", "cylinder", "capsule", "sphere"])
def test_combined_body_radial_extrusion(name):
    shape = SHAPES[name]
    tissue = TissueConfig(extrude=0.005)
    model = build_combined_body(shape, tissue, extrude_direction="radial")
    x, att, partner = model.particle_rest_x, model.particle_attached, model.particle_partner
    a = x[att]
    ext = x[partner[att]] - a
    radial = a / np.linalg.norm(a, axis=1, keepdims=True)
    assert np.abs(ext - tissue.extrude * radial).max() < 1e-12
    assert np.abs(distances(shape, a)[:, 0]).max() < 1e-9
    for i in np.flatnonzero(att):
        assert np.abs(quat_to_matrix(model.particle_rest_q[i])[:, 2] - radial[i]).max() < 1e-12
    check_groups(model, tissue.group_size)


def test_combined_body_radial_equals_normal_on_a_sphere():
    shape = SHAPES["sphere"]
    a = build_combined_body(shape, TissueConfig())
    b = build_combined_body(shape, TissueConfig(), extrude_direction="radial")
    assert np.abs(a.particle_rest_x - b.particle_rest_x).max() < 1e-15


def test_combined_body_radial_differs_from_normal_on_a_box():
    shape = SHAPES["box"]
    a = build_combined_body(shape, TissueConfig())
    b = build_combined_body(shape, TissueConfig(), extrude_direction="radial")
    assert np.abs(a.particle_rest_x - b.particle_rest_x).max() > 1e-3


def test_combined_body_with_shape_offset():
    shape = SHAPES["cylinder"]
    offset = np.array([0.01, -0.02, 0.005])
    tissue = TissueConfig()
    base = build_combined_body(shape, tissue)
    moved = build_combined_body(shape, tissue, shape_offset=offset)
    assert np.abs(moved.particle_rest_x - (base.particle_rest_x + offset)).max() < 1e-15
    att = moved.particle_attached
    assert np.abs(distances(shape, moved.particle_rest_x[att] - offset)[:, 0]).max() < 1e-9
    # radial extrusion goes from the centre of mass (the frame origin), not the shape centre
    radial = build_combined_body(shape, tissue, shape_offset=offset, extrude_direction="radial")
    a = radial.particle_rest_x[att]
    ext = radial.particle_rest_x[radial.particle_partner[att]] - a
    assert np.abs(ext - tissue.extrude * a / np.linalg.norm(a, axis=1, keepdims=True)).max() < 1e-12


@pytest.mark.parametrize("group_size", [4, 5, 12])
def test_combined_body_group_size(group_size):
    tissue = TissueConfig(group_size=group_size)
    model = build_combined_body(SHAPES["capsule"], tissue)
    check_groups(model, group_size)
    check_nearest(model)


def test_combined_body_metadata_from_config():
    tissue = TissueConfig(shear_modulus=5e3, friction_static=0.8, friction_dynamic=0.4, particle_density=20_000.0,
                          mass_density=1200.0, extrude=0.004)  # fmt: skip
    shape = SHAPES["box"]
    model = build_combined_body(shape, tissue)
    assert model.body_count == 1
    assert model.body_particle_offsets.tolist() == [0, model.particle_count]
    assert model.body_core_shape.tolist() == [-1]
    assert (model.group_kappa > 0).all()  # G / (rho l^2) per group: tests/tissue/test_compliant.py
    stiffer = build_combined_body(shape, replace(tissue, shear_modulus=1e4))
    np.testing.assert_allclose(stiffer.group_kappa, 2.0 * model.group_kappa)
    assert model.body_friction.tolist() == [[0.8, 0.4]]
    assert (model.particle_body == 0).all()
    assert model.particle_mass.sum() == pytest.approx(1200.0 * shape.area * 0.004, rel=1e-9)
    for name in ("particle_rest_x", "particle_rest_q", "particle_radii", "particle_mass", "group_rest_offset"):
        arr = getattr(model, name)
        assert arr.dtype == np.float64 and arr.flags.c_contiguous, name
    # more density, more particles
    assert model.particle_count > build_combined_body(shape, TissueConfig()).particle_count


def test_combined_body_rejects_bad_direction():
    with pytest.raises(ValueError, match="extrude_direction"):
        build_combined_body(SHAPES["box"], TissueConfig(), extrude_direction="sideways")


# --- build_free_block ----------------------------------------------------------------------------


def test_free_block_lattice():
    tissue = TissueConfig(mass_density=900.0, group_size=6)
    h = (0.02, 0.01, 0.015)
    model = build_free_block(h, tissue, spacing=0.005)
    n = model.particle_count
    assert n == 8 * 4 * 6
    x = model.particle_rest_x
    assert np.abs(x.mean(axis=0)).max() < 1e-15
    assert (np.abs(x) < np.array(h)).all()
    assert np.abs(x.max(axis=0) - (np.array(h) - 0.0025)).max() < 1e-15
    assert model.particle_mass.sum() == pytest.approx(900.0 * 8 * h[0] * h[1] * h[2], rel=1e-12)
    assert (model.particle_partner == -1).all()
    assert not model.particle_attached.any()
    assert np.abs(model.particle_rest_q - [0.0, 0.0, 0.0, 1.0]).max() == 0.0
    assert np.abs(model.particle_radii - 0.0025).max() < 1e-15  # half the cubic cell
    assert model.body_core_shape.tolist() == [-1]
    check_groups(model, 6)
    check_nearest(model)


def test_free_block_default_spacing_from_density():
    tissue = TissueConfig(particle_density=40_000.0)  # spacing 5 mm
    model = build_free_block((0.01, 0.01, 0.01), tissue)
    assert model.particle_count == 4**3


@pytest.mark.parametrize(
    "half_extents, spacing, field",
    [
        ((0.0, 0.01, 0.01), None, "half_extents"),
        ((0.01, -0.01, 0.01), None, "half_extents"),
        ((0.01, 0.01), None, "half_extents"),
        ((0.01, 0.01, 0.01), -0.001, "spacing"),
        ((0.01, 0.01, 0.01), 0.0, "spacing"),
    ],
)
def test_free_block_rejects_bad_input(half_extents, spacing, field):
    with pytest.raises(ValueError, match=field):
        build_free_block(half_extents, TissueConfig(), spacing=spacing)


# --- build_groups --------------------------------------------------------------------------------


def test_build_groups_on_a_line():
    x = np.array([[0.0, 0, 0], [1.0, 0, 0], [3.0, 0, 0], [6.0, 0, 0], [10.0, 0, 0]])
    mass = np.array([1.0, 1.0, 2.0, 1.0, 4.0])
    partner = np.array([4, -1, -1, -1, 0])
    offsets, members, rest = build_groups(x, mass, partner, 3)
    groups = [members[offsets[i] : offsets[i + 1]].tolist() for i in range(5)]
    assert groups == [[0, 4, 1], [1, 0, 2], [2, 1, 0], [3, 2, 4], [4, 0, 3]]
    # rest offsets from each group's mass-weighted centre
    g0 = [0, 4, 1]
    com = (mass[g0, None] * x[g0]).sum(axis=0) / mass[g0].sum()
    assert np.abs(rest[0:3] - (x[g0] - com)).max() < 1e-15
    assert com[0] == pytest.approx(41.0 / 6.0)


def test_build_groups_small_body_uses_every_particle():
    x = np.array([[0.0, 0, 0], [1.0, 0, 0], [0.0, 2.0, 0]])
    offsets, members, _ = build_groups(x, np.ones(3), np.full(3, -1), 8)
    assert offsets.tolist() == [0, 3, 6, 9]
    for i in range(3):
        g = members[offsets[i] : offsets[i + 1]]
        assert g[0] == i and sorted(g.tolist()) == [0, 1, 2]


def test_build_groups_leaves_inputs_untouched():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(30, 3))
    mass = rng.uniform(0.5, 2.0, size=30)
    partner = np.concatenate([np.arange(15, 30), np.arange(15)])
    x0, m0, p0 = x.copy(), mass.copy(), partner.copy()
    build_groups(x, mass, partner, 8)
    assert (x == x0).all() and (mass == m0).all() and (partner == p0).all()


def _groups_by_all_pairs(x, partner, size):
    """The definition itself: the partner, then the nearest others, ties to the lower index."""
    d2 = ((x[:, None, :] - x[None, :, :]) ** 2).sum(axis=2)
    out = []
    for i in range(len(x)):
        row = [i] + ([int(partner[i])] if partner[i] >= 0 else [])
        others = [int(j) for j in np.argsort(d2[i], kind="stable") if j != i and j != partner[i]]
        out.append((row + others)[:size])
    return np.array(out)


@pytest.mark.parametrize("kind", ["box", "cylinder", "sphere", "capsule", "lattice", "random", "sheet"])
@pytest.mark.parametrize("size", [4, 8, 16])
def test_build_groups_matches_the_all_pairs_definition(kind, size):
    """The grid search finds exactly the groups an all-pairs distance table gives, ties included
    (lattices and sampled surfaces are full of equal distances)."""
    rng = np.random.default_rng(1)
    if kind in ("box", "cylinder", "sphere", "capsule"):
        m = build_combined_body(CoreShape(kind, half_extents=(0.008, 0.02, 0.03), radius=0.02, half_height=0.03),
                                TissueConfig())  # fmt: skip
        x, partner = m.particle_rest_x, m.particle_partner
    elif kind == "lattice":
        m = build_free_block((0.02, 0.02, 0.02), TissueConfig(), spacing=0.008)
        x, partner = m.particle_rest_x, m.particle_partner
    elif kind == "random":
        x, partner = rng.normal(size=(400, 3)), np.full(400, -1)
    else:  # a nearly flat sheet: the grid must not assume a volume
        x, partner = rng.uniform(size=(300, 3)) * [1.0, 1.0, 1e-3], np.full(300, -1)
    offsets, members, _ = build_groups(x, np.ones(len(x)), partner, size)
    assert np.array_equal(members.reshape(len(x), -1), _groups_by_all_pairs(x, partner, min(size, len(x))))


def test_build_groups_memory_is_linear_in_the_particle_count():
    """1e6 particles per m^2, 250 times the default density (16,000 particles a finger, builds in well under a second of
    arithmetic and a few kB per particle; the all-pairs table needed n^2 * 24 bytes (6 GB here)."""
    import tracemalloc

    tissue = TissueConfig(particle_density=1e6)  # 1 mm spacing
    build_combined_body(CoreShape("box", half_extents=(0.008, 0.02, 0.03)), TissueConfig())  # compiled
    tracemalloc.start()
    m = build_combined_body(CoreShape("box", half_extents=(0.008, 0.02, 0.03)), tissue)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert m.particle_count == 16_000
    assert peak < 2_000 * m.particle_count


def test_a_tissue_that_cannot_fit_is_refused_before_building(monkeypatch):
    from softgrasp_env.tissue import builder

    monkeypatch.setattr(builder, "_available_bytes", lambda: 100 * 2**20)  # 100 MiB free
    with pytest.raises(ValueError, match=r"combined body: 64,000 particles would need about 0\.2 GiB.*density"):
        build_combined_body(CoreShape("box", half_extents=(0.008, 0.02, 0.03)), TissueConfig(particle_density=4e6))
    with pytest.raises(ValueError, match="free block"):
        build_free_block((0.1, 0.1, 0.1), TissueConfig(), spacing=0.001)


def test_combined_body_on_chosen_faces_only():
    """Tissue only where contact can happen: the chosen faces of a box core, the rest bare. Areas
    still sum to exactly the covered faces' area, and every attached particle lies on one of them."""
    box = CoreShape("box", half_extents=(0.008, 0.02, 0.03))
    tissue = TissueConfig(particle_density=10_000.0)  # 10 mm spacing: counts worked out by hand
    full = build_combined_body(box, tissue)
    part = build_combined_body(box, tissue, faces=("+x", "-z"))
    att = part.particle_attached
    x = part.particle_rest_x[att]
    on_plus_x = np.isclose(x[:, 0], 0.008)
    on_minus_z = np.isclose(x[:, 2], -0.03)
    assert (on_plus_x | on_minus_z).all() and on_plus_x.any() and on_minus_z.any()
    pts, _, area = sample_surface(box, tissue.spacing, faces=("+x", "-z"))
    assert area.sum() == pytest.approx(4 * 0.02 * 0.03 + 4 * 0.008 * 0.02, rel=1e-12)
    assert part.particle_count == 64 and full.particle_count == 176
    with pytest.raises(ValueError, match="subset"):
        build_combined_body(box, tissue, faces=("+w",))
    with pytest.raises(ValueError, match="box core only"):
        sample_surface(CoreShape("sphere", radius=0.01), 0.01, faces=("+x",))


def test_build_groups_rejects_a_single_particle():
    with pytest.raises(ValueError, match="at least 2"):
        build_groups(np.zeros((1, 3)), np.ones(1), np.full(1, -1), 8)


# --- core_shape_from_bullet ----------------------------------------------------------------------


@pytest.fixture
def bullet():
    import pybullet as p

    from softgrasp_env.sim.bullet import connect

    client = connect()
    try:
        yield client, p
    finally:
        client.disconnect()


def test_core_shape_from_bullet(bullet):
    client, p = bullet

    def body(**kwargs):
        frame_pos = kwargs.pop("inertial_pos", [0.0, 0.0, 0.0])
        shape = client.createCollisionShape(**kwargs)
        return client.createMultiBody(0.5, shape, basePosition=[1.0, 2.0, 3.0], baseInertialFramePosition=frame_pos)

    shape, pos, orn = core_shape_from_bullet(client, body(shapeType=p.GEOM_BOX, halfExtents=[0.01, 0.02, 0.03]))
    assert shape.kind == "box"
    assert shape.half_extents == pytest.approx((0.01, 0.02, 0.03), rel=1e-9)
    assert np.abs(pos).max() == 0.0 and np.abs(orn - [0.0, 0.0, 0.0, 1.0]).max() == 0.0
    assert pos.dtype == np.float64 and orn.dtype == np.float64

    shape, _, _ = core_shape_from_bullet(client, body(shapeType=p.GEOM_CYLINDER, radius=0.03, height=0.1))
    assert shape.kind == "cylinder"
    assert shape.radius == pytest.approx(0.03, rel=1e-9)
    assert shape.half_height == pytest.approx(0.05, rel=1e-9)

    shape, _, _ = core_shape_from_bullet(client, body(shapeType=p.GEOM_CAPSULE, radius=0.02, height=0.08))
    assert shape.kind == "capsule"
    assert shape.radius == pytest.approx(0.02, rel=1e-9)
    assert shape.half_height == pytest.approx(0.04, rel=1e-9)

    shape, _, _ = core_shape_from_bullet(client, body(shapeType=p.GEOM_SPHERE, radius=0.05))
    assert shape.kind == "sphere"
    assert shape.radius == pytest.approx(0.05, rel=1e-9)

    # the pose is relative to the centre-of-mass frame
    b = body(shapeType=p.GEOM_BOX, halfExtents=[0.01, 0.02, 0.03], collisionFramePosition=[0.1, 0.2, 0.3])
    _, pos, _ = core_shape_from_bullet(client, b)
    assert pos == pytest.approx([0.1, 0.2, 0.3], abs=1e-12)
    b = body(shapeType=p.GEOM_BOX, halfExtents=[0.01, 0.02, 0.03], inertial_pos=[0.05, 0.0, 0.0])
    _, pos, _ = core_shape_from_bullet(client, b)
    assert pos == pytest.approx([-0.05, 0.0, 0.0], abs=1e-12)


def test_core_shape_from_bullet_rejects_unsupported(bullet):
    client, p = bullet
    plane = client.createMultiBody(0.0, client.createCollisionShape(p.GEOM_PLANE))
    with pytest.raises(ValueError, match="not a supported core"):
        core_shape_from_bullet(client, plane)
    empty = client.createMultiBody(1.0, -1)
    with pytest.raises(ValueError, match="exactly one collision shape"):
        core_shape_from_bullet(client, empty)
    compound = client.createMultiBody(
        1.0,
        client.createCollisionShapeArray(
            [p.GEOM_BOX, p.GEOM_SPHERE], halfExtents=[[0.01, 0.02, 0.03], [0.0, 0.0, 0.0]], radii=[0.0, 0.02]
        ),
    )
    with pytest.raises(ValueError, match="exactly one collision shape"):
        core_shape_from_bullet(client, compound)


def test_core_shape_from_bullet_feeds_the_builder(bullet):
    client, p = bullet
    b = client.createMultiBody(0.05, client.createCollisionShape(p.GEOM_BOX, halfExtents=[0.008, 0.02, 0.03]))
    shape, pos, _ = core_shape_from_bullet(client, b)
    model = build_combined_body(shape, TissueConfig(), shape_offset=pos)
    assert model.particle_mass.sum() == pytest.approx(1000.0 * 0.008 * 8 * (0.008 * 0.02 + 0.02 * 0.03 + 0.008 * 0.03),
                                                      rel=1e-6)  # fmt: skip
