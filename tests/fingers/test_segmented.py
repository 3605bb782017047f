"""Segmented rigid fingers (SceneConfig(fingers=SegmentedConfig(...)), softgrasp_env/fingers/
segmented.py): layout, springs, grasp, misalignment and the ranges of its settings, against physics
measured first (numbers in each test's docstring; this 2-core machine, pybullet 3.2.x). What every
kind shares (builds, validated fields, scripted hold, determinism, rendering, divergence) is in
tests/fingers/test_contract.py."""

from __future__ import annotations

import math

import numpy as np
import pybullet as p
import pytest

from softgrasp_env.accuracy import GraspPlan, run_grasp
from softgrasp_env.fingers import SegmentedConfig, segmented
from softgrasp_env.registration import TISSUE_V3
from softgrasp_env.scene import GraspScene, SceneConfig
from tests.helpers import run_episode


def _scene(fingers: SegmentedConfig | None = None, **kw) -> GraspScene:
    return GraspScene(SceneConfig(fingers=fingers or SegmentedConfig(), **kw))


# --- layout ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [1, 3, 8])
def test_builds_with_links_where_segmented_says(n: int) -> None:
    """2 cores + per finger a carriage and a gimbal and a segment per segment: 4 + 4 n joints. Each
    segment's inner face centre sits SEGMENT_STANDOFF + SEGMENT_THICKNESS in front of its core's
    inner face at centres_y, in the core's (tilted, yawed) frame, and its box has half_extents."""
    sc = _scene(SegmentedConfig(segments=n), jaw_wedge=0.1, yaw=0.2)
    try:
        c, g, s = sc.client, sc.gripper.body, sc.fingers
        assert c.getNumJoints(g) == 4 + 4 * n
        assert len(s.segment_links[0]) == len(s.segment_links[1]) == n
        fh = sc.config.finger_half_extents
        width = (2 * fh[1] - (n - 1) * segmented.SEGMENT_GAP) / n
        assert s.half_extents == pytest.approx((0.5 * segmented.SEGMENT_THICKNESS, 0.5 * width, fh[2]), abs=1e-15)
        face_depth = fh[0] + segmented.SEGMENT_STANDOFF + segmented.SEGMENT_THICKNESS
        for k, inward in ((0, 1.0), (1, -1.0)):
            core_pos, core_orn = c.getLinkState(g, k, computeForwardKinematics=True)[4:6]
            rot = np.array(c.getMatrixFromQuaternion(core_orn)).reshape(3, 3)
            for i, link in enumerate(s.segment_links[k]):
                pos, orn = c.getLinkState(g, link, computeForwardKinematics=True)[4:6]
                seg_rot = np.array(c.getMatrixFromQuaternion(orn)).reshape(3, 3)
                face = np.asarray(pos) + seg_rot @ np.array([inward * 0.5 * segmented.SEGMENT_THICKNESS, 0.0, 0.0])
                want = np.asarray(core_pos) + rot @ np.array([inward * face_depth, s.centres_y[i], 0.0])
                np.testing.assert_allclose(face, want, rtol=0, atol=1e-6)
                np.testing.assert_allclose(seg_rot, rot, rtol=0, atol=1e-9)  # at rest: flush with the core
                shape = c.getCollisionShapeData(g, link)[0]
                np.testing.assert_allclose(np.asarray(shape[3]) * 0.5, s.half_extents, atol=1e-9)
            # the segments span the face, gaps included
            assert s.centres_y[0] - 0.5 * width == pytest.approx(-fh[1], abs=1e-12)
            assert s.centres_y[-1] + 0.5 * width == pytest.approx(fh[1], abs=1e-12)
    finally:
        sc.close()


# --- springs ---------------------------------------------------------------------------------------


def _static_deflection(axis: str, tau: float, *, steps: int = 480, **kw) -> tuple[float, float, np.ndarray]:
    """Hold a constant torque ``tau`` [N m] on finger 0's segment 0 about its pitch (y) or yaw (z)
    axis for ``steps`` steps, fingers open (no contact); (final angle, tau / k, every angle)."""
    sc = _scene(**kw)
    try:
        s, g = sc.fingers, sc.gripper.body
        joint = s.pitch_joints[0] if axis == "pitch" else s.yaw_joints[0]
        k = sc.config.fingers.stiffness_pitch if axis == "pitch" else sc.config.fingers.stiffness_yaw
        vec = [0.0, tau, 0.0] if axis == "pitch" else [0.0, 0.0, tau]
        qs = []
        for _ in range(steps):
            sc.client.applyExternalTorque(g, s.segment_links[0][0], vec, p.WORLD_FRAME)
            sc.step()
            qs.append(sc.client.getJointState(g, joint)[0])
        return qs[-1], tau / k, np.array(qs)
    finally:
        sc.close()


