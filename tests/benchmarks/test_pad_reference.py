"""The pad's finite-element reference (benchmarks/pad_reference.py) against analytic limits and its
own mesh refinement, and the spatial convergence benchmark's tissue rig
(benchmarks/spatial_convergence.py). These record, not assert, whether the tissue converges in
space: that is the material's open question (docs/results/spatial-convergence.md)."""

from __future__ import annotations

import csv
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def _skfem():
    return pytest.importorskip("skfem", reason="the pad reference needs scikit-fem (pip install softgrasp-env[reference])")


@pytest.mark.parametrize("nu", [0.0, 0.3, 0.45])
def test_a_confined_layer_under_uniform_pressure_compresses_as_the_analytic_layer(nu):
    """u = p h (1 - 2 nu) / (2 G (1 - nu)): a linear field, which P2 elements hold exactly; the
    largest error measured is 8e-15 of it (round-off)."""
    _skfem()
    from benchmarks.pad_reference import LayerModel, confined_compression, default_pad

    pad = default_pad()
    u = -LayerModel(pad, nu, 4, sides="roller").uniform_pressure(1000.0)
    exact = confined_compression(1000.0, pad.thickness, pad.shear_modulus, nu)
    assert abs(u - exact).max() < 5e-14 * exact


def test_a_thin_layer_under_the_cylinder_meets_its_thin_layer_limit():
    """At h / a = 0.09 the line load is within 0.08 % of the elastic-foundation limit (measured
    1.0001 at nu 0, 0.9992 at nu 0.3), and the contact's half-width within 2 % (0.983, 0.987)."""
    _skfem()
    from benchmarks.pad_reference import LayerModel, Pad, default_pad, thin_layer_load

    base = default_pad()
    delta = 5e-4
    a = math.sqrt(base.radius**2 - (base.radius - delta) ** 2)
    for nu in (0.0, 0.3):
        thin = Pad(5e-4, 8 * a, base.height, base.radius, base.shear_modulus)
        c = LayerModel(thin, nu, 4, across=min(thin.thickness / 4, a / 60)).contact(delta)
        assert c["P"] / thin_layer_load(delta, thin, nu) == pytest.approx(1.0, abs=3e-3)
        assert c["a"] / a == pytest.approx(1.0, abs=0.03)
        assert c["penetration"] < 1e-9 * delta and c["pull"] == 0.0


def test_refining_the_reference_moves_it_toward_a_limit():
    """The indentation under 3 N (nu 0.3) at 4, 8 and 16 elements across the layer: each change
    smaller than the last (measured -1.3e-3, then +1.4e-3 and +1.8e-4 of it), the last under 5e-4."""
    _skfem()
    from benchmarks.pad_reference import LayerModel, default_pad

    pad = default_pad()
    d = [LayerModel(pad, 0.3, level).indentation(3.0)[0] for level in (4, 8, 16)]
    assert abs(d[2] - d[1]) < abs(d[1] - d[0])
    assert abs(d[2] - d[1]) < 5e-4 * d[2]
    assert 1.5e-3 < d[2] < 2.5e-3  # 1.994 mm


def test_the_tissue_rig_compresses_more_under_more_load_at_the_default_density():
    """The benchmark's rig at TissueConfig's default density: a finite compression at 1 and 3 N,
    larger at 3 N (measured 3.74 mm at 3 N). Whether it matches the reference is not asserted."""
    from benchmarks.spatial_convergence import PadRig
    from softgrasp_env.config import TissueConfig

    rig = PadRig(TissueConfig().particle_density, friction=0.0)
    c1, f1 = rig.press_to(1.0, guess=2e-3)
    c3, f3 = rig.press_to(3.0, guess=1.5 * c1)
    assert math.isfinite(c1) and math.isfinite(c3)
    assert f1 == pytest.approx(1.0, rel=0.01) and f3 == pytest.approx(3.0, rel=0.01)
    assert 0.0 < c1 < c3 < rig.pad


def test_the_benchmark_quick_run_writes_its_table_and_figure(tmp_path):
    _skfem()
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "spatial_convergence.py"), "--quick", "--out",
                           str(tmp_path)], cwd=ROOT, capture_output=True, text=True, timeout=600,
                          env={"PYTHONPATH": str(ROOT), "PATH": ""})  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-2000:]
    rows = list(csv.DictReader(open(tmp_path / "spatial_convergence.csv")))
    assert {r["quantity"] for r in rows} == {"compression", "contact_width", "tangential_compliance"}
    assert {r["density_per_m2"] for r in rows} == {"4000", "16000"}
    assert all(math.isfinite(float(r["tissue"])) and float(r["tissue"]) > 0 for r in rows)
    assert (tmp_path / "spatial_convergence.png").stat().st_size > 5_000


