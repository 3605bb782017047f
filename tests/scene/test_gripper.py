"""The gripper's control: the env's action as a GripperControl (the arm's target moved by the
action, kept in the workspace and within reach of the palm; the finger target), and a control
applied to the scene moves the palm and fingers as it says."""

from __future__ import annotations

import numpy as np
import pytest

from softgrasp_env.scene import GraspScene, GripperActions, GripperControl, SceneConfig, Workspace
from softgrasp_env.scene.gripper import GRIP_TOP, MAX_LEAD, WORKSPACE_HALF_WIDTH

CFG = SceneConfig(fingers="rigid")
WS = Workspace.of(CFG)
ACTIONS = GripperActions(0.0075, WS, CFG.finger_max_opening)
G2P = np.array([0.0, 0.0, 0.08])  # palm above the grip point


def _control(action, palm_target, palm=None):
    palm = palm_target if palm is None else palm
    return ACTIONS.control(np.asarray(action, dtype=np.float64), palm_target=np.asarray(palm_target),
                           palm=np.asarray(palm), grip_to_palm=G2P)  # fmt: skip


def test_the_workspace_is_the_documented_box():
    np.testing.assert_allclose(WS.low, [-WORKSPACE_HALF_WIDTH, -WORKSPACE_HALF_WIDTH,
                                        CFG.finger_half_extents[2] + CFG.tissue.extrude + 0.003])  # fmt: skip
    np.testing.assert_allclose(WS.high, [WORKSPACE_HALF_WIDTH, WORKSPACE_HALF_WIDTH, GRIP_TOP])
    assert WS.max_lead == MAX_LEAD == 0.02


def test_an_action_moves_the_target_by_the_step_length_and_sets_the_fingers():
    start = np.array([0.01, -0.02, 0.18])
    c = _control([0.0, 0.0, 0.0, -1.0], start)
    np.testing.assert_allclose(c.palm_target, start, atol=1e-15)
    assert c.finger_closing == 0.0
    c = _control([1.0, -0.5, 0.0, 1.0], start)
    np.testing.assert_allclose(c.palm_target - start, [0.0075, -0.00375, 0.0], atol=1e-15)
    assert c.finger_closing == pytest.approx(CFG.finger_max_opening)
    assert _control([0, 0, 0, 0.0], start).finger_closing == pytest.approx(0.5 * CFG.finger_max_opening)


def test_the_target_stays_in_the_workspace_and_within_reach_of_the_palm():
    edge = np.array([WORKSPACE_HALF_WIDTH, 0.0, 0.1]) + G2P  # grip at the +x edge
    c = _control([1.0, 0.0, 0.0, 0.0], edge)
    assert c.palm_target[0] - G2P[0] == pytest.approx(WORKSPACE_HALF_WIDTH)  # no further out
    low = np.array([0.0, 0.0, WS.low[2]]) + G2P
    assert _control([0.0, 0.0, -1.0, 0.0], low).palm_target[2] - G2P[2] == pytest.approx(WS.low[2])
    # the palm lags 3 cm behind its target: the target may lead it by 2 cm at most
    target = np.array([0.05, 0.0, 0.15])
    palm = target - np.array([0.03, 0.0, 0.0])
    c = _control([1.0, 0.0, 0.0, 0.0], target, palm)
    assert c.palm_target[0] == pytest.approx(palm[0] + MAX_LEAD)


def test_a_control_moves_the_palm_and_fingers_where_it_says():
    sc = GraspScene(CFG)
    try:
        target = sc.start_palm + np.array([0.01, 0.0, 0.02])
        control = GripperControl(target, 0.02)
        for _ in range(240):
            sc.step(control)
        assert sc.control is control and sc.palm_target is target
        np.testing.assert_allclose(sc.palm_position(), target, atol=2e-4)
        np.testing.assert_allclose(sc.finger_closing(), [0.02, 0.02], atol=2e-4)
    finally:
        sc.close()
