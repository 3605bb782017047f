"""Tactile pads: the taxel grid, and the readings of every kind against the
physics they come from - pybullet's contact points, the cylinder's weight, the motors' squeeze."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import softgrasp_env  # noqa: F401
from softgrasp_env.fingers.tactile import INNER_NORMAL, TAXEL_CHANNELS, TaxelGrid, _spread
from softgrasp_env.policies import ScriptedGraspPolicy
from tests.helpers import soft_physics

G = 9.81


def test_grid_checks_its_fields_and_maps_the_face():
    with pytest.raises(ValueError, match="TaxelGrid.rows"):
        TaxelGrid(0, 3, 0.02, 0.03)
    with pytest.raises(ValueError, match="TaxelGrid.cols"):
        TaxelGrid(4, 3.0, 0.02, 0.03)
    with pytest.raises(ValueError, match="TaxelGrid.half_width"):
        TaxelGrid(4, 3, -0.02, 0.03)
    g = TaxelGrid(4, 3, 0.02, 0.03)
    assert g.shape == (2, 4, 3, len(TAXEL_CHANNELS))
    assert g.area == pytest.approx(0.04 * 0.06 / 12)
    assert g.taxel(-0.02, 0.03) == (0, 0)  # top row, -y column
    assert g.taxel(0.02, -0.03) == (3, 2)  # the far edges belong to the taxels inside them
    assert g.taxel(0.0, 0.0) == (2, 1)
    assert g.taxel(0.021, 0.0) is None and g.taxel(0.0, -0.031) is None


def test_a_footprint_is_spread_by_area_and_keeps_its_whole_load():
    g = TaxelGrid(4, 4, 0.02, 0.02)  # 1 cm taxels
    index = np.empty(16, dtype=np.int64)
    weight = np.empty(16)
    # a 1 cm square centred on a taxel corner covers four taxels, a quarter each
    n = _spread(0.0, 0.0, 0.005, 0.005, g.params(), index, weight)
    assert n == 4 and np.allclose(weight[:n], 0.25) and sorted(index[:n]) == [5, 6, 9, 10]
    # half of it hangs over the face's edge: the on-face half takes the whole load
    n = _spread(0.02, 0.0025, 0.005, 0.0025, g.params(), index, weight)
    assert n == 1 and weight[0] == pytest.approx(1.0) and index[0] == 1 * 4 + 3
    # inside one taxel: all of it there
    n = _spread(0.005, 0.005, 0.002, 0.002, g.params(), index, weight)
    assert n == 1 and weight[0] == 1.0
    assert _spread(0.05, 0.0, 0.005, 0.005, g.params(), index, weight) == 0  # off the face


def _easy(fingers: str, **kwargs):
    """The easy task on ``fingers``; ``kind@v5`` on the soft ids' latest physics, else on the thesis
    tissue these readings were first measured on (tests.helpers.soft_physics)."""
    kind, _, physics = fingers.partition("@")
    env_id, keywords = soft_physics("SoftGraspEasy", physics or "thesis")
    return gym.make(env_id, fingers=kind, **keywords, **kwargs)


def _held(fingers: str, steps: int = 80):
    """The easy task's scripted grasp (:func:`_easy`) on ``fingers`` (``"tissue-consistent"``: the
    consistent coupling; ``"tissue@v5"``: the latest physics), lifted and held still (6.5 cm up
    from 40 env steps on, measured)."""
    kind, _, coupling = fingers.partition("-")
    from softgrasp_env.config import SimConfig

    env = _easy(kind, **({"sim": SimConfig(coupling=coupling)} if coupling else {}))
    policy = ScriptedGraspPolicy.for_env(env)
    obs, _ = env.reset(seed=0)
    for _ in range(steps):
        obs, *_ = env.step(policy(obs))
    return env


@pytest.mark.parametrize("fingers", ["tissue", "tissue@v5", "rigid", "rigid_torsion"])
def test_no_contact_no_load(fingers):
    """Open fingers above the cylinder at the reset: no pressure, no traction, no shear anywhere
    (the tissue starts at rest on its core: its shear channel reads under 1e-17 m on both
    physics, measured)."""
    env = _easy(fingers)
    try:
        env.reset(seed=0)
        kind = env.unwrapped.scene.fingers
        tac = kind.tactile(kind.taxel_grid(4, 3))
        assert tac.shape == (2, 4, 3, 5)
        assert np.all(tac[..., :3] == 0.0)
        assert np.abs(tac[..., 3:]).max() < 1e-15
    finally:
        env.close()


@pytest.mark.parametrize("fingers", ["tissue", "tissue-consistent", "tissue@v5", "rigid", "rigid_torsion"])
def test_a_held_cylinder_loads_the_pads_with_the_squeeze_and_its_weight(fingers):
    """Held aloft and still, each pad's pressure integrates to the motor's squeeze (3 N; measured
    within 0.1 %, 0.09 % on the latest physics) and the two pads' vertical traction to the
    cylinder's weight (measured within 0.07 %, 0.06 %), for the tissue (its contacts of the last
    world step) and for pybullet's contact points
    (whose friction forces are read in the right sense: a fair peer). The tissue's
    pressure also matches its contact normal force within 6 % (3.9 % measured: on the curved
    contact the normals fan out, and the load into the face counts their x parts and friction's;
    3.8 % on the latest)."""
    env = _held(fingers)
    fingers = fingers.split("-")[0].split("@")[0]
    try:
        u = env.unwrapped
        kind = u.scene.fingers
        grid = kind.taxel_grid(4, 3)
        tac = kind.tactile(grid)
        squeeze = u.scene.config.finger_force
        mass = u.scene.config.cylinder_mass
        pressure = tac[..., 0].sum(axis=(1, 2)) * grid.area
        assert np.allclose(pressure, squeeze, rtol=5e-3), pressure
        lift_force = -tac[..., 2].sum() * grid.area  # the pads' downward load holds the cylinder up
        assert lift_force == pytest.approx(mass * G, rel=3e-3)
        assert np.all(tac[..., 0] >= 0.0)  # a pad is pressed, never pulled
        normal = kind.contact_force()
        assert np.allclose(pressure, normal, rtol=0.06 if fingers == "tissue" else 2e-4)
        if fingers == "tissue":
            # the pad shears downward under the weight it carries, on every loaded taxel
            loaded = tac[..., 0] > 0.0
            assert np.all(tac[..., 4][loaded] < -1e-4)
        else:
            assert np.all(tac[..., 3:] == 0.0)
    finally:
        env.close()


def test_the_rigid_reading_is_pybullets_contact_points_binned():
    """Every contact point of each rigid finger, turned into the core's frame and added to the
    taxel under it by hand, gives the reading exactly."""
    env = _held("rigid")
    try:
        scene = env.unwrapped.scene
        kind, site, c = scene.fingers, scene.fingers.site, scene.client
        grid = kind.taxel_grid(5, 4)
        got = kind.tactile(grid)
        want = grid.empty()
        points = 0
        for k, link in enumerate(site.core_links):
            pos, orn = c.getLinkState(site.gripper, link, computeForwardKinematics=1)[:2]
            rot = np.array(c.getMatrixFromQuaternion(orn)).reshape(3, 3)
            for pt in c.getContactPoints(bodyA=site.gripper, linkIndexA=link):
                # friction acts on the body made first (the cylinder) along its directions
                f = pt[9] * np.array(pt[7]) - (pt[10] * np.array(pt[11]) + pt[12] * np.array(pt[13]))
                local = rot.T @ (np.array(pt[5]) - np.array(pos))
                load = rot.T @ f
                cell = grid.taxel(local[1], local[2])
                assert cell is not None  # every contact is on the inner face
                want[k, cell[0], cell[1], 0] -= INNER_NORMAL[k] * load[0] / grid.area
                want[k, cell[0], cell[1], 1:3] += load[1:] / grid.area
                points += 1
        assert points >= 2
        assert np.allclose(got, want, rtol=1e-12, atol=1e-9)
    finally:
        env.close()


@pytest.mark.parametrize(("fingers", "coupling", "squeeze"), [("tissue", "thesis", 2.0), ("tissue", "thesis", 3.0),
                                                          ("tissue", "thesis", 4.0), ("tissue", "consistent", 3.0),
                                                          ("rigid", "thesis", 2.0), ("rigid", "thesis", 4.0)])  # fmt: skip
def test_shear_grows_with_the_load_up_to_slip(fingers, coupling, squeeze):
    """The held cylinder made heavier until it slips (accuracy.shear_under_load), at 2, 3 and 4 N
    per finger and both couplings, the defaults otherwise (3 iterations, mu_s = mu_k 0.9). It lets
    go at Coulomb's 2 mu_s F (measured: tissue -0.8 / -1.7 / -3.6 %, rigid +5.7 / +3.8 %, pybullet's
    creep before its break); the taxels' traction is the load all the way (gap at most 0.9 % tissue,
    1.1 % rigid); the tissue's shear grows strictly with the load and linearly: 0.557-0.562 mm/N at
    every squeeze (an elastic layer's compliance does not depend on the normal load), 1.34 x two
    layers' h / (2 G A), and 1.008-1.015 x its small-load line at 95 % of the way to slip, where
    Cattaneo-Mindlin's circular contact softens to 1.5 x (the patch sticks as a whole,
    benchmarks/incipient_slip.py); a rigid pad's shear is 0."""
    from softgrasp_env.accuracy import shear_under_load
    from softgrasp_env.config import SimConfig
    from softgrasp_env.scene import GraspScene, SceneConfig

    scene = GraspScene(SceneConfig(fingers=fingers, finger_force=squeeze, sim=SimConfig(coupling=coupling)))
    try:
        bound = 2.0 * scene.config.tissue.friction_static * squeeze
        rec = shear_under_load(scene, max_load=1.3 * bound)
        cfg = scene.config
    finally:
        scene.close()
    assert rec.slip_load == pytest.approx(bound, rel=0.06 if fingers == "tissue" else 0.08)
    span = rec.slip_load - rec.load[0]
    before = rec.load <= rec.load[0] + 0.95 * span
    assert before.sum() >= 50
    assert np.allclose(rec.traction[before], rec.load[before], rtol=0.02)
    if fingers != "tissue":
        assert np.all(rec.shear == 0.0)
        return
    assert np.all(np.diff(rec.shear[before]) > 0.0)
    early = rec.load <= rec.load[0] + 0.2 * span
    compliance = np.polyfit(rec.load[early], rec.shear[early], 1)[0]
    face = 4.0 * cfg.finger_half_extents[1] * cfg.finger_half_extents[2]
    layer = cfg.tissue.extrude / (2.0 * cfg.tissue.shear_modulus * face)
    assert 1.25 < compliance / layer < 1.45
    linear = (rec.shear[before][-1] - rec.shear[0]) / (compliance * (rec.load[before][-1] - rec.load[0]))
    assert linear == pytest.approx(1.0, abs=0.04)


