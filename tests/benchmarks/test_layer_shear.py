"""The layered pad in shear (benchmarks/layer_shear.py): a flat punch stuck to the pad and moved
along the face, against the finite-element reference and the continuum's uniform shear."""

from __future__ import annotations

import pytest

from benchmarks.layer_shear import HALF_WIDTHS, shear


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
