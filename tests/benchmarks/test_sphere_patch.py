"""The tissue's patch on a sphere follows the sphere's chord at the pad's indentation,
sqrt(2 R delta - delta^2), as the squeeze grows (benchmarks/sphere_patch.py)."""

from __future__ import annotations

import math

import pytest

from benchmarks.sphere_patch import measure

R = 0.03


def _chord(delta: float) -> float:
    return math.sqrt(2 * R * delta - delta * delta)


def test_the_default_patch_follows_the_chord():
    """Default tissue (particles 15.8 mm apart), 1 and 6 N: the pressure's second-moment radius is
    1.12 and 0.91 of the chord (measured), both fingers alike; it grows with the squeeze."""
    ratios, radii = [], []
    for force in (1.0, 6.0):
        left, right = measure(force, "default")
        assert left["a2"] == pytest.approx(right["a2"], rel=1e-3)
        ratios.append(left["a2"] / _chord(left["delta"]))
        radii.append(left["a2"])
    assert radii[1] > radii[0] * 1.1
    assert 1.05 < ratios[0] < 1.18 and 0.85 < ratios[1] < 0.97, ratios


@pytest.mark.slow
def test_the_converged_patch_reaches_the_chord():
    """The converged tissue at 1, 3 and 6 N: the farthest contact from the centre of pressure is
    0.94-0.96 of the chord (the outermost touching particle sits inside the rim)."""
    for force in (1.0, 3.0, 6.0):
        left, _ = measure(force, "converged")
        assert 0.91 < left["a"] / _chord(left["delta"]) < 0.99, force
