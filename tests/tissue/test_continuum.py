"""The continuum group energy (TissueConfig.group_energy "continuum"; tissue/compliant.py,
continuum_groups; builder.continuum_groups): E = G V ||F - R||^2 per group, its gradient, its
Newton step, its momentum, the uniform-strain patch test, and the pad against the finite-element
reference (benchmarks/pad_reference.py)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from softgrasp_env.config import TissueConfig
from softgrasp_env.tissue.builder import CoreShape, build_combined_body, build_free_block
from softgrasp_env.tissue.compliant import continuum_energy, continuum_groups, core_stiffness, substeps_for
from softgrasp_env.tissue.rotation import quat_to_matrix
from softgrasp_env.tissue.shape_matching import group_frames, group_pack

G = 4_000.0
CONTINUUM = TissueConfig(group_energy="continuum")
FACE = (0.008, 0.02, 0.03)  # the scene's finger core: 16 x 40 x 60 mm, tissue on +x


def pad(density: float, *, hourglass: float = 0.0, layers: int = 1):
    tissue = replace(CONTINUUM, particle_density=density, hourglass_stiffness=hourglass, layers=layers)
    return build_combined_body(CoreShape("box", half_extents=FACE), tissue, faces=("+x",))


def random_group(rng, n=8):
    q = rng.normal(size=(n, 3)) * 0.005
    m = rng.uniform(0.5, 1.5, n) * 1e-3
    q -= (m[:, None] * q).sum(axis=0) / m.sum()
    mq = m[:, None] * q
    ainv = np.linalg.inv(mq.T @ q)
    return q, m, mq, ainv


def _ainv(row):
    return np.array([[row[0], row[1], row[2]], [row[1], row[3], row[4]], [row[2], row[4], row[5]]])


def model_energy(model, x):
    """sum_g E_g and dE/dx (N, 3) of a continuum model at positions x."""
    pack = group_pack(model)
    total, grad = 0.0, np.zeros_like(x)
    for i in range(model.particle_count):
        e = slice(int(model.group_offsets[i]), int(model.group_offsets[i + 1]))
        mem = model.group_members[e]
        row = model.group_continuum[i]
        en, g, _ = continuum_energy(x[mem], pack[e, 1:4], _ainv(row), row[6], mass=model.particle_mass[mem],
                                    beta=row[7])  # fmt: skip
        total += en
        np.add.at(grad, mem, g)
    return total, grad


def run_group(model, i, xp, fixed, dt, group_q=None):
    """continuum_groups on group i alone (core 0, held still): returns
    (xp after, g_u, the core's linear impulse [N s], quat(R))."""
    n = model.particle_count
    pack = group_pack(model)
    frame = np.zeros((n, 10))
    xs = xp.copy()
    group_frames(model.group_offsets, model.group_members, model.particle_mass, xs, frame)
    gq = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)) if group_q is None else group_q.copy()
    members = model.group_members.shape[0]
    g_u, g_raw = np.zeros((members, 3)), np.zeros((members, 3))
    imp = [np.zeros((1, 3)) for _ in range(3)]
    xp = xp.copy()
    continuum_groups(i, i + 1, 0, 0, 0, 0.0, 50, model.group_continuum, model.group_offsets, model.group_members,
                     pack, frame, xs, xp, gq, fixed, g_u, g_raw, model.particle_mass, np.zeros((1, 3)),
                     np.array([[0.0, 0.0, 0.0, 1.0]]), np.zeros(1), np.zeros((1, 3)), np.zeros((1, 3)),
                     np.zeros(1, dtype=np.bool_), *imp, dt)  # fmt: skip
    return xp, g_u, imp[0][0] * dt, gq[i].copy()


