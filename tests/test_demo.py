"""The main job's flags (``python -m softgrasp_env.demo``): every number of TissueConfig and
SimConfig, the optional ones included, and the material; a wrong combination is the parser's
error, naming the fix. (The scene is captured, not simulated: tests/test_policies.py and the
grasp tests run the grasp itself.)"""

from __future__ import annotations

import pytest

from softgrasp_env import demo


class _Built(Exception):
    pass


@pytest.fixture
def built(monkeypatch):
    cfgs = []

    def capture(cfg, **kwargs):
        cfgs.append(cfg)
        raise _Built

    monkeypatch.setattr(demo, "GraspScene", capture)
    return cfgs


def test_the_material_flags_reach_the_scene(built):
    for argv in (["--shear-modulus", "8000", "--damping", "50"], ["--material", "per_step", "--stiffness", "0.7"]):
        with pytest.raises(_Built):
            demo.main(argv)
    compliant, per_step = built
    assert compliant.tissue.material == "compliant" and compliant.tissue.modulus == 8000.0
    assert compliant.sim.damping == 50.0
    assert per_step.tissue.material == "per_step" and per_step.tissue.step_stiffness == 0.7


def test_a_per_step_stiffness_on_the_compliant_material_is_refused(built, capsys):
    with pytest.raises(SystemExit):
        demo.main(["--stiffness", "0.7"])
    assert "shear_modulus" in capsys.readouterr().err and not built
