"""The main job's flags (``python -m softgrasp_env.demo``): every number of TissueConfig and
SimConfig, the optional ones included; a wrong combination is the parser's
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
    with pytest.raises(_Built):
        demo.main(["--shear-modulus", "8000", "--damping", "50", "--max-deviation", "0.01"])
    (cfg,) = built
    assert cfg.tissue.shear_modulus == 8000.0 and cfg.tissue.max_deviation == 0.01 and cfg.sim.damping == 50.0


def test_the_retired_material_flags_are_gone(built, capsys):
    for argv in (["--material", "per_step"], ["--stiffness", "0.7"]):
        with pytest.raises(SystemExit):
            demo.main(argv)
        assert "unrecognized arguments" in capsys.readouterr().err
    assert not built