@pytest.mark.parametrize("hourglass", [0.0, 1.0])
def test_energy_and_gradient_against_finite_differences(hourglass):
    rng = np.random.default_rng(3)
    q, m, mq, ainv = random_group(rng)
    k = 2.0 * G * 1e-6
    beta = hourglass * 0.5 * k / np.trace(mq.T @ q)  # builder.continuum_groups' beta
    x = q @ (np.eye(3) + 0.05 * rng.normal(size=(3, 3))).T + rng.normal(size=(8, 3)) * 2e-3 + 0.1
    e0, grad, _ = continuum_energy(x, mq, ainv, k, mass=m, beta=beta)
    assert e0 > 0.0
    if hourglass:  # the term is there (2 % of this energy), not a rounding
        assert e0 > 1.01 * continuum_energy(x, mq, ainv, k)[0]

    def energy(y):
        return continuum_energy(y, mq, ainv, k, mass=m, beta=beta)[0]

    fd = np.zeros_like(x)
    h = 1e-7
    for j in range(x.shape[0]):
        for a in range(3):
            xp, xm = x.copy(), x.copy()
            xp[j, a] += h
            xm[j, a] -= h
            fd[j, a] = (energy(xp) - energy(xm)) / (2 * h)
    np.testing.assert_allclose(grad, fd, rtol=1e-5, atol=1e-6 * np.abs(grad).max())
    np.testing.assert_allclose(grad.sum(axis=0), 0.0, atol=1e-12 * np.abs(grad).max() * 8)  # no net force
    # and no net torque about any point: R is the polar factor of F
    np.testing.assert_allclose(np.cross(x, grad).sum(axis=0), 0.0, atol=1e-9 * np.abs(grad).max())