@pytest.mark.parametrize("axis,tau", [("pitch", 0.03), ("pitch", -0.01), ("yaw", 0.003), ("yaw", -0.002)])
def test_static_spring_deflection_is_torque_over_k(axis: str, tau: float) -> None:
    """A constant torque on a free segment settles at tau / k at the default dt (1/240 s). Measured:
    |q / (tau / k) - 1| <= 9e-16 after 2 s, within 1 % from step 9 and 2.5e-5 from step 30; before the damping cap
    (segmented.MAX_STEP_DAMPING) the joint cycled between 2.58 and 1.29 tau / k (yaw) / 1.39 and
    0.70 (pitch) every step and never settled. Tolerance: 1e-13, roundoff."""
    q, want, qs = _static_deflection(axis, tau)
    assert q == pytest.approx(want, rel=1e-13)
    assert np.ptp(qs[-100:]) <= 1e-13 * abs(want)  # settled, not cycling
    assert np.abs(qs[30:] / want - 1.0).max() < 1e-3  # and quickly: within 0.125 s


def test_spring_stability_margin_at_the_defaults() -> None:
    """The saturated spring motor settles under a free load iff a = k dt^2 / I < 3 at b = 0.5
    (segmented.py): at the defaults a = 1.39 (pitch) / 2.58 (yaw) with 3 segments. With 8
    segments the narrow segments' yaw inertia gives a = 29: documented, there only a blocking
    contact gives the static stiffness exactly (it still grasps, test_scripted_grasp_...)."""
    for n, pitch, yaw in ((3, 1.39, 2.58), (8, 4.25, 29.4)):
        sc = _scene(SegmentedConfig(segments=n))
        try:
            s = sc.fingers
            a = s.step_stiffness()
            npj = len(s.pitch_joints)
            assert a[:npj] == pytest.approx(pitch, rel=0.01)
            assert a[npj:] == pytest.approx(yaw, rel=0.01)
            assert (s.damping_applied * sc.config.sim.dt / s.inertia <= 0.5 + 1e-12).all()
        finally:
            sc.close()


def test_torque_springs_diverge_and_the_env_says_so(make_env, scripted) -> None:
    """SegmentedConfig(spring='torque') (explicit -(k q + c q')): at the defaults c dt / I = 4.1 (yaw) > 2,
    so a segment kicked by 0.01 rad reaches pybullet's 100 rad/s joint-rate clamp within 5 steps
    (measured: 100 rad/s at step 3) and slams between its joint limits from then on, finite
    throughout. SegmentedFingers.diverged() flags it, and the env ends the episode with
    info['diverged'] (at env step 2 in the scripted episode; never with the 'motor' springs)."""
    sc = _scene(SegmentedConfig(spring="torque"))
    try:
        s = sc.fingers
        sc.client.resetJointState(sc.gripper.body, s.yaw_joints[1], 0.01, 0.0)
        assert not s.diverged()
        rates = []
        for _ in range(10):
            sc.step()
            rates.append(np.abs(s.joint_states()[1]).max())
        assert max(rates[:5]) > segmented.DIVERGED_JOINT_RATE
        assert s.is_finite() and s.diverged()
    finally:
        sc.close()
    env = make_env("SoftGrasp-v5", fingers=SegmentedConfig(spring="torque"))
    rewards = []
    ep = run_episode(env, scripted, seed=0, max_steps=10, on_step=lambda obs, r, *_: rewards.append(r))
    assert ep.diverged and ep.terminated and rewards[-1] == 0.0 and np.isfinite(ep.observation).all()


def _not_diverged(obs, reward, term, trunc, info) -> None:
    assert not info["diverged"], info["divergence"]


