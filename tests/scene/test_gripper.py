"""The gripper's control: the env's action as a GripperControl (the palm's velocity, kept in the
workspace; the finger target), the arm's path
(speed and acceleration limits exactly, no overshoot, the same at every dt), and a control
applied to the scene moves the palm and fingers as it says, smoothly under any action sequence."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from softgrasp_env.config import SimConfig
from softgrasp_env.scene import GraspScene, GripperControl, SceneConfig, Workspace
from softgrasp_env.scene.gripper import (
    GRIP_TOP,
    MAX_LEAD,
    WORKSPACE_HALF_WIDTH,
    PalmPath,
    VelocityActions,
)

CFG = SceneConfig(fingers="rigid")
WS = Workspace.of(CFG)
G2P = np.array([0.0, 0.0, 0.08])  # palm above the grip point
A_MAX, V_MAX = CFG.arm_acceleration, CFG.arm_speed


def _scene(palm_target, palm=None):
    """What an action reads of the scene: the arm's target, the palm, the palm's offset."""
    palm = np.asarray(palm_target if palm is None else palm, dtype=np.float64)
    return SimpleNamespace(palm_target=np.asarray(palm_target, dtype=np.float64), palm_state=lambda: (palm,),
                           grip_to_palm=lambda: G2P)  # fmt: skip


def test_the_workspace_is_the_documented_box():
    np.testing.assert_allclose(WS.low, [-WORKSPACE_HALF_WIDTH, -WORKSPACE_HALF_WIDTH,
                                        CFG.finger_half_extents[2] + CFG.tissue.extrude + 0.003])  # fmt: skip
    np.testing.assert_allclose(WS.high, [WORKSPACE_HALF_WIDTH, WORKSPACE_HALF_WIDTH, GRIP_TOP])


def test_the_arm_keyword_is_retired():
    """SceneConfig(arm="smooth") (the only arm left) warns and is the default; the jump arm of
    release 0.6.0 is a ValueError naming it."""
    with pytest.warns(DeprecationWarning, match="arm='smooth' is deprecated"):
        assert SceneConfig(fingers="rigid", arm="smooth") == CFG
    with pytest.raises(ValueError, match=r"arm='jump' was retired; `pip install softgrasp-env==0\.6\.0`"):
        SceneConfig(arm="jump")
    with pytest.raises(ValueError, match="no longer an argument"):
        SceneConfig(arm="teleport")


def test_a_smooth_arm_action_is_a_velocity_with_the_workspace_as_its_box():
    actions = VelocityActions(0.15, 20.0, WS, CFG.finger_travel)
    c = actions.control(np.array([1.0, -0.5, 0.0, 1.0]), _scene([0.0, 0.0, 0.2]))
    assert c.palm_target is None
    np.testing.assert_allclose(c.palm_velocity, [0.15, -0.075, 0.0], atol=1e-15)
    np.testing.assert_allclose(c.palm_box[0], WS.low + G2P)
    np.testing.assert_allclose(c.palm_box[1], WS.high + G2P)
    assert c.finger_closing == pytest.approx(CFG.finger_travel)
    assert actions.control(np.zeros(4), _scene([0.0, 0.0, 0.2])).finger_closing == pytest.approx(0.03)


def _run(path: PalmPath, control: GripperControl, steps: int, palm=None) -> np.ndarray:
    """The setpoint at each step (the palm following it exactly unless ``palm`` is given)."""
    xs = [list(path.x)]
    for _ in range(steps):
        path.step(control, path.x if palm is None else palm)
        xs.append(list(path.x))
    return np.array(xs)


def _rates(xs: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    v = np.diff(xs, axis=0) / dt
    return np.linalg.norm(v, axis=1), np.linalg.norm(np.diff(v, axis=0), axis=1) / dt


@pytest.mark.parametrize("dt", [1 / 1000, 1 / 240, 1 / 120])
def test_the_path_to_a_target_keeps_both_limits_stops_on_it_and_takes_the_same_time_at_every_dt(dt):
    """5 cm: a trapezoid (accelerate at a to v_max, cruise, brake), arriving after d / v + v / a =
    0.433 s in continuous time; the discrete path may take a step or two more, never overshoots."""
    path = PalmPath(np.zeros(3), v_max=V_MAX, a_max=A_MAX, dt=dt)
    target = np.array([0.03, 0.0, 0.04])
    xs = _run(path, GripperControl(target, 0.0), int(round(0.8 / dt)))
    speed, accel = _rates(xs, dt)
    assert speed.max() <= V_MAX * (1 + 1e-12)
    assert accel.max() <= A_MAX * (1 + 1e-9)
    np.testing.assert_allclose(xs[-1], target, atol=1e-12)
    along = xs @ (target / np.linalg.norm(target))
    assert along.max() <= np.linalg.norm(target) + 1e-12  # no overshoot
    arrived = np.argmax(np.linalg.norm(xs - target, axis=1) < 1e-9) * dt
    assert arrived == pytest.approx(0.05 / V_MAX + V_MAX / A_MAX, abs=3 * dt)
    assert path.v == [0.0, 0.0, 0.0] and not path.step(GripperControl(target, 0.0), path.x)  # at rest there


def test_a_velocity_command_ramps_up_at_the_acceleration_limit_and_brakes_before_the_workspace_wall():
    dt = 1 / 240
    box = (np.array([-0.1, -0.1, 0.0]), np.array([0.1, 0.1, 0.3]))
    path = PalmPath(np.zeros(3), v_max=V_MAX, a_max=A_MAX, dt=dt)
    xs = _run(path, GripperControl(None, 0.0, palm_velocity=np.array([0.3, 0.0, 0.0]), palm_box=box), 480)
    speed, accel = _rates(xs, dt)
    assert speed[0] == pytest.approx(A_MAX * dt)  # from rest: one step of a dt
    k = int(math.ceil(V_MAX / (A_MAX * dt)))
    assert speed[k:k + 10].max() == pytest.approx(V_MAX)  # the command, capped at v_max
    assert accel.max() <= A_MAX * (1 + 1e-9)
    assert xs[:, 0].max() <= 0.1 + 1e-12 and xs[-1, 0] == pytest.approx(0.1, abs=1e-9)  # stopped at the wall
    assert speed[-1] == pytest.approx(0.0, abs=1e-12)


def _python_path_step(x, v, control, palm, v_max, a_max, dt, max_lead=MAX_LEAD):
    """The arm's path step written out in Python floats (as it ran before it was compiled): the
    reference the compiled step must match to the bit."""

    def brake(d):
        u = d / (a_max * dt * dt)
        m = math.floor(0.5 * (math.sqrt(8.0 * u + 1.0) - 1.0))
        return a_max * dt * (u + 0.5 * m * (m + 1)) / (m + 1)

    u = control.palm_velocity
    wx, wy, wz = (0.0, 0.0, 0.0) if u is None else (float(u[0]), float(u[1]), float(u[2]))
    if control.palm_target is not None:
        t = control.palm_target
        ex, ey, ez = float(t[0]) - x[0], float(t[1]) - x[1], float(t[2]) - x[2]
        d = math.sqrt(ex * ex + ey * ey + ez * ez)
        if d > 0.0:
            s = brake(d) / d
            wx, wy, wz = wx + ex * s, wy + ey * s, wz + ez * s
    vx, vy, vz = v
    if wx == wy == wz == 0.0 and vx == vy == vz == 0.0:
        return x, v
    w = math.sqrt(wx * wx + wy * wy + wz * wz)
    if w > v_max:
        wx, wy, wz = wx * v_max / w, wy * v_max / w, wz * v_max / w
    lx, ly, lz = x[0] - float(palm[0]), x[1] - float(palm[1]), x[2] - float(palm[2])
    lead = math.sqrt(lx * lx + ly * ly + lz * lz)
    if lead > 0.0:
        out = (wx * lx + wy * ly + wz * lz) / lead
        cap = brake(max(0.0, max_lead - lead))
        if out > cap:
            wx, wy, wz = wx - (out - cap) * lx / lead, wy - (out - cap) * ly / lead, wz - (out - cap) * lz / lead
    w3 = [wx, wy, wz]
    if control.palm_box is not None:
        low, high = control.palm_box
        for k in range(3):
            if w3[k] > 0.0:
                w3[k] = min(w3[k], brake(max(0.0, float(high[k]) - x[k])))
            elif w3[k] < 0.0:
                w3[k] = max(w3[k], -brake(max(0.0, x[k] - float(low[k]))))
    dx, dy, dz = w3[0] - vx, w3[1] - vy, w3[2] - vz
    dv = math.sqrt(dx * dx + dy * dy + dz * dz)
    lim = a_max * dt
    if dv > lim:
        dx, dy, dz = dx * lim / dv, dy * lim / dv, dz * lim / dv
    v = [vx + dx, vy + dy, vz + dz]
    return [x[0] + v[0] * dt, x[1] + v[1] * dt, x[2] + v[2] * dt], v


def test_the_compiled_path_step_gives_the_python_formulas_numbers_to_the_bit():
    """Random targets, velocities, boxes and lagging palms, 1,000 steps: the compiled step (IEEE
    double, no contraction) equals the same formulas in Python floats exactly."""
    rng = np.random.default_rng(3)
    dt = 1 / 240
    path = PalmPath(np.zeros(3), v_max=V_MAX, a_max=A_MAX, dt=dt)
    x, v = [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
    control = None
    for step in range(1000):
        if step % 25 == 0:  # a new control now and then, of every kind
            kind = rng.integers(3)
            box = (rng.uniform(-0.2, 0.0, 3), rng.uniform(0.0, 0.2, 3)) if rng.random() < 0.5 else None
            if kind == 0:
                control = GripperControl(rng.uniform(-0.1, 0.1, 3), 0.0, palm_box=box)
            elif kind == 1:
                control = GripperControl(None, 0.0, palm_velocity=rng.uniform(-0.3, 0.3, 3), palm_box=box)
            else:
                control = GripperControl(rng.uniform(-0.1, 0.1, 3), 0.0, palm_velocity=rng.uniform(-0.05, 0.05, 3),
                                         palm_box=box)  # fmt: skip
        palm = np.array(x) + (rng.normal(scale=0.01, size=3) if step % 3 else 0.0)  # sometimes lagging
        moved = path.step(control, palm)
        x2, v2 = _python_path_step(x, v, control, palm, V_MAX, A_MAX, dt)
        assert moved == (x2 is not x)
        x, v = x2, v2
        assert path.x == x and path.v == v, f"step {step}: {path.x} {path.v} != {x} {v}"


def test_the_setpoint_waits_for_a_blocked_palm():
    dt = 1 / 240
    path = PalmPath(np.zeros(3), v_max=V_MAX, a_max=A_MAX, dt=dt)
    stuck = np.zeros(3)  # the palm pressing on something, not moving
    xs = _run(path, GripperControl(None, 0.0, palm_velocity=np.array([0.0, 0.0, -0.15])), 480, palm=stuck)
    assert np.linalg.norm(xs, axis=1).max() <= MAX_LEAD + V_MAX * dt


def test_a_control_moves_the_palm_and_fingers_where_it_says():
    sc = GraspScene(CFG)
    try:
        target = sc.start_palm + np.array([0.01, 0.0, 0.02])
        control = GripperControl(target, 0.02)
        for _ in range(240):
            sc.step(control)
        assert sc.control is control and sc.palm_target is target
        np.testing.assert_allclose(sc.palm_setpoint, target, atol=1e-12)
        np.testing.assert_allclose(sc.palm_position(), target, atol=2e-4)
        np.testing.assert_allclose(sc.finger_closing(), [0.02, 0.02], atol=2e-4)
    finally:
        sc.close()


@pytest.mark.parametrize("dt", [1 / 1000, 1 / 240, 1 / 120])
def test_the_palm_itself_stays_under_the_acceleration_limit_under_bang_bang_actions(dt):
    """The env's actions flipping between full speed one way and the other every control step
    (the hardest on the arm), with a cylinder in the way: the palm's own acceleration, from
    pybullet's velocities at every physics step, stays under 2 m/s^2 (the arm's 1.5 plus what its
    constraint and the contacts add) at every dt; an arm whose target jumped once per control step
    (release 0.6.0's v1/v2) kicked it at 86 m/s^2 (1/240 s)."""
    cfg = SceneConfig(fingers="rigid", sim=SimConfig(dt=dt))
    sc = GraspScene(cfg)
    actions = VelocityActions(cfg.arm_speed, 20.0, Workspace.of(cfg), cfg.finger_travel)
    rng = np.random.default_rng(0)
    per_control = int(round(1 / (20.0 * dt)))
    try:
        v_prev, peak = sc.palm_state()[2].copy(), 0.0
        for k in range(40):
            a = np.concatenate([np.sign(rng.uniform(-1, 1, 3)) * (1 if k % 2 else -1), rng.uniform(-1, 1, 1)])
            control = actions.control(a, sc)
            for _ in range(per_control):
                sc.step(control)
                v = sc.palm_state()[2].copy()
                peak = max(peak, float(np.linalg.norm(v - v_prev)) / dt)
                v_prev = v
        assert peak <= 2.0, f"peak palm acceleration {peak:.2f} m/s^2 at dt {dt:g}"
    finally:
        sc.close()


@pytest.mark.parametrize(("fingers", "physics"), [("tissue", "thesis"), ("tissue", "v5"), ("rigid", "thesis")])
def test_force_actions_squeeze_with_the_commanded_force(fingers, physics):
    """``finger_action="force"``: the last action entry sets the squeeze, 0 to finger_force. Held
    aloft, the pads press with the commanded force (the taxels' pressure, within 0.5 %; measured
    0.1 %, on SoftGraspEasy-v4 with the thesis tissue, TISSUE_V3; the soft ids' latest physics,
    SoftGraspEasy-v5, too), through the carry's own controls too; at -1 the fingers do not squeeze
    at all."""
    import gymnasium as gym

    import softgrasp_env  # noqa: F401
    from softgrasp_env.policies import ScriptedGraspPolicy
    from tests.helpers import soft_physics

    env_id, keywords = soft_physics("SoftGraspEasy", physics)
    for squeeze in (1.5, 2.5):
        env = gym.make(env_id, fingers=fingers, finger_action="force", tactile=(2, 2), carry=True, **keywords)
        try:
            u = env.unwrapped
            policy = ScriptedGraspPolicy.for_env(env)
            obs, _ = env.reset(seed=0)
            a3 = 2.0 * squeeze / u.args.control.finger_force - 1.0
            carried = 0
            for _ in range(100):  # the episode, its carry included
                action = policy(obs)
                action[3] = a3 if action[3] > 0 else -1.0
                obs, _, _, _, info = env.step(action)
                if u.task.carrying(u.scene.steps):
                    carried += 1
                    assert u.scene.control.finger_force == pytest.approx(squeeze)
            assert carried >= 20 and info["held"] and info["lift_height"] > 0.04
            grid = u.plan.taxel_grid
            pressed = u._last.tactile[..., 0].sum(axis=(1, 2)) * grid.area
            np.testing.assert_allclose(pressed, squeeze, rtol=5e-3)
        finally:
            env.close()
    env = gym.make(env_id, fingers=fingers, finger_action="force", **keywords)
    try:
        env.reset(seed=0)
        for _ in range(20):
            obs, *_ = env.step(np.array([0.0, 0.0, 0.0, -1.0], dtype=np.float32))
        assert env.unwrapped.scene.control.finger_force == 0.0
        assert np.all(env.unwrapped._last.force == 0.0)
    finally:
        env.close()
    with pytest.raises(ValueError, match="finger_action"):
        gym.make("SoftGraspEasy-v5", finger_action="torque")