def test_small_strain_energy_is_linear_elasticity_with_nu_zero():
    """E = G V ||F - R||^2 -> V mu eps:eps: a uniform stretch eps gives G V eps^2 + ..., a shear
    gamma G V gamma^2 / 2 (tau = G gamma), in the limit of small strain."""
    rng = np.random.default_rng(4)
    q, m, mq, ainv = random_group(rng)
    vol = 1e-6
    k = 2.0 * G * vol
    for h, want in ((np.diag([1e-4, 0.0, 0.0]), G * vol * 1e-8),
                    (np.array([[0.0, 1e-4, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]), G * vol * 1e-8 / 2)):  # fmt: skip
        rot = quat_to_matrix(np.array([0.3, -0.2, 0.5, 0.8]) / np.linalg.norm([0.3, -0.2, 0.5, 0.8]))
        x = q @ (rot @ (np.eye(3) + h)).T + 0.05
        np.testing.assert_allclose(continuum_energy(x, mq, ainv, k)[0], want, rtol=1e-3)


def test_a_rotated_group_has_no_energy_and_does_not_move():
    model = build_free_block((0.01, 0.01, 0.01), CONTINUUM, spacing=0.005)
    rot_q = np.array([0.2, -0.4, 0.1, 0.9])
    rot_q /= np.linalg.norm(rot_q)
    rot = quat_to_matrix(rot_q)
    x = model.particle_rest_x @ rot.T + np.array([0.1, -0.2, 0.3])
    e, grad = model_energy(model, x)
    assert e < 1e-20 and np.abs(grad).max() < 1e-12
    fixed = np.zeros(model.particle_count, dtype=np.bool_)
    for i in (0, 13, model.particle_count - 1):
        after, _, _, qr = run_group(model, i, x, fixed, 1.0 / 240.0)  # from identity: 50 rotation sweeps
        np.testing.assert_allclose(after, x, atol=1e-12)
        assert abs(abs(qr @ rot_q) - 1.0) < 1e-9


def test_the_hourglass_term_costs_nothing_for_affine_motion_and_penalises_a_checkerboard():
    """E_h = (beta / 2) sum_j m_j |x_j - c - F q_j|^2 is zero for any affine motion of a group
    (a stretch, a shear, a turn and a shift) and for a uniform shear of the pad, and it adds to
    the energy of a checkerboard across the surface, which a group's affine fit averages away."""
    model = pad(64_000.0, hourglass=1.0)
    pack = group_pack(model)
    rng = np.random.default_rng(8)
    x0 = model.particle_rest_x
    rot = quat_to_matrix(np.array([0.1, 0.2, -0.3, 0.9]) / np.linalg.norm([0.1, 0.2, -0.3, 0.9]))
    affine = x0 @ (rot @ (np.eye(3) + 0.05 * rng.normal(size=(3, 3)))).T + 0.01
    for i in range(0, model.particle_count, 37):
        e = slice(int(model.group_offsets[i]), int(model.group_offsets[i + 1]))
        mem = model.group_members[e]
        row = model.group_continuum[i]
        m = model.particle_mass[mem]
        full = continuum_energy(affine[mem], pack[e, 1:4], _ainv(row), row[6], mass=m, beta=row[7])[0]
        bare = continuum_energy(affine[mem], pack[e, 1:4], _ainv(row), row[6])[0]
        assert row[7] > 0.0
        np.testing.assert_allclose(full, bare, rtol=1e-9)
    # the outer particles pushed along the face by +-0.1 mm in a checkerboard (measured: the term
    # adds 68 % to the energy of this pattern, nothing to a uniform shear)
    spacing = 1.0 / np.sqrt(64_000.0)
    cell = np.round(x0[:, 1:] / spacing).astype(int).sum(axis=1)
    free = ~model.particle_attached
    x = x0.copy()
    x[free, 2] += 1e-4 * np.where(cell[free] % 2 == 0, 1.0, -1.0)
    hour, _ = model_energy(model, x)
    bare, _ = model_energy(pad(64_000.0), x)
    assert hour > 1.5 * bare > 0.0
    x = x0.copy()
    x[free, 2] += 1e-4
    np.testing.assert_allclose(model_energy(model, x)[0], model_energy(pad(64_000.0), x)[0], rtol=1e-9)


@pytest.mark.parametrize("hourglass", [0.0, 1.0])
def test_the_newton_step_is_exact_and_keeps_momentum(hourglass):
    """A pad group with members held by the core: after one step the free members satisfy
    m_j u_j + dt^2 grad_j E = 0 (R held; with the hourglass term, its gradient included), and their
    momentum plus the core's impulse is zero. A free group keeps its momentum and angular momentum
    about the start positions."""
    model = pad(64_000.0, hourglass=hourglass)
    rng = np.random.default_rng(5)
    dt = 1.0 / 240.0 / 6
    x = model.particle_rest_x + np.where(model.particle_attached[:, None], 0.0,
                                         rng.normal(size=model.particle_rest_x.shape) * 1e-3)  # fmt: skip
    fixed = model.particle_attached.copy()
    m = model.particle_mass
    pack = group_pack(model)
    for i in range(model.particle_count):
        e = slice(int(model.group_offsets[i]), int(model.group_offsets[i + 1]))
        mem = model.group_members[e]
        held = fixed[mem]
        if not (held.any() and (~held).any()):
            continue
        after, g_u, core_impulse, qr = run_group(model, i, x, fixed, dt)
        row = model.group_continuum[i]
        b = pack[e, 1:4] @ _ainv(row)
        f = after[mem].T @ b
        grad = row[6] * b @ (f - quat_to_matrix(qr)).T
        if hourglass:
            assert row[7] > 0.0
            c = (m[mem, None] * after[mem]).sum(axis=0) / m[mem].sum()
            grad = grad + row[7] * m[mem, None] * (after[mem] - c - model.group_rest_offset[e] @ f.T)
        res = m[mem, None] * (after[mem] - x[mem]) + dt * dt * grad
        scale = np.abs(dt * dt * grad).max()
        np.testing.assert_allclose(res[~held], 0.0, atol=1e-9 * scale)
        moved = (m[mem, None] * (after[mem] - x[mem])).sum(axis=0)
        np.testing.assert_allclose(moved + core_impulse, 0.0, atol=1e-9 * scale)
        assert np.abs(core_impulse).max() > 1e-3 * scale
        break
    else:
        raise AssertionError("no group with held and free members")
    block = build_free_block((0.01, 0.01, 0.01), replace(CONTINUUM, hourglass_stiffness=hourglass), spacing=0.005)
    xb = block.particle_rest_x + rng.normal(size=block.particle_rest_x.shape) * 1e-3
    after, _, _, _ = run_group(block, 7, xb, np.zeros(block.particle_count, dtype=np.bool_), 1.0 / 240.0)
    mb = block.particle_mass[:, None]
    dx = after - xb
    assert np.abs(dx).max() > 1e-6
    np.testing.assert_allclose((mb * dx).sum(axis=0), 0.0, atol=1e-15)
    mem = block.group_members[block.group_offsets[7]:block.group_offsets[8]]
    cs = (mb[mem] * xb[mem]).sum(axis=0) / mb[mem].sum()
    np.testing.assert_allclose(np.cross(xb - cs, mb * dx).sum(axis=0), 0.0, atol=1e-17)


@pytest.mark.parametrize("hourglass", [0.0, 1.0])
def test_the_newton_step_with_a_sliding_core_is_exact_and_keeps_momentum(hourglass):
    """Under the consistent coupling a core that slides along its joint axis inside the solve is
    the group's one more unknown. After one step of a pad group whose held members ride a core of
    0.05 kg sliding along x (every attached particle of the pad moves with it): the free members
    satisfy m_j u_j + dt^2 grad_j E = 0, the core satisfies (m_c + M_att) U_c + dt^2 a . sum_fix
    grad_j E = 0, and the momentum of the tissue, the core's m_c U_c and the impulses across the
    axis (which the joint takes) sum to zero."""
    model = pad(64_000.0, hourglass=hourglass)
    rng = np.random.default_rng(7)
    dt = 1.0 / 240.0 / 6
    n = model.particle_count
    x = model.particle_rest_x + np.where(model.particle_attached[:, None], 0.0,
                                         rng.normal(size=model.particle_rest_x.shape) * 1e-3)  # fmt: skip
    fixed = model.particle_attached.copy()
    m = model.particle_mass
    m_core, axis = 0.05, np.array([1.0, 0.0, 0.0])
    pack = group_pack(model)
    for i in range(n):
        e = slice(int(model.group_offsets[i]), int(model.group_offsets[i + 1]))
        mem = model.group_members[e]
        held = fixed[mem]
        if not (held.any() and (~held).any()):
            continue
        frame = np.zeros((n, 10))
        group_frames(model.group_offsets, model.group_members, m, x, frame)
        gq = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
        g_u, g_raw = np.zeros((model.group_members.shape[0], 3)), np.zeros((model.group_members.shape[0], 3))
        imp_lin, imp_ang, coupling = np.zeros((1, 3)), np.zeros((1, 3)), np.zeros((1, 3))
        rig_x = np.zeros((1, 3))
        after = x.copy()
        m_att = float(m[fixed].sum())
        continuum_groups(i, i + 1, 0, 0, n, m_att, 50, model.group_continuum, model.group_offsets,
                         model.group_members, pack, frame, x, after, gq, fixed, g_u, g_raw, m, rig_x,
                         np.array([[0.0, 0.0, 0.0, 1.0]]), np.array([1.0 / m_core]), np.ones((1, 3)),
                         axis[None, :], np.ones(1, dtype=np.bool_), imp_lin, imp_ang, coupling, dt)  # fmt: skip
        qr = gq[i].copy()
        uc = rig_x[0] @ axis
        assert abs(uc) > 0.0
        np.testing.assert_allclose(after[fixed] - x[fixed], np.outer(np.full(fixed.sum(), uc), axis), atol=1e-15)
        row = model.group_continuum[i]
        b = pack[e, 1:4] @ _ainv(row)
        f = after[mem].T @ b
        grad = row[6] * b @ (f - quat_to_matrix(np.array(qr))).T
        if hourglass:
            c = (m[mem, None] * after[mem]).sum(axis=0) / m[mem].sum()
            grad = grad + row[7] * m[mem, None] * (after[mem] - c - model.group_rest_offset[e] @ f.T)
        res = m[mem, None] * (after[mem] - x[mem]) + dt * dt * grad
        scale = np.abs(dt * dt * grad).max()
        np.testing.assert_allclose(res[~held], 0.0, atol=1e-9 * scale)
        core_res = (m_core + m_att) * uc + dt * dt * grad[held].sum(axis=0) @ axis
        assert abs(core_res) <= 1e-9 * scale, (core_res, scale)
        moved = (m[:, None] * (after - x)).sum(axis=0)
        np.testing.assert_allclose(moved + imp_lin[0] * dt, 0.0, atol=1e-9 * scale)
        assert abs(imp_lin[0] @ axis * dt - m_core * uc) <= 1e-12 * scale  # along the axis: the core's inertia alone
        break
    else:
        raise AssertionError("no group with held and free members")


PATCH_TOL = 0.02
"""Relative tolerance of the patch test's stresses [-] (measured: below 1e-6 for the energy's
stress, which a least-squares F reproduces exactly for a linear field)."""


@pytest.mark.parametrize("density", [16_000.0, 64_000.0])
def test_uniform_strain_patch_test(density):
    """The pad under a uniform stretch across the layer and a uniform shear: its stress,
    (1 / V) dE/dH, is 2 G eps (nu = 0; tau = G gamma for the shear), and its core feels the
    traction over the face. The volume of the groups sums to the layer's."""
    model = pad(density)
    x0 = model.particle_rest_x
    vol = 2 * FACE[1] * 2 * FACE[2] * CONTINUUM.extrude
    np.testing.assert_allclose(model.group_continuum[:, 6].sum(), 2.0 * G * vol, rtol=1e-9)
    ref = x0.mean(axis=0)
    for a, b in ((0, 0), (0, 1), (1, 2)):
        eps = 1e-4

        def energy(t, a=a, b=b):
            h = np.zeros((3, 3))
            h[a, b] = t
            return model_energy(model, x0 + (x0 - ref) @ h.T)[0]

        sigma = (energy(2 * eps) - energy(0.0)) / (2 * eps) / vol  # (1 / V) dE/dH_ab at H_ab = eps
        want = 2.0 * G * eps if a == b else G * eps  # sigma_aa = 2 G eps_aa; tau_ab = G gamma, gamma = H_ab
        np.testing.assert_allclose(sigma, want, rtol=PATCH_TOL)
    # the core under a shear of the layer: the outer particles moved gamma h along y
    gamma = 1e-3
    x = x0.copy()
    x[~model.particle_attached, 1] += gamma * CONTINUUM.extrude
    _, grad = model_energy(model, x)
    pull = grad[~model.particle_attached].sum(axis=0)  # what the groups put on the core through the held members
    np.testing.assert_allclose(pull[1], G * gamma * 2 * FACE[1] * 2 * FACE[2], rtol=PATCH_TOL)


def test_substeps_follow_the_continuum_stiffness():
    model = pad(64_000.0)
    kappa = model.group_kappa
    assert model.continuum and (kappa > 0).all()
    n = substeps_for(model, 1.0 / 240.0)
    assert kappa.max() * (1.0 / 240.0 / n) ** 2 <= 0.25 < kappa.max() * (1.0 / 240.0 / (n - 1)) ** 2
    # the layer's stiffness against its core is the confined modulus of nu = 0, 2 G A / h
    np.testing.assert_allclose(core_stiffness(model)[0], 2 * G * 2 * FACE[1] * 2 * FACE[2] / CONTINUUM.extrude,
                               rtol=1e-6)  # fmt: skip


def test_the_default_is_shape_matching():
    model = build_combined_body(CoreShape("box", half_extents=FACE), TissueConfig(), faces=("+x",))
    assert not model.continuum and (model.group_continuum == 0.0).all()
    with pytest.raises(ValueError, match="group_energy"):
        TissueConfig(group_energy="fem")
    with pytest.raises(ValueError, match="hourglass_stiffness acts on the continuum"):
        TissueConfig(hourglass_stiffness=0.5)
    with pytest.raises(ValueError, match="hourglass_stiffness"):
        TissueConfig(group_energy="continuum", hourglass_stiffness=1.5)
    assert (model.group_continuum[:, 7] == 0.0).all() and (pad(16_000.0).group_continuum[:, 7] == 0.0).all()


REFERENCE_3N = 2.865e-3
"""The pad's compression under 3 N in the plane-strain P2 reference, nu = 0 [m]
(benchmarks/pad_reference.py; docs/results/spatial-convergence.md)."""
COMPRESSION_TOL = 0.08
"""Relative tolerance against the reference [-]: measured -2.0 % at 16,000 and -6.2 % at 64,000 per
m^2 (docs/results/spatial-convergence.md)."""


@pytest.mark.parametrize("density", [16_000.0, 64_000.0])
def test_compression_against_the_reference(density):
    from benchmarks.spatial_convergence import PadRig

    rig = PadRig(density, friction=0.0, tissue=CONTINUUM)
    c, f = rig.press_to(3.0, guess=2.7e-3)
    assert abs(f - 3.0) < 0.02
    assert abs(c / REFERENCE_3N - 1.0) < COMPRESSION_TOL


def test_the_v4_default_pad_has_the_compression_errors_its_card_names():
    """The v4 tissue at its default 4,000 per m^2 (one layer, hourglass control): too coarse for the
    strip (three particle columns across it), it compresses -1.1 / -23.5 / -23.6 % against the
    reference under 1 / 3 / 6 N (1.344 / 2.865 / 4.603 mm), the errors the env card names; refined
    to 16,000 per m^2 it is within 4 % (test above)."""
    from benchmarks.spatial_convergence import PadRig

    tissue = TissueConfig(group_energy="continuum", hourglass_stiffness=1.0, friction_law="contact")
    errors = []
    for load, ref in ((1.0, 1.344e-3), (3.0, REFERENCE_3N), (6.0, 4.603e-3)):
        rig = PadRig(4_000.0, friction=0.0, tissue=tissue)
        c, f = rig.press_to(load, guess=ref)
        assert abs(f - load) < 0.02 * load
        errors.append(c / ref - 1.0)
    assert abs(errors[0]) < 0.04 and all(-0.28 < e < -0.19 for e in errors[1:]), errors


REFERENCE_WIDTH_3N = 5.560e-3
"""The contact strip's pressure-weighted RMS half-width under 3 N in the reference, nu = 0 [m]
(benchmarks/pad_reference.pressure_width)."""


@pytest.mark.slow
def test_compression_and_the_strips_width_agree_between_two_densities():
    """The continuum energy's pad at 64,000 and 256,000 particles per m^2 (the spacing halved):
    compression under 3 N 2.688 / 2.660 mm (1.0 % apart), the strip's RMS half-width 5.575 / 5.403
    mm (3.1 % apart; the reference's 5.560: +0.3 / -2.8 %)."""
    from benchmarks.spatial_convergence import PadRig

    rows = []
    for density in (64_000.0, 256_000.0):
        rig = PadRig(density, friction=0.0, tissue=CONTINUUM)
        c, f = rig.press_to(3.0, guess=2.7e-3)
        rows.append((c, rig.contact_width()))
    (c1, w1), (c2, w2) = rows
    assert abs(c2 / c1 - 1.0) < 0.03, rows
    assert abs(w2 / w1 - 1.0) < 0.06, rows
    assert all(abs(w / REFERENCE_WIDTH_3N - 1.0) < 0.06 for _, w in rows), rows


COMPRESSED_TANGENTIAL_3N = 1.357e-3
"""The 3-D reference's tangential compliance at 3 N linearised about the pad as the cylinder
compressed it, nu 0, 2 mm elements [m/N] (pad_reference.tangential_compliance_3d, indentation=):
the continuum energy's shear modulus across a layer at stretch s is G 2 s / (1 + s)."""


def test_the_tangential_compliance_against_the_compressed_pads_reference():
    """At 16,000 per m^2 the continuum pad's tangential compliance at 3 N is 1.372 mm/N: 15 % above
    the linear reference (1.194) and 1.1 % above the reference linearised about the compressed pad,
    whose shear across the layer softens as the energy's does at finite strain."""
    from benchmarks.spatial_convergence import measure_tissue, tangential_at

    c = measure_tissue(16_000.0, (3.0,), material="continuum")["compliance"]
    assert abs(c / COMPRESSED_TANGENTIAL_3N - 1.0) < 0.04, c
    assert c > 1.1 * 1.194e-3, c  # and not the linear pad's
    # the band's single-load measurement is the same procedure
    assert tangential_at(16_000.0, 3.0, material="continuum") == pytest.approx(c, rel=0.01)


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="the continuum pad's tangential compliance does not converge in space yet "
                   "(1.374 mm/N at 64,000 per m^2, 1.253 at 256,000, 1.367 at 1,024,000; the 3-D reference 1.194): "
                   "docs/results/spatial-convergence.md, 'What did not'")