def test_the_fem_pads_have_no_tactile_reading_and_say_so():
    """pybullet reports no contact points of its FEM pads' nodes: the kind refuses rather than read
    zeros."""
    with pytest.raises(ValueError, match="fingers='fem'.*no contact points"):
        gym.make("SoftGraspEasy-v5", fingers="fem", tactile=(4, 3))
    env = gym.make("SoftGraspEasy-v5", fingers="fem")
    try:
        env.reset(seed=0)
        kind = env.unwrapped.scene.fingers
        with pytest.raises(NotImplementedError, match="no tactile reading"):
            kind.tactile(kind.taxel_grid(2, 2))
    finally:
        env.close()


def test_under_coulomb_per_contact_the_taxels_read_the_load_and_the_shear_softens_before_slip():
    """The same ramp with friction_law="contact" (3 N per finger, the defaults otherwise): every
    contact sticks or slides in its own cone, so the strip's edges slide first and the shear grows
    faster than its small-load line as the slip nears, toward Cattaneo-Mindlin's 1.5 x (measured
    1.146 x at 95 % of the way, the patch law 1.009 x); it lets go at 1.013 x 2 mu_s F (the
    contacts' normal forces on the wrapped pads sum to a little more than the squeeze). The
    taxels' traction is the load all the way (gap at most 0.9 %): a single contact's kinetic
    friction is all at position level, so the reading counts it once (counted twice, as a
    sliding patch's is, the gap was 71 %)."""
    from softgrasp_env.accuracy import shear_under_load
    from softgrasp_env.config import TissueConfig
    from softgrasp_env.scene import GraspScene, SceneConfig

    scene = GraspScene(SceneConfig(fingers="tissue", tissue=TissueConfig(friction_law="contact")))
    try:
        bound = 2.0 * scene.config.tissue.friction_static * scene.config.finger_force
        rec = shear_under_load(scene, max_load=1.3 * bound)
    finally:
        scene.close()
    assert rec.slip_load == pytest.approx(1.013 * bound, rel=0.03)
    span = rec.slip_load - rec.load[0]
    before = rec.load <= rec.load[0] + 0.95 * span
    assert np.allclose(rec.traction[before], rec.load[before], rtol=0.02)
    assert np.all(np.diff(rec.shear[before]) > 0.0)
    early = rec.load <= rec.load[0] + 0.2 * span
    compliance = np.polyfit(rec.load[early], rec.shear[early], 1)[0]
    linear = (rec.shear[before][-1] - rec.shear[0]) / (compliance * (rec.load[before][-1] - rec.load[0]))
    assert 1.10 < linear < 1.5, linear