def test_the_3d_tangential_reference_has_the_pads_free_ends_and_tends_to_the_anti_plane_pad():
    """The finger's face is 60 mm long with free ends, so along the cylinder's axis it is more
    compliant than the anti-plane pad of infinite length: measured 1.184 mm/N against 1.128 (4 mm
    elements; 1.194 at 2 mm, 1.198 at 1.33 mm). Made longer, the compliance per face length falls
    toward the anti-plane value as the ends' share does, 1 / length: 1.1842, 1.1506, 1.1346, 1.1267
    mm/N at 1, 2, 4, 8 face lengths, each step about half the last."""
    _skfem()
    from benchmarks.pad_reference import LayerModel, default_pad, tangential_compliance_3d

    pad = default_pad()
    model = LayerModel(pad, 0.0)
    a = model.indentation(3.0)[1]["a"]
    anti_plane = model.tangential_compliance(a)
    c = [tangential_compliance_3d(pad, a, 0.0, element=4e-3, length=k * pad.height) for k in (1, 2, 4, 8)]
    assert c[0] > 1.04 * anti_plane, (c, anti_plane)
    steps = np.diff(c)
    assert np.all(steps < 0) and np.all(np.abs(steps[1:] / steps[:-1]) == pytest.approx(0.5, abs=0.06)), c
    assert abs(c[-1] / anti_plane - 1) < 0.01, (c, anti_plane)
    with pytest.raises(ValueError, match="half-width"):
        tangential_compliance_3d(pad, pad.width, 0.0)


def test_the_compressed_pad_shears_as_the_continuum_energy_does_at_finite_strain():
    """Linearised about the pad the cylinder has compressed (``indentation``), the 3-D reference
    takes the continuum group energy's shear modulus across the layer, G 2 s / (1 + s) at the
    stretch s: more compliant by 13.6 % at 3 N (1.357 against 1.195 mm/N, 2 mm elements; the
    tissue's continuum pad: 1.372 / 1.374 / 1.367 mm/N at 16,000 / 64,000 / 1,024,000 per m^2). A
    vanishing indentation is the linear pad; a deeper one is softer; nu other than 0 is refused."""
    _skfem()
    from benchmarks.pad_reference import LayerModel, default_pad, tangential_compliance_3d

    pad = default_pad()
    delta, contact = LayerModel(pad, 0.0).indentation(3.0)
    a = contact["a"]
    linear = tangential_compliance_3d(pad, a, 0.0, element=4e-3)
    assert tangential_compliance_3d(pad, a, 0.0, element=4e-3, indentation=0.0) == pytest.approx(linear, rel=1e-12)
    c = [tangential_compliance_3d(pad, a, 0.0, element=4e-3, indentation=f * delta) for f in (0.5, 1.0)]
    assert linear < c[0] < c[1], (linear, c)
    assert c[1] / linear == pytest.approx(1.136, abs=0.01), (linear, c)
    with pytest.raises(ValueError, match="nu 0"):
        tangential_compliance_3d(pad, a, 0.3, indentation=delta)


def test_the_plane_strain_profile_agrees_with_the_thin_layer_under_a_flat_punch():
    """Under a flat punch (the cylinder given a 5 m radius) the layer is compressed uniformly, so
    the plane-strain field's stretches are the thin layer's and both linearisations give the same
    pad (measured 0.9595 mm/N each, 2 mm elements); under the 3 cm cylinder at 3 N the field gives
    1.350 mm/N against the thin layer's 1.357. An unknown profile is refused."""
    _skfem()
    from dataclasses import replace

    from benchmarks.pad_reference import default_pad, tangential_compliance_3d

    punch = replace(default_pad(), radius=5.0)
    thin, field = (tangential_compliance_3d(punch, 19.9e-3, 0.0, element=4e-3, indentation=1.265e-3, profile=p)
                   for p in ("thin", "plane_strain"))  # fmt: skip
    assert field == pytest.approx(thin, rel=5e-3), (thin, field)
    with pytest.raises(ValueError, match="profile"):
        tangential_compliance_3d(punch, 19.9e-3, 0.0, indentation=1e-3, profile="exact")