def test_the_tangential_compliance_agrees_between_two_densities():
    """The same two densities, pressed to 3 N with the default friction and moved along the axis
    (spatial_convergence.measure_tissue): agreement within 3 %; strict, so that the day it
    converges it says so."""
    from benchmarks.spatial_convergence import measure_tissue

    c1 = measure_tissue(64_000.0, (3.0,), material="continuum")["compliance"]
    c2 = measure_tissue(256_000.0, (3.0,), material="continuum")["compliance"]
    assert abs(c2 / c1 - 1.0) < 0.03, (c1, c2)


REFERENCE_6N = 4.603e-3
"""The pad's compression under 6 N in the reference, nu = 0 [m]."""


@pytest.mark.slow
def test_four_layers_carry_6N_without_inverting_under_hourglass_control():
    """Four element layers at 256,000 per m^2 (3,000 particles) pressed to 6 N: without the
    hourglass term the thin layers fold and the pad gives 22 % more than the reference; with it
    (hourglass_stiffness 1) the compression is within 2 % (measured -1.7 %)."""
    from benchmarks.spatial_convergence import PadRig

    rig = PadRig(256_000.0, friction=0.0, tissue=replace(CONTINUUM, layers=4, hourglass_stiffness=1.0))
    c, f = rig.press_to(6.0, guess=4.4e-3)
    assert abs(f - 6.0) < 0.05
    assert abs(c / REFERENCE_6N - 1.0) < 0.04, c


