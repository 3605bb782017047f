"""Particle layers through the pad's thickness (TissueConfig.layers; tissue/builder.py,
build_combined_body and _layered): one layer is the two-layer pad exactly; L layers give L + 1
particle layers at depths k extrude / L with equal masses and the trapezoid rule's group volumes
(a uniform stress in balance at every inner particle), inner particles that stay off the
cylinder, groups across the layers, and a continuum pad near the finite-element reference
(benchmarks/pad_reference.py; docs/results/spatial-convergence.md)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from softgrasp_env.config import TissueConfig
from softgrasp_env.fingers.tactile import face_footprints
from softgrasp_env.tissue.builder import (
    CoreShape,
    build_combined_body,
    build_groups,
    quat_z_to,
    sample_surface,
    surface_particles,
)

FACE = (0.008, 0.02, 0.03)  # the scene's finger core: 16 x 40 x 60 mm, tissue on +x
BOX = CoreShape("box", half_extents=FACE)
AREA = 4 * FACE[1] * FACE[2]
CONTINUUM = TissueConfig(group_energy="continuum")


def pad(layers: int, density: float = 16_000.0, tissue: TissueConfig = CONTINUUM):
    return build_combined_body(BOX, replace(tissue, layers=layers, particle_density=density), faces=("+x",))


@pytest.mark.parametrize("shape", [BOX, CoreShape("capsule", radius=0.02, half_height=0.03)], ids=["box", "capsule"])
def test_one_layer_is_the_two_layer_pad(shape):
    """layers=1 (the default) builds exactly the thesis' pad: attached particles on the surface,
    one outer partner extrude further out along the normal, half the prism's mass each, the same
    radii and orientations, partners paired, groups as build_groups makes them from the partners."""
    tissue = TissueConfig(particle_density=8_000.0)
    assert tissue.layers == 1
    model = build_combined_body(shape, tissue)
    pts, nrm, area = sample_surface(shape, tissue.spacing)
    k = pts.shape[0]
    rest_x = np.concatenate([pts, pts + tissue.extrude * nrm])
    m = tissue.mass_density * area * tissue.extrude
    mass = np.concatenate([0.5 * m, 0.5 * m])
    t = tissue.radius_scale * np.sqrt(area)
    radii = np.tile(np.stack([t, t, np.full(k, tissue.normal_radius)], axis=1), (2, 1))
    partner = np.concatenate([np.arange(k, 2 * k), np.arange(k)])
    offsets, members, rest = build_groups(rest_x, mass, partner, tissue.group_size)
    for got, want in ((model.particle_rest_x, rest_x), (model.particle_mass, mass), (model.particle_radii, radii),
                      (model.particle_rest_q, np.tile(quat_z_to(nrm), (2, 1))), (model.particle_partner, partner),
                      (model.particle_attached, np.arange(2 * k) < k), (model.group_offsets, offsets),
                      (model.group_members, members), (model.group_rest_offset, rest)):  # fmt: skip
        assert got.dtype == np.asarray(want).dtype or got.dtype.kind == np.asarray(want).dtype.kind
        assert got.shape == want.shape and got.tobytes() == want.astype(got.dtype).tobytes()
    assert (surface_particles(model) == ~model.particle_attached).all()


@pytest.mark.parametrize("layers", [2, 4])
def test_layers_sit_at_their_depths_with_the_prisms_mass(layers):
    tissue = replace(CONTINUUM, layers=layers, particle_density=16_000.0)
    model = pad(layers, 16_000.0)
    pts, _, area = sample_surface(BOX, tissue.spacing, faces=("+x",))
    k = pts.shape[0]
    n = model.particle_count
    assert n == (layers + 1) * k
    depth = (model.particle_rest_x[:, 0] - FACE[0]).reshape(layers + 1, k)
    np.testing.assert_allclose(depth, np.arange(layers + 1)[:, None] * tissue.extrude / layers + 0 * depth, atol=1e-15)
    # every column is the surface point's, straight out along the normal
    np.testing.assert_array_equal(model.particle_rest_x[:, 1:].reshape(layers + 1, k, 2), np.tile(pts[:, 1:], (layers + 1, 1, 1)))
    # the column's prism shared equally by its particles; the groups' volumes by the trapezoid rule:
    # half a slice at each end, a whole slice inside, the pad's volume in all
    share = model.particle_mass.reshape(layers + 1, k) / (tissue.mass_density * area * tissue.extrude)
    np.testing.assert_allclose(share, 1.0 / (layers + 1) + 0 * share, rtol=1e-12)
    np.testing.assert_allclose(model.particle_mass.sum(), tissue.mass_density * AREA * tissue.extrude, rtol=1e-12)
    volume = model.group_continuum[:, 6].reshape(layers + 1, k) / (2.0 * tissue.shear_modulus)
    slices = volume / (area * tissue.extrude / layers)
    np.testing.assert_allclose(slices, np.r_[0.5, np.ones(layers - 1), 0.5][:, None] + 0 * slices, rtol=1e-12)
    np.testing.assert_allclose(volume.sum(), AREA * tissue.extrude, rtol=1e-12)
    # attached: the first layer only; the surface: the last; paired with each other, inner ones with none
    layer = np.repeat(np.arange(layers + 1), k)
    assert (model.particle_attached == (layer == 0)).all()
    assert (surface_particles(model) == (layer == layers)).all()
    p = model.particle_partner
    assert (p[layer == 0] == np.flatnonzero(layer == layers)).all() and (p[layer == layers] == np.arange(k)).all()
    assert (p[(layer > 0) & (layer < layers)] == -1).all()
    # the surface keeps its radii; the inner layers' normal radius is a quarter of the layer spacing
    r = model.particle_radii
    assert (r[layer == layers, 2] == tissue.normal_radius).all() and (r[layer == 0, 2] == tissue.normal_radius).all()
    np.testing.assert_allclose(r[(layer > 0) & (layer < layers), 2], 0.25 * tissue.extrude / layers)
    np.testing.assert_array_equal(r[:, 0], r[layer == layers, 0].tolist() * (layers + 1))


@pytest.mark.parametrize("layers", [2, 4])
def test_groups_reach_across_one_layer_spacing(layers):
    """Each group is its particle, the particles directly below and above it, and its group_size
    nearest others in its own layer (the default 8: the two whole rings of the face's grid, so a
    group inside the face is symmetric along it): cross-layer members, none more than one layer
    away."""
    model = pad(layers, 64_000.0)
    n, k = model.particle_count, model.particle_count // (layers + 1)
    layer = np.arange(n) // k
    off, mem = model.group_offsets, model.group_members
    x = model.particle_rest_x
    for i in range(n):
        g = mem[off[i]:off[i + 1]]
        lay = layer[g]
        assert lay[0] == layer[i] and np.abs(lay - layer[i]).max() == 1
        column = [i + k] if layer[i] < layers else []
        column += [i - k] if layer[i] > 0 else []
        assert g.size == 1 + len(column) + CONTINUUM.group_size
        assert list(g[1:1 + len(column)]) == column
        assert (lay[1 + len(column):] == layer[i]).all()
        ring = x[g[1 + len(column):], 1:] - x[i, 1:]  # along the face (y, z)
        inside = abs(x[i, 1]) < 0.015 and abs(x[i, 2]) < 0.025  # two spacings in from the face's edges
        if inside:  # away from the rim: whole rings, so the members' offsets cancel
            np.testing.assert_allclose(ring.sum(axis=0), 0.0, atol=1e-12)
    # the groups' extent across the layer is one spacing (two for an inner layer), not the pad's thickness
    across = np.abs(model.group_rest_offset[:, 0]).max()
    assert across <= 2 * CONTINUUM.extrude / layers * (1 + 1e-9)


@pytest.mark.parametrize("layers", [2, 3, 4])
@pytest.mark.parametrize("density", [16_000.0, 64_000.0])
def test_a_uniform_stress_is_in_balance_at_every_inner_layer(layers, density):
    """The patch test through the thickness (the integration constraint of particle methods, Chen
    et al. 2001): under a uniform stress the continuum energy's force on particle j is
    2 G sum_g V_g eps b_gj, so each layer's shares along the normal, sum_g V_g b_gj . d over its
    particles, must be -1 (the core), 0 (every inner layer) and +1 (the surface) times the face's
    area. With the trapezoid rule's masses they were -0.918 / -0.164 / 0 / +0.164 / +0.918 (four
    layers, 64,000 per m^2), and a uniformly sheared pad shears in an S."""
    model = pad(layers, density)
    n, k = model.particle_count, model.particle_count // (layers + 1)
    layer = np.arange(n) // k
    cont = model.group_continuum
    off, mem, q = model.group_offsets, model.group_members, model.group_rest_offset
    share = np.zeros(layers + 1)
    for g in range(n):
        e = slice(off[g], off[g + 1])
        ainv = cont[g, [[0, 1, 2], [1, 3, 4], [2, 4, 5]]]
        b = (model.particle_mass[mem[e], None] * q[e]) @ ainv
        np.add.at(share, layer[mem[e]], cont[g, 6] / (2.0 * CONTINUUM.shear_modulus) * b[:, 0])  # d = +x
    want = np.zeros(layers + 1)
    want[0], want[-1] = -1.0, 1.0
    np.testing.assert_allclose(share / AREA, want, atol=1e-9)


def test_the_taxels_read_the_surface_layer():
    """face_footprints counts the face's cells from the surface particles: the same cells at any
    layer count."""
    one, four = pad(1), pad(4)
    f1 = face_footprints(one.particle_rest_x, surface_particles(one), one.body_particle_offsets, FACE[1], FACE[2])
    f4 = face_footprints(four.particle_rest_x, surface_particles(four), four.body_particle_offsets, FACE[1], FACE[2])
    k = one.particle_count // 2
    np.testing.assert_array_equal(f4, np.tile(f1[:k], (5, 1)))


@pytest.mark.parametrize("value", [0, 9, 1.5, "2", True])
def test_bad_layer_counts_are_refused(value):
    with pytest.raises(ValueError, match=r"TissueConfig\.layers"):
        TissueConfig(layers=value)


def test_layers_is_keyword_only():
    """The fields after it keep their positions (TissueConfig(density, extrude, group_size))."""
    assert TissueConfig(4_000.0, 0.008, 10).group_size == 10
    assert TissueConfig(layers=8).layers == 8


REFERENCE = {1.0: 1.344e-3, 3.0: 2.865e-3}
"""The pad's compression in the plane-strain P2 reference, nu = 0 [m] (benchmarks/pad_reference.py)."""
COMPRESSION_TOL = 0.05
"""Relative tolerance against the reference [-]: measured with layers=2 at 64,000 per m^2 (no
hourglass control), +3.7 % at 1 N and -0.3 % at 3 N (docs/results/spatial-convergence.md, layers
through the thickness)."""