def test_the_references_partial_slip_grows_in_from_the_edges_to_gross_slip_at_coulombs_load():
    """The anti-plane pad of the default scene pressed to 3 N, then pulled along the cylinder's axis
    with Coulomb's law at every surface node (LayerModel.partial_slip): Q / mu P rises to 1 as the
    last node slides, the stick share falls from 1 to 0, and the stick zone shrinks from the edges
    (the outermost sticking node moves in monotonically). For this pad (h / a = 0.71) the stick zone
    follows Cattaneo-Mindlin's (1 - Q / mu P)^(1/2) (measured 0.867 / 0.733 / 0.533 / 0.333 at
    0.25 / 0.5 / 0.75 / 0.9: +0.3 / +3.7 / +6.6 / +5.4 %), not the thin layer's
    (1 - Q / mu P)^(1/3) (0.908 / 0.794 / 0.630 / 0.464)."""
    _skfem()
    from benchmarks.pad_reference import LayerModel, at_ratios, default_pad

    model = LayerModel(default_pad(), 0.0)
    _, c = model.indentation(3.0)
    out = model.partial_slip(c["f"], 0.9, steps=200)
    assert all(np.diff(out["ratio"]) > 0.0) and out["ratio"][-1] == 1.0, out["ratio"][-3:]
    assert all(np.diff(out["share"]) <= 0.0) and out["share"][-1] == 0.0 and out["share"][0] > 0.99
    assert all(np.diff(out["c_geom"]) <= 0.0)
    levels = np.array([0.25, 0.5, 0.75, 0.9])
    cm = np.sqrt(1.0 - levels)
    c_over_a = at_ratios(out, levels, "c_geom")
    assert np.all(np.abs(c_over_a / cm - 1.0) < 0.1), c_over_a / cm
    assert np.all(c_over_a < (1.0 - levels) ** (1 / 3)), c_over_a


def test_the_references_partial_slip_meets_the_thin_layer_limit():
    """On a layer thin against its contact (h / a 0.18, then 0.09, the parabolic pressure of an
    elastic foundation) each node's shear is its own, so the stick zone is where mu p(y) exceeds
    the uniform stuck traction: c / a = (1 - Q / mu P)^(1/3). Measured at Q / mu P 0.9: 0.401 and
    0.434 against 0.464, the gap halving with h."""
    _skfem()
    from benchmarks.pad_reference import LayerModel, Pad, at_ratios, default_pad

    pad = default_pad()
    delta = 5e-4
    a = math.sqrt(pad.radius**2 - (pad.radius - delta) ** 2)
    limit = (1.0 - 0.9) ** (1 / 3)
    gaps = []
    for h in (1e-3, 5e-4):
        thin = Pad(h, 8 * a, pad.height, pad.radius, pad.shear_modulus)
        model = LayerModel(thin, 0.0, 4, across=min(h / 4, a / 60))
        out = model.partial_slip(model.contact(delta)["f"], 0.9, steps=200)
        gaps.append(limit - float(at_ratios(out, [0.9], "c_geom")[0]))
    assert 0.0 < gaps[1] < 0.6 * gaps[0] and gaps[1] < 0.04, gaps


def test_the_3d_references_partial_slip_has_the_anti_plane_pads_stick_zone_away_from_its_ends():
    """The 3-D pad of the face's length (partial_slip_3d, coarse: 4 mm elements, 1 mm across the
    strip) under the same ramp: its stick share follows the anti-plane pad's to three quarters of
    the slip load (measured 0.858 / 0.643 against 0.860 / 0.665 at 0.5 / 0.75); the free ends, where
    the shear traction must fall to zero, stick longer, so over the middle half of the height the
    stick zone is narrower than over the whole face."""
    _skfem()
    from benchmarks.pad_reference import LayerModel, at_ratios, default_pad, partial_slip_3d

    pad = default_pad()
    model = LayerModel(pad, 0.0)
    _, c = model.indentation(3.0)
    plane = model.partial_slip(c["f"], 0.9)
    full = partial_slip_3d(pad, model.y, c["pressure"], 0.9, element=4e-3, across=1e-3)
    assert all(np.diff(full["ratio"]) > 0.0) and full["ratio"][-1] == 1.0 and all(np.diff(full["share"]) <= 0.0)
    levels = [0.5, 0.75]
    assert np.allclose(at_ratios(full, levels, "share"), at_ratios(plane, levels, "share"), rtol=0.05)
    assert np.all(at_ratios(full, [0.5, 0.75, 0.9], "c_over_a_mid") < at_ratios(full, [0.5, 0.75, 0.9]))