REFERENCE_1N = 1.344e-3
"""The pad's compression under 1 N in the reference, nu = 0 [m]."""


@pytest.mark.slow
def test_layers_as_thick_as_the_spacing_keep_the_compression_on_the_reference():
    """The continuum energy with hourglass control 1 and a layer about as thick as the particle
    spacing (convergence_table --layers auto): one layer at 16,000, two at 64,000, four at
    256,000 per m^2. Measured against the reference at 1 / 3 / 6 N: -2.2 / -3.5 / -1.5 %,
    -1.3 / -1.3 / -0.5 %, -1.5 / -2.5 / -1.6 % (one layer alone drifts to -9.7 / -7.1 / -5.0 % at
    256,000)."""
    from benchmarks.spatial_convergence import measure_tissue

    refs = {1.0: REFERENCE_1N, 3.0: REFERENCE_3N, 6.0: REFERENCE_6N}
    for density, layers in ((16_000.0, 1), (64_000.0, 2), (256_000.0, 4)):
        r = measure_tissue(density, material="continuum", layers=layers, hourglass=1.0, tangential=False)
        errors = {f: r[f"compression_{f:g}N"] / ref - 1.0 for f, ref in refs.items()}
        assert all(abs(e) < 0.05 for e in errors.values()), (density, layers, errors)


