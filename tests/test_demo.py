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


def test_the_main_job_runs_the_newest_soft_ids_tissue_and_the_older_ones_on_request(built):
    """By default the demo runs the soft ids' v5: the v4 tissue (presets.TISSUE_V4: the continuum
    energy, hourglass control, Coulomb per contact, layers as thick as the spacing) under the global
    material solve; ``--tissue v4`` sweeps it group by group, ``--tissue v3`` is the thesis' shape
    matching with its patch law; a ``--layers`` given is kept, and so is a ``--material-solve``."""
    from softgrasp_env.config import TissueConfig

    for argv in ([], ["--particle-density", "64000"], ["--particle-density", "64000", "--layers", "1"], ["--tissue", "v3"],
                 ["--tissue", "v4"], ["--material-solve", "groups"], ["--rigid"]):  # fmt: skip
        with pytest.raises(_Built):
            demo.main(argv)
    v5, dense, dense_one, v3, v4, asked, rigid = built
    assert (v5.tissue.group_energy, v5.tissue.friction_law, v5.tissue.hourglass_stiffness, v5.tissue.layers) == (
        "continuum", "contact", 1.0, 1)  # fmt: skip
    assert v5.sim.material_solve == "global" and dense.sim.material_solve == "global"
    assert dense.tissue.layers == 2 and dense_one.tissue.layers == 1
    assert v3.tissue == TissueConfig() and v3.sim.material_solve == "groups"
    assert v4.tissue == v5.tissue and v4.sim.material_solve == "groups" and asked.sim.material_solve == "groups"
    assert rigid.fingers.kind == "rigid" and rigid.sim.material_solve == "groups"
