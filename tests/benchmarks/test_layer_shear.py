"""The layered pad in shear (benchmarks/layer_shear.py): a flat punch stuck to the pad and moved
along the face, against the finite-element reference and the continuum's uniform shear."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.layer_shear import HALF_WIDTHS, linear_shear, shear


def test_one_and_two_layer_pads_shear_as_the_reference_under_the_whole_face():
    """The whole face stuck to a flat punch (64,000 per m^2, the v4 material): the continuum shears
    the layer uniformly. Measured 0.860 and 0.896 mm/N with one and two element layers against the
    3-D reference's 0.881 (the face stuck to |y| = 19.5 mm: -2.4 / +1.7 %); the two-layer pad's
    middle particle layer travels 0.500 of the punch's travel, as uniform shear has it."""
    pytest.importorskip("skfem")
    from benchmarks.pad_reference import default_pad, tangential_compliance_3d

    ref = tangential_compliance_3d(default_pad(), 0.0195, 0.0)
    one, two = (shear(64_000.0, n, HALF_WIDTHS["whole face"]) for n in (1, 2))
    assert abs(one["compliance"] / ref - 1.0) < 0.04 and abs(two["compliance"] / ref - 1.0) < 0.04, (one, two, ref)
    assert abs(two["profile"][1] - 0.5) < 0.01, two["profile"]


def test_a_four_layer_pad_shears_uniformly_under_the_whole_face():
    """The same punch on four element layers: the particle layers travel 0 / 0.247 / 0.499 / 0.753 / 1
    of the punch's travel (measured), as uniform shear has it, and the pad is within 4 % of the
    reference (0.909 mm/N, +3.1 %). With the trapezoid rule's masses in the groups' fits the layers
    travelled 0 / 0.290 / 0.500 / 0.710 / 1: a uniform stress was not in balance at the layers next
    to the core and the surface (tests/tissue/test_layers.py, the balance test)."""
    pytest.importorskip("skfem")
    from benchmarks.pad_reference import default_pad, tangential_compliance_3d

    r = shear(64_000.0, 4, HALF_WIDTHS["whole face"])
    assert all(abs(r["profile"][k] - k / 4) < 0.01 for k in range(5)), r["profile"]
    ref = tangential_compliance_3d(default_pad(), 0.0195, 0.0)
    assert abs(r["compliance"] / ref - 1.0) < 0.04, (r, ref)


def test_the_discrete_energy_converges_as_the_layers_are_refined():
    """The same punches on the discrete energy's own static equilibrium (linear_shear: the Hessian
    of the continuum group energy and its hourglass term, no solver), 64,000 per m^2, 1 / 2 / 4 / 8
    element layers. Measured, whole face: 0.8333 / 0.8645 / 0.8734 / 0.8751 mm/N, each change 3.5
    and 5.2 times smaller than the last, the layers travelling as uniform shear within 0.003; the
    3 N strip: 1.1613 / 1.2361 / 1.2831 / 1.3000 mm/N (changes 0.075, 0.047, 0.017)."""
    whole = [linear_shear(64_000.0, n, HALF_WIDTHS["whole face"]) for n in (1, 2, 4, 8)]
    strip = [linear_shear(64_000.0, n, HALF_WIDTHS["3 N strip"])["compliance"] for n in (1, 2, 4, 8)]
    for values in ([r["compliance"] for r in whole], strip):
        steps = np.diff(values)
        assert np.all(steps > 0.0) and steps[2] < 0.5 * steps[1] and steps[1] < steps[0], values
    for r, n in zip(whole, (1, 2, 4, 8), strict=True):
        assert all(abs(r["profile"][k] - k / n) < 0.005 for k in range(n + 1)), (n, r["profile"])
    np.testing.assert_allclose([r["compliance"] * 1e3 for r in whole], [0.8333, 0.8645, 0.8734, 0.8751], atol=2e-4)