def _candidate_grasp(coupling: str, mass: float, steps: int, material_solve: str = "groups") -> dict:
    """The scripted aligned grasp (SoftGraspEasy-v4, whose registered tissue keywords are this
    tissue's) on the continuum energy with hourglass control 1 and Coulomb per contact, run for
    ``steps`` env steps (20 Hz), under ``coupling`` and ``material_solve`` (SimConfig)."""
    import gymnasium as gym

    import softgrasp_env  # noqa: F401
    from benchmarks.grasp_checks import ALIGNED
    from softgrasp_env.config import SimConfig
    from softgrasp_env.policies import ScriptedGraspPolicy

    tissue = TissueConfig(group_energy="continuum", hourglass_stiffness=1.0, friction_law="contact")
    env = gym.make("SoftGraspEasy-v4", max_episode_steps=steps, tissue=tissue, sim=SimConfig(coupling=coupling, material_solve=material_solve))
    try:
        policy = ScriptedGraspPolicy.for_env(env)
        obs, _ = env.reset(seed=0, options={**ALIGNED, "cylinder_mass": mass})
        lifts, held, diverged = [], [], False
        for _ in range(steps):
            obs, _, term, trunc, info = env.step(policy(obs))
            lifts.append(info["lift_height"])
            held.append(info["held"])
            diverged |= bool(info["diverged"])
            if term or trunc:
                break
        return {"lifts": np.array(lifts), "held": np.array(held), "diverged": diverged}
    finally:
        env.close()