# --- grasp -----------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [3, 8])
def test_scripted_grasp_lifts_and_holds_without_slip(n: int) -> None:
    """The default plan (5 cm in 1 s, 2 s hold), default 0.1 kg cylinder. Measured (3 / 8
    segments): lift 49.99 / 49.99 mm, hold slip 0.001 / 0.007 mm, tilt 0.03 / 0.05 deg, finger
    forces 3.000 / 3.05 N against the motors' 3 N (tolerance 3 %)."""
    sc = _scene(SegmentedConfig(segments=n))
    try:
        plan = GraspPlan()
        rec = run_grasp(sc, plan)
        assert rec.finite and rec.held(plan) and rec.holds_without_slip(plan)
        assert rec.lift_height == pytest.approx(plan.lift_distance, abs=5e-4)
        assert rec.hold_slip < 1e-4
        assert rec.max_tilt < math.radians(0.5)
        np.testing.assert_allclose(sc.finger_forces(), sc.config.finger_force, rtol=0.03)
        assert not sc.fingers.diverged()
    finally:
        sc.close()


def test_segmented_holds_at_a_wedge_where_rigid_slips(make_env, scripted) -> None:
    """The stability map's CI cell (jaw wedge 0.1 rad, yaw 0.1 rad, lateral offset 5 mm, the
    scripted policy, 5 s episode): the rigid twin lifts and loses the cylinder (it slips from a
    0.025 rad wedge on), the segmented fingers hold it. Measured over the map's wedge row 0 - 0.45
    rad x yaw 0 / 0.1 / 0.3: segmented held every cell, rigid only the 0 wedge (on SoftGrasp-v4 with
    the thesis tissue's keywords, TISSUE_V3, as measured)."""
    outcome = {}
    options = {"jaw_wedge": 0.1, "yaw": 0.1, "lateral_offset": 0.005, "cylinder_xy": (0.0, 0.0)}
    for fingers in ("rigid", "segmented"):
        env = make_env("SoftGrasp-v4", fingers=fingers, carry=False, **TISSUE_V3)  # the map's static hold (no carry)
        ep = run_episode(env, scripted, seed=0, options=options, on_step=_not_diverged)
        outcome[fingers] = "held" if ep.success else ("slipped" if ep.successes else "dropped")
    assert outcome == {"rigid": "slipped", "segmented": "held"}


@pytest.mark.slow
def test_soak_holds_120_s() -> None:
    """120 s of hold after the default lift: the multi-body fingers settle and stay. Measured at
    the v3 defaults (the smooth arm): slip from the start of the hold 0.015 / 0.026 / 0.033 /
    0.035 / 0.123 / 0.153 mm and tilt 0.08 / 0.16 / 0.23 / 0.26 / 0.44 / 0.61 deg at 10 / 20 / ...
    / 60 s, then 0.156 mm and 0.668 deg at 120 s and the same at 300 s (with 200 N on the arm too:
    the path, not the arm's force, sets it). With an arm whose target jumped once per control step
    (release 0.6.0's v1/v2) the drift was linear instead, 0.76 um/s and 0.0037 deg/s (0.046 mm,
    0.224 deg at 60 s), the thesis' "slowly growing instabilities" of multi-body fingers; the tissue and the rigid twin stay below 0.02 mm and
    0.05 deg (benchmarks/accuracy_defaults.py). Recorded as the expectation: within 2 deg and 1 mm,
    and no more than twice the measured settling."""
    sc = _scene()
    try:
        plan = GraspPlan(hold=120.0)
        rec = run_grasp(sc, plan)
        assert rec.finite and rec.holds_without_slip(plan)
        assert rec.max_tilt < math.radians(2.0) and rec.hold_slip < 1e-3
        assert rec.hold_slip < 2 * 0.156e-3 and rec.max_tilt < math.radians(2 * 0.668)
        assert rec.min_lift_during_hold > 0.9 * plan.lift_distance
        np.testing.assert_allclose(sc.finger_forces(), sc.config.finger_force, rtol=0.03)
    finally:
        sc.close()


# --- bad input -------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kw,field",
    [
        ({"segments": 0}, "segments"),
        ({"segments": 9}, "segments"),
        ({"segments": 2.5}, "segments"),
        ({"stiffness_pitch": -0.1}, "stiffness_pitch"),
        ({"stiffness_yaw": -0.1}, "stiffness_yaw"),
        ({"stiffness_yaw": 0.0}, "stiffness_yaw"),
        ({"damping_pitch": -1e-3}, "damping_pitch"),
    ],
)
def test_segment_settings_out_of_their_ranges_raise_naming_the_field(kw: dict, field: str) -> None:
    """The ends of the ranges (the contract test gives every field a non-number): 1-8 whole
    segments, a stiffness above 0 (open), a damping of at least 0."""
    with pytest.raises(ValueError, match=rf"SegmentedConfig\.{field}\b"):
        SegmentedConfig(**kw)