def test_the_coupled_3d_pull_presses_the_trailing_end_and_lifts_the_leading_one():
    """partial_slip_3d without Goodman's approximation (``goodman`` False): the couple of the pull,
    carried from the pad's surface to its core, presses the face's trailing end harder and lifts the
    leading one, and Coulomb's bound moves with each node's normal force. Very coarse here (8 mm
    elements, 2 mm across the strip; the measured figures below are this mesh's). At mu 0.1 the
    couple is a ninth of mu 0.9's and the stick share follows Goodman's within 3 % at 0.25 ... 0.95
    of the slip load (0.426 against 0.438 at 0.9). At mu 0.9 the trailing half sticks 0.453 at 0.9
    against the leading half's 0.201, the leading half has let go entirely by 0.95 where the
    trailing half still sticks 0.196, 15 strip nodes have lifted off, and the share at 0.95 is
    0.104 against Goodman's 0.259. The cylinder holds its place across the pad, so the pull changes
    the normal load (+0.2 % by gross slip), which the ratio reads as it is."""
    _skfem()
    from benchmarks.pad_reference import LayerModel, at_ratios, default_pad, partial_slip_3d

    pad = default_pad()
    model = LayerModel(pad, 0.0)
    _, c = model.indentation(3.0)
    mesh = dict(element=8e-3, across=2e-3)
    levels = [0.25, 0.5, 0.75, 0.9, 0.95]
    goodman = at_ratios(partial_slip_3d(pad, model.y, c["pressure"], 0.9, **mesh), levels, "share")
    light = partial_slip_3d(pad, model.y, c["pressure"], 0.1, goodman=False, **mesh)
    assert np.allclose(at_ratios(light, levels, "share"), goodman, rtol=0.04)
    full = partial_slip_3d(pad, model.y, c["pressure"], 0.9, goodman=False, **mesh)
    assert all(np.diff(full["ratio"]) > 0.0) and full["ratio"][-1] == pytest.approx(1.0, abs=1e-12)
    assert full["Q"][-1] / (0.9 * 3.0) == pytest.approx(1.0, abs=0.01)
    share, trailing, leading, lifted = (at_ratios(full, levels, key) for key in ("share", "trailing", "leading", "open"))
    assert share[4] < 0.5 * goodman[4]
    assert trailing[3] > 2.0 * leading[3] and leading[4] == 0.0 and trailing[4] > 0.15
    assert lifted[3] >= 10 and at_ratios(light, [0.9], "open")[0] <= 2


def test_the_compressed_pads_partial_slip_softens_by_the_stuck_strips_finite_strain_factor():
    """partial_slip_3d about the pad the cylinder compressed (``indentation``: the continuum energy's
    shear across the layer at finite strain, as tangential_compliance_3d's): the reference for the
    tissue's tangential row with both the compression and the edges' slip. Coarse (4 mm elements,
    1 mm across), 3 N. Read as the rig reads the tissue (the secant from 0.25 to 0.75 mm of the
    cylinder's travel) it measured 1.444 mm/N against the linear pad's 1.265: 1.1415 x, the same
    factor as the first step's (the strip nearly all stuck: 1.355 against 1.190, 1.1386 x); the
    whole strip still slides at Coulomb's load."""
    _skfem()
    from benchmarks.pad_reference import LayerModel, default_pad, partial_slip_3d

    pad = default_pad()
    model = LayerModel(pad, 0.0)
    delta, c = model.indentation(3.0)
    ramps = [partial_slip_3d(pad, model.y, c["pressure"], 0.9, element=4e-3, across=1e-3, indentation=d)
             for d in (None, delta)]  # fmt: skip
    secant = [0.5e-3 / np.diff(np.interp([0.25e-3, 0.75e-3], r["U"], r["Q"]))[0] for r in ramps]
    first = [r["U"][0] / r["Q"][0] for r in ramps]
    assert secant[0] == pytest.approx(1.265e-3, rel=2e-3) and secant[1] == pytest.approx(1.444e-3, rel=2e-3)
    assert secant[1] / secant[0] == pytest.approx(first[1] / first[0], rel=0.005)
    for r in ramps:
        assert all(np.diff(r["ratio"]) > 0.0) and r["ratio"][-1] == 1.0 and all(np.diff(r["share"]) <= 0.0)
    with pytest.raises(ValueError, match="nu 0"):
        partial_slip_3d(pad, model.y, c["pressure"], 0.9, nu=0.3, indentation=delta)