@pytest.mark.slow
def test_the_candidate_tissue_holds_near_its_bound_for_a_minute():
    """0.45 kg (86 % of the hold bound, 0.529 kg) held for 65 s, past any episode, under the
    thesis coupling: held at every step after the lift, and the cylinder settles by at most 1 mm
    (measured 0.6 mm: 65.3 mm at 5 s, 64.7 mm at 65 s) without diverging."""
    r = _candidate_grasp("thesis", 0.45, 1300)
    assert not r["diverged"] and r["held"][100:].all()
    assert r["lifts"][100:].min() > r["lifts"][100] - 1e-3, (r["lifts"][100], r["lifts"][100:].min())


def test_both_couplings_press_the_cylinder_alike_on_the_continuum_energy():
    """The scripted grasp at 2 x 3 N on the v4 material (SoftGraspEasy-v4, whose registered tissue
    keywords are this tissue's): the contacts' summed normal force on the cylinder. Measured: 5.932 N (thesis coupling), 5.922 N (consistent: the sliding core is the
    continuum group's unknown too); 4.85 N before it was, the core held still inside the step."""
    from benchmarks.grasp_checks import scripted_episode

    tissue = TissueConfig(group_energy="continuum", hourglass_stiffness=1.0, friction_law="contact")
    press = [scripted_episode({"fingers": "tissue", "coupling": c}, "v4", options={"cylinder_mass": 0.3},
                              tissue=tissue)["press"] for c in ("thesis", "consistent")]  # fmt: skip
    assert abs(press[1] / press[0] - 1.0) < 0.03, press
