"""The object map's cells and its summary (benchmarks/object_map.py): a few cells run for real."""

from __future__ import annotations

import argparse
import csv

import pytest

from benchmarks.object_map import MAPS, SQUEEZES, cells, run, summary


def _args(tmp_path, **kw) -> argparse.Namespace:
    base = dict(objects="cone", methods="rigid;rigid_torsion", cells="all", maps="band", squeezes="0.5,3",
                name="m", out=tmp_path, summary=False, only="")  # fmt: skip
    return argparse.Namespace(**{**base, **kw})


def test_the_grid_is_every_object_map_squeeze_and_value():
    every = list(cells(["sphere", "cone"]))
    per_object = sum(len(values) for _, values in MAPS.values()) * len(SQUEEZES)
    assert len(every) == 2 * per_object == 152
    # each cell carries: the misalignment maps at the 1.9 Hz sway, the band map at its own
    for _obj, name, value, _squeeze, options, aim in every:
        assert options["carry_frequency"] in (1.2, 1.9, 3.0)
        assert (aim > 0) == (name == "offset" and value != "0")


def test_on_the_cone_the_bare_rigid_fingers_lose_it_and_torsion_holds_it(tmp_path, capsys):
    """A flat rigid face touches the cone's taper at one point a side: it turns about the line
    through them and tips out (83 deg at 3 N); with the torsional lever it is carried through every
    band. At 0.5 N per finger no method lifts the 0.1 kg cone: Coulomb's bound m g / (2 mu) is
    0.55 N."""
    run(_args(tmp_path))
    with open(tmp_path / "m.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 * 3 * 2
    out = {(r["method"], r["squeeze"], r["value"]): int(r["outcome"]) for r in rows}
    for band in MAPS["band"][1]:
        assert out[("rigid", "3", band)] < 2 and out[("rigid_torsion", "3", band)] == 2
        assert out[("rigid", "0.5", band)] == 0 and out[("rigid_torsion", "0.5", band)] == 0
    tilts = [float(r["tilt_deg"]) for r in rows if r["method"] == "rigid" and r["squeeze"] == "3"]
    assert min(tilts) > 45.0
    # a second run adds nothing: every cell is there
    run(_args(tmp_path))
    with open(tmp_path / "m.csv", newline="") as f:
        assert len(list(csv.DictReader(f))) == len(rows)
    summary(_args(tmp_path, summary=True))
    text = capsys.readouterr().out
    assert "| cone | 0 | 3 |" in text  # held through the carry: rigid none, torsion the three bands at 3 N
    assert "| cone | - / - | - / - | - (0) | 0 | 0 | - (no converged run) |" in text


def _sphere_at_half_a_newton(**physics) -> int:
    import gymnasium as gym

    from benchmarks.object_map import ALIGNED, SWAY, episode
    from softgrasp_env.registration import TISSUE_V4

    env = gym.make("SoftGraspEasy-v4", object="sphere", finger_force=0.5, carry=True, **{**TISSUE_V4, **physics})
    try:
        return episode(env, {**ALIGNED, **SWAY}, 0.0).outcome
    finally:
        env.close()


@pytest.mark.xfail(strict=True, reason="the default pad holds the 0.1 kg sphere at 0.5 N per finger, below Coulomb's "
                   "0.55 N for two flat faces: its particles, 16 mm apart, reach round the curve and contact normals "
                   "tilted up carry weight; the converged pad (the slow test) and every rigid kind drop it")
def test_the_default_pad_drops_a_sphere_squeezed_below_coulombs_bound():
    assert _sphere_at_half_a_newton() != 2


@pytest.mark.slow
def test_the_converged_pad_drops_a_sphere_squeezed_below_coulombs_bound():
    """m g / (2 mu) = 0.1 * 9.81 / 1.8 = 0.55 N: at 0.5 N per finger nothing that only presses and
    rubs on the sphere's sides can lift it (about 30 s)."""
    assert _sphere_at_half_a_newton(preset="converged") == 0
