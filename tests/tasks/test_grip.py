"""The grip-force task (softgrasp_env/tasks/grip.py) and its scripted policies
(softgrasp_env/policies/grip.py): the least force from Coulomb, the reward's squeeze term, the
success bound, and that feeling the pads beats any force-blind grip."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

from softgrasp_env.policies.grip import ConstantGripPolicy, ShearLagGripPolicy, TactileGripPolicy
from softgrasp_env.registration import GRIP_TASK_CARRY, GRIP_TASK_LEAST, RETIRED_AS
from softgrasp_env.tasks import CarryTest, GripForceTask
from softgrasp_env.tasks.grip import least_squeeze
from tests.helpers import assert_same, rollout
from tests.trajectories import GRIP_V3_TASK

G = 9.81


def test_least_squeeze_is_coulomb_off_the_jaw_axis():
    x = np.array([1.0, 0.0, 0.0])
    # at rest: 2 mu F = m g
    assert least_squeeze(0.2, 0.8, np.zeros((3, 3)), x) == pytest.approx(0.2 * G / 1.6, rel=1e-12)
    # an acceleration along the jaw axis is the normals' to carry: no more friction needed
    assert least_squeeze(0.2, 0.8, np.array([[5.0, 0.0, 0.0]]), x) == pytest.approx(0.2 * G / 1.6, rel=1e-12)
    # across it, friction carries it with the weight: |(0, a, g)|, the worst instant counts
    acc = np.array([[0.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, -1.0, 0.0]])
    assert least_squeeze(0.2, 0.8, acc, x) == pytest.approx(0.2 * math.hypot(3.0, G) / 1.6, rel=1e-12)
    # accelerating upward asks for more, falling freely for nothing
    assert least_squeeze(0.1, 1.0, np.array([[0.0, 0.0, 2.0]]), x) == pytest.approx(0.1 * (G + 2.0) / 2, rel=1e-12)
    assert least_squeeze(0.1, 1.0, np.array([[0.0, 0.0, -G]]), x) == pytest.approx(0.0, abs=1e-15)


def test_grip_ids_are_the_task(make_env):
    for env_id, kind, task in (("SoftGraspGrip-v7", "tissue", GRIP_TASK_CARRY),
                               ("SoftGraspGrip-v6", "tissue", GRIP_TASK_CARRY),
                               ("SoftGraspGripRigid-v5", "rigid", GRIP_TASK_CARRY),
                               ("SoftGraspGripRigidTorsion-v5", "rigid_torsion", GRIP_TASK_CARRY),
                               ("SoftGraspGripRigid-v4", "rigid", GRIP_TASK_LEAST),
                               ("SoftGraspGripRigidTorsion-v4", "rigid_torsion", GRIP_TASK_LEAST)):  # fmt: skip
        spec = gym.spec(env_id)
        assert spec.kwargs["fingers"] == kind and spec.kwargs["start"] == "easy" and spec.kwargs["carry"] is True
        assert {k: spec.kwargs[k] for k in task} == task
    env = make_env("SoftGraspGripRigid-v5")
    u = env.unwrapped
    assert isinstance(u.task, GripForceTask) and isinstance(u.task.find(CarryTest), CarryTest)
    assert u.task.reward_terms == ("lift", "reach", "squeeze")
    # this step's taxels and the two steps' before them
    assert u.obs_names[-1] == "tactile_past2_right_r3_c3_shear_z" and len(u.obs_names) == 11 + 3 * 2 * 16 * 5
    # what the gripper itself senses: not the cylinder's pose or motion
    assert not {"cyl_rel_x", "cyl_vz", "cyl_wx", "cyl_axis_z", "lift"} & set(u.obs_names)
    assert {"grip_z", "grip_vz", "finger_gap", "force_left", "force_right", "time"} <= set(u.obs_names)
    # the draws span the least force 18-fold: mass 0.17 x U(1 +- 0.75), mu_s 0.9 x U(1 +- 0.45)
    seen = []
    for seed in range(40):
        env.reset(seed=seed)
        cfg = u.scene.config
        seen.append(cfg.cylinder_mass * G / (2 * cfg.tissue.friction_static))
    assert min(seen) < 0.3 and max(seen) > 1.8


def test_reward_charges_the_squeeze_and_info_reports_it(make_env):
    """The grip task's first charge (the squeeze in shares of the finger's force, every step)."""
    env = make_env("SoftGraspGripRigid-v5", **GRIP_V3_TASK)
    obs, info = env.reset(seed=3)
    assert info["carry_squeeze"] == 0.0 and info["least_squeeze"] == 0.0  # before the carry
    policy = ConstantGripPolicy(env, 3.0)
    for _ in range(100):
        obs, reward, _, _, info = env.step(policy(obs))
        terms = info["reward_terms"]
        u = env.unwrapped
        want = -0.5 * float(np.mean(u._last.force)) / 6.0
        assert terms["squeeze"] == pytest.approx(want, rel=1e-12, abs=1e-15)
        assert reward == pytest.approx(terms["lift"] + terms["reach"] + terms["squeeze"], rel=1e-12, abs=1e-15)
    # held with 3 N through the carry: the carry's mean squeeze is the motors' 3 N, its least the
    # Coulomb bound of this cylinder with the sway's accelerations
    cfg = env.unwrapped.scene.config
    static = cfg.cylinder_mass * G / (2 * cfg.tissue.friction_static)
    assert info["held"] and info["carry_squeeze"] == pytest.approx(3.0, rel=0.01)
    # the sway adds up to 1 m/s^2 across the jaw: |a + g| at most 0.5 % above g, at least g
    assert static <= info["least_squeeze"] <= static * 1.01
    assert info["is_success"] == (info["carry_squeeze"] <= 2.0 * info["least_squeeze"])


def test_the_charge_in_least_forces_costs_a_margin_the_same_on_every_cylinder(make_env):
    """``squeeze_reference="least"`` divides the squeeze by the episode's static least force
    m g / (2 mu_s): a light cylinder and one four times heavier, each gripped at 1.5 x its own
    least, pay the same charge per step once the fingers press steadily."""
    charges = []
    for mass in (0.05, 0.2):
        env = make_env("SoftGraspGripRigid-v5", **{**GRIP_V3_TASK, "squeeze_reference": "least"})
        obs, _ = env.reset(seed=3, options={"cylinder_mass": mass, "friction_scale": 1.0})
        cfg = env.unwrapped.scene.config
        static = cfg.cylinder_mass * G / (2 * cfg.tissue.friction_static)
        policy = ConstantGripPolicy(env, 1.5 * static)
        for _ in range(60):
            obs, reward, _, _, info = env.step(policy(obs))
            terms = info["reward_terms"]
            want = -0.5 * float(np.mean(env.unwrapped._last.force)) / static
            assert terms["squeeze"] == pytest.approx(want, rel=1e-12, abs=1e-15)
        assert info["held"]
        charges.append(terms["squeeze"])
    assert charges[0] == pytest.approx(-0.5 * 1.5, rel=0.02) and charges[1] == pytest.approx(-0.5 * 1.5, rel=0.02)


def test_the_charge_on_the_carrys_steps_alone_leaves_the_physics_and_the_carrys_charge(make_env):
    """``squeeze_charge_steps="carry"``: the same grip gives the same observations; the squeeze
    costs nothing before the carry and what the v4 id's charge costs in it, so a grasp carried through
    pays more than leaving the cylinder alone."""
    runs = {}
    for steps in ("all", "carry"):
        env = make_env("SoftGraspGripRigid-v4", squeeze_charge_steps=steps)
        obs, _ = env.reset(seed=5)
        policy = ConstantGripPolicy(env, 1.5 * env.unwrapped.task.reference)
        rows = []
        done = False
        while not done:
            obs, reward, term, trunc, info = env.step(policy(obs))
            # the carry's steps as the task judges the squeeze: its last step included
            in_carry = env.unwrapped.task.task.phase(env.unwrapped.scene.steps) is not None
            rows.append((obs.copy(), info["reward_terms"]["squeeze"], in_carry, reward, info["is_success"]))
            done = term or trunc
        runs[steps] = rows
    assert len(runs["all"]) == len(runs["carry"])
    carried = 0
    for (o1, q1, c1, r1, _), (o2, q2, c2, r2, _) in zip(runs["all"], runs["carry"], strict=True):
        assert np.array_equal(o1, o2) and c1 == c2
        if c1:
            carried += 1
            assert q2 == q1 and r2 == r1
        else:
            assert q2 == 0.0 and r2 == pytest.approx(r1 - q1, rel=1e-12, abs=1e-12)
    assert carried > 0 and runs["carry"][-1][4], "the 1.5 x least grip carries the cylinder through"
    before = sum(q for _, q, c, _, _ in runs["all"] if not c)
    assert before < -1.0, "the v4 id's charge costs the closing and the lift"
    ret = {k: sum(r[3] for r in v) for k, v in runs.items()}
    assert ret["carry"] == pytest.approx(ret["all"] - before, rel=1e-9)


def test_the_free_squeeze_is_not_charged(make_env):
    """``squeeze_free=1`` with the least force as the reference charges only the margin over the
    least, w max(0, F / F_least - 1), step by step; a grip below the least costs nothing."""
    for factor in (1.5, 0.8):
        env = make_env("SoftGraspGripRigid-v4", squeeze_free=1.0, squeeze_weight=1.0)
        obs, _ = env.reset(seed=3, options={"cylinder_mass": 0.2, "friction_scale": 1.0})
        static = env.unwrapped.task.reference
        policy = ConstantGripPolicy(env, factor * static)
        for _ in range(40):
            obs, _, _, _, info = env.step(policy(obs))
            f = float(np.mean(env.unwrapped._last.force))
            assert info["reward_terms"]["squeeze"] == pytest.approx(-max(0.0, f / static - 1.0), rel=1e-12, abs=1e-15)
        if factor > 1.0:
            assert info["reward_terms"]["squeeze"] == pytest.approx(-(factor - 1.0), rel=0.05)
        else:
            assert info["reward_terms"]["squeeze"] == 0.0


def test_success_needs_the_squeeze_within_the_factor(make_env):
    """The same held episode succeeds or not by the factor alone."""
    for factor, expect in ((2.0, False), (100.0, True)):
        env = make_env("SoftGraspGripRigid-v5", squeeze_factor=factor)
        obs, _ = env.reset(seed=3, options={"cylinder_mass": 0.05, "friction_scale": 1.0})  # least 0.27 N
        policy = ConstantGripPolicy(env, 3.0)
        for _ in range(100):
            obs, _, _, _, info = env.step(policy(obs))
        assert info["held"] and info["is_success"] is expect


@pytest.mark.parametrize("kwargs, match", [
    ({"squeeze_weight": 0.5, "carry": False}, "carry=True"),
    ({"squeeze_factor": 2.0, "carry": False}, "carry=True"),
    ({"squeeze_factor": 0.5}, "squeeze_factor"),
    ({"squeeze_weight": -1.0}, "squeeze_weight"),
    ({"observe_object": "no"}, "observe_object"),
    ({"squeeze_weight": 0.5, "squeeze_reference": "weight"}, "squeeze_reference"),
    ({"squeeze_weight": 0.5, "squeeze_charge_steps": "lift"}, "squeeze_charge_steps"),
    ({"squeeze_weight": 0.5, "squeeze_free": -1.0}, "squeeze_free"),
])  # fmt: skip
def test_bad_grip_arguments_are_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        gym.make("SoftGraspEasyRigid-v3", **kwargs)


def test_grip_policies_refuse_what_they_cannot_drive(make_env):
    with pytest.raises(ValueError, match="finger_action='force'"):
        TactileGripPolicy(make_env("SoftGraspEasyRigid-v3"))
    with pytest.raises(ValueError, match="tactile"):
        TactileGripPolicy(make_env("SoftGraspGripRigid-v5", tactile=None, tactile_history=1))
    with pytest.raises(ValueError, match="force"):
        ConstantGripPolicy(make_env("SoftGraspGripRigid-v5"), 7.0)


def test_grip_task_is_deterministic(make_env):
    a, b = make_env("SoftGraspGrip-v7"), make_env("SoftGraspGrip-v7")
    rollout(b, seed=2, steps=30, action_seed=1)
    assert_same(rollout(a, seed=7, steps=100, action_seed=4), rollout(b, seed=7, steps=100, action_seed=4))


def _episodes(env, policy, seeds) -> list[dict]:
    out = []
    for seed in seeds:
        obs, info = env.reset(seed=seed)
        policy.reset()
        for _ in range(100):
            obs, _, terminated, _, info = env.step(policy(obs))
            if terminated:
                break
        out.append(info)
    return out


def test_feeling_the_pads_beats_every_force_blind_grip(make_env):
    """The rigid peer's tactile policy (its pads' binned contact forces) against constant grips,
    20 seeded episodes each. Measured: tactile 19 / 20 (squeeze 1.56 x the least that holds,
    median); constant 0.5 / 1 / 2 / 3 N 4 / 8 / 6 / 3 of 20 (benchmarks/grip_force.py: 50 seeds
    of every kind)."""
    env = make_env("SoftGraspGripRigid-v5")
    seeds = range(1000, 1020)
    tactile = _episodes(env, TactileGripPolicy(env), seeds)
    wins = sum(i["is_success"] for i in tactile)
    assert wins >= 17
    for force in (0.5, 1.0, 2.0, 3.0):
        blind = sum(i["is_success"] for i in _episodes(env, ConstantGripPolicy(env, force), seeds))
        assert blind <= wins - 8, force
    ratios = [i["carry_squeeze"] / i["least_squeeze"] for i in tactile if i["is_success"]]
    assert 1.3 < np.median(ratios) < 1.8  # the margin 1.5 over the slip, found within a step of 15 %


@pytest.mark.slow
@pytest.mark.parametrize(("env_id", "least_wins", "margin"), [("SoftGraspGrip-v7", 15, 8), ("SoftGraspGrip-v6", 15, 8)])
def test_feeling_the_tissue_pads_beats_every_force_blind_grip(make_env, env_id, least_wins, margin):
    """As above with the soft fingers. Measured on v3 (the patch law, whose pads read less cleanly:
    a patch slides all at once): tactile 13 / 20; constant 0.5 / 1 / 2 / 3 N 3 / 1 / 3 / 4 of 20.
    On v4 (Coulomb per contact, the strip's edges slide first): tactile 18 / 20; constant 3 / 5 / 6
    / 4 of 20 (benchmarks/grip_force.py, 50 seeds: 41 / 50 against v3's 31). On v7 (the same
    tissue solved globally): tactile 18 / 20; constant 3 / 6 / 6 / 4 of 20."""
    env = make_env(env_id)
    seeds = range(1000, 1020)
    wins = sum(i["is_success"] for i in _episodes(env, TactileGripPolicy(env), seeds))
    assert wins >= least_wins
    for force in (0.5, 1.0, 2.0, 3.0):
        blind = sum(i["is_success"] for i in _episodes(env, ConstantGripPolicy(env, force), seeds))
        assert blind <= wins - margin, force


@pytest.mark.slow
def test_the_tissue_that_feels_slip_coming_grips_as_surely_as_the_peer_and_lighter(make_env):
    """The soft grip id's shear-lag script (the pads' edges lagging their centre: slip on its way)
    against the torsional peer's slip script (its binned contact forces falling below the weight),
    the same 50 seeds (1000-1049). Measured: the tissue 47 of 50 at a median squeeze of 1.40 x the
    least that holds, the peer 46 of 50 at 1.56 x (on the cards' 100 seeds 92 and 89, 1.44 and
    1.57 x; on seeds 3000-3099 95 and 93; benchmarks/grip_force.py)."""
    seeds = range(1000, 1050)
    soft = make_env("SoftGraspGrip-v7")
    peer = make_env("SoftGraspGripRigidTorsion-v5")
    mine = _episodes(soft, ShearLagGripPolicy(soft), seeds)
    theirs = _episodes(peer, TactileGripPolicy(peer), seeds)
    wins = sum(i["is_success"] for i in mine)
    assert wins >= 45 and wins >= sum(i["is_success"] for i in theirs), wins

    def median_ratio(infos) -> float:
        return float(np.median([i["carry_squeeze"] / i["least_squeeze"] for i in infos if i["is_success"]]))

    assert median_ratio(mine) < median_ratio(theirs) - 0.08, (median_ratio(mine), median_ratio(theirs))


def _soak(env, seeds) -> list[tuple[float, float]]:
    """Each episode the tactile policy succeeds in at 5 s, run on to 30 s: (lift at 5 s, at 30 s)
    [m], 0 at 30 s if dropped."""
    policy = TactileGripPolicy(env)
    out = []
    for seed in seeds:
        obs, _ = env.reset(seed=seed)
        policy.reset()
        for k in range(600):
            obs, _, terminated, _, info = env.step(policy(obs))
            if k == 99:
                if not info["is_success"]:
                    break
                at5 = info["lift_height"]
            if terminated:
                break
        else:
            out.append((at5, info["lift_height"] if info["held"] else 0.0))
    return out


def test_the_light_grip_holds_six_times_longer_than_an_episode(make_env):
    """The tactile policy's squeeze (1.5 x the last that held) held for 30 s, 25 s past the carry:
    the rigid twin, seeds 1000-1009. Measured (seeds 1000-1019): 19 of 19 held, the cylinder at
    most 0.45 mm lower at 30 s than at 5 s (the torsional peer 0.46 mm; the tissue, slow test, 0)."""
    runs = _soak(make_env("SoftGraspGripRigid-v5", max_episode_steps=600), range(1000, 1010))
    assert len(runs) >= 9
    assert all(at30 > 0.0 and at5 - at30 < 1.5e-3 for at5, at30 in runs), runs


@pytest.mark.slow
@pytest.mark.parametrize(("env_id", "least_runs", "settle"), [("SoftGraspGrip-v7", 15, 1.0e-4),
                                                              ("SoftGraspGrip-v6", 15, 1.0e-3)])
def test_the_light_tissue_grip_holds_six_times_longer_than_an_episode(make_env, env_id, least_runs, settle):
    """As above with the soft fingers: measured on v3 13 of 13 held, 0.00 mm lower at 30 s; on v4
    18 of 18 held, at most 0.37 mm lower; on v7 (solved globally) 18 of 18 held, at most 0.02 mm
    lower."""
    runs = _soak(make_env(env_id, max_episode_steps=600), range(1000, 1020))
    assert len(runs) >= least_runs
    assert all(at30 > 0.0 and at5 - at30 < settle for at5, at30 in runs), runs


@pytest.mark.slow
def test_the_converged_pads_grip_holds_six_times_longer_than_an_episode(make_env):
    """The same soak on the converged preset's pads (64,000 particles per m^2 in two element layers,
    1,140 particles): 7-9 minutes an episode. Measured, seeds 1000-1002: the two the policy succeeds
    in at 5 s (1000, 1001) held to 30 s, the cylinder 0.000 and 0.007 mm lower than at 5 s."""
    runs = _soak(make_env("SoftGraspGrip-v6", max_episode_steps=600, preset="converged"), range(1000, 1003))
    assert len(runs) >= 2
    assert all(at30 > 0.0 and at5 - at30 < 0.05e-3 for at5, at30 in runs), runs


def _constant_returns(env, factor: float, seeds) -> list[tuple[float, bool]]:
    """The return and the success of each seeded episode squeezed with ``factor`` x its static
    least force, m g / (2 mu_s) of the drawn cylinder (the scripted constant grip)."""
    out = []
    for seed in seeds:
        env.reset(seed=seed)
        cfg = env.unwrapped.scene.config
        static = cfg.cylinder_mass * G / (2 * cfg.tissue.friction_static)
        policy = ConstantGripPolicy(env, min(factor * static, 6.0))
        obs, _ = env.reset(seed=seed)
        total, done, info = 0.0, False, {}
        while not done:
            obs, reward, terminated, truncated, info = env.step(policy(obs))
            total += reward
            done = terminated or truncated
        out.append((total, bool(info["is_success"])))
    return out


def test_the_rigid_grip_reward_falls_with_every_margin_above_the_least(make_env):
    """SoftGraspGripRigid-v4 charges the squeeze in least forces: in every seeded episode carried
    at 1.1, 1.5 and 2 x the least, the return falls as the margin grows, by the charge on it: 0.3
    x the extra least forces over the steps the fingers press (7-12 per 0.4 here). Measured
    (benchmarks/squeeze_charge.py, 36 seeds): mean 45.7 / 34.8 / 24.8; the rigid twin carried
    the cylinder at 1.1 x in 36 of 36 (seed 1005 is carried at 1.1 and 2 x, not at 1.2-1.5)."""
    env = make_env("SoftGraspGripRigid-v4")
    seeds = range(1000, 1006)
    runs = [_constant_returns(env, f, seeds) for f in (1.1, 1.5, 2.0)]
    carried = [k for k in range(len(seeds)) if all(run[k][1] for run in runs)]
    assert len(carried) >= 5
    for k in carried:
        r = [run[k][0] for run in runs]
        assert r[0] > r[1] + 3.0 and r[1] > r[2] + 3.0, r


@pytest.mark.slow
@pytest.mark.parametrize("env_id", ["SoftGraspGrip-v6", "SoftGraspGrip-v7"])
def test_the_tissue_grip_reward_peaks_between_1_2_and_1_5_least_forces(make_env, env_id):
    """The retired SoftGraspGrip-v5's charge (its keywords in RETIRED_AS: the whole squeeze in
    least forces from the first step) over constant grips, on the sweep's tissue (v6: the retired
    id itself) and on the global solve's (v7): the mean return at 1.35 x the static least is above
    the one at 1.1 (where the tissue drops half the cylinders) and at 2.0 (the margin paid).
    Measured on v6 over 36 seeds: 27.7 +- 5.5 / 34.8 +- 4.2 / 27.9 +- 0.1 (and 35.9, 35.7 at 1.2,
    1.5; benchmarks/squeeze_charge.py, 2 cores of an Intel Xeon, about 6 minutes for these 72
    episodes); on v7 over these 24 seeds 28.4 +- 5.7 / 35.9 +- 4.5 / 26.8 +- 0.1 (+- the standard
    error; 35.9 and 35.6 at 1.2 and 1.5)."""
    _, keywords = RETIRED_AS["SoftGraspGrip-v5"]
    env = make_env(env_id, **keywords)
    seeds = range(1000, 1024)
    low, mid, high = (float(np.mean([r for r, _ in _constant_returns(env, f, seeds)])) for f in (1.1, 1.35, 2.0))
    assert mid > low and mid > high + 3.0, (low, mid, high)