def test_a_two_layer_continuum_pad_meets_the_reference_and_its_inner_layer_stays_clear():
    """Pressed by the cylinder to 1 and 3 N, the pad compresses as the reference does, and no inner
    particle comes within its ellipsoid of the cylinder (PadRig.inner_gap: measured 4.3 mm clear)."""
    from benchmarks.spatial_convergence import PadRig

    rig = PadRig(64_000.0, friction=0.0, tissue=replace(CONTINUUM, layers=2))
    assert rig.inner.size == rig.particle_count // 3
    guess = 1.3e-3
    for load, want in REFERENCE.items():
        c, f = rig.press_to(load, guess=guess)
        assert abs(f / load - 1.0) < 0.01
        assert abs(c / want - 1.0) < COMPRESSION_TOL
        guess = 1.6 * c
    assert rig.inner_clearance > 1e-3
    lc = rig.solver.last_contacts()
    touching = lc.particle[: lc.count][(lc.shape[: lc.count] == 1) & (lc.normal_lambda[: lc.count] > 0.0)]
    assert touching.size > 0 and surface_particles(rig.model)[touching].all()


def test_inner_layers_stay_clear_of_the_cylinder_at_3_newtons():
    """Four layers at 16,000 per m^2: the cylinder pressed to 3 N touches the surface only (the
    inner layers' least clearance, PadRig.inner_gap, measured 1.2 mm over the normal search)."""
    from benchmarks.spatial_convergence import PadRig

    rig = PadRig(16_000.0, friction=0.0, tissue=replace(CONTINUUM, layers=4))
    c, f = rig.press_to(3.0, guess=3e-3)
    assert abs(f / 3.0 - 1.0) < 0.01
    assert rig.inner_clearance > 0.5e-3
    lc = rig.solver.last_contacts()
    touching = lc.particle[: lc.count][(lc.shape[: lc.count] == 1) & (lc.normal_lambda[: lc.count] > 0.0)]
    assert touching.size > 0 and surface_particles(rig.model)[touching].all()
