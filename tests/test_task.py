"""The task (``task="reach"``, the -v1 ids): it needs a closed-loop policy. The gripper starts above
the cylinder's top, 4-10 cm from the origin in a random direction, the cylinder anywhere within
+-4 cm, the fingers misaligned (jaw wedge up to +-0.15 rad, yaw up to +-pi/4)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import softgrasp_env  # noqa: F401
from agents.scripted import ScriptedGraspPolicy


def _open_loop(name: str) -> list[list[float]]:
    """Constant action sequences a policy without feedback might try (100 steps each)."""
    down_close_up = [[0, 0, -1, -1]] * 14 + [[0, 0, 0, 1]] * 10
    seqs = {
        # the issue's: it solved every v0 episode (the fingers started around the cylinder)
        "close 15, then up": [[0, 0, 0, 1]] * 15 + [[0, 0, 1, 1]] * 85,
        "down, close, up": down_close_up + [[0, 0, 1, 1]] * 76,
        # the best of twelve tried (benchmark below): along +x for 5 steps first
        "+x 5, down, close, up": [[1, 0, 0, -1]] * 5 + down_close_up + [[0, 0, 1, 1]] * 71,
        "+x+y 5, down, close, up": [[0.7, 0.7, 0, -1]] * 5 + down_close_up + [[0, 0, 1, 1]] * 71,
    }
    return seqs[name]


def _success_rate(env, policy_or_actions, seeds) -> float:
    ok = 0
    for seed in seeds:
        obs, _ = env.reset(seed=seed)
        info = {}
        for t in range(100):
            a = policy_or_actions(obs) if callable(policy_or_actions) else np.asarray(policy_or_actions[t], np.float32)
            obs, _, term, trunc, info = env.step(a)
            if term or trunc:
                break
        ok += bool(info["is_success"])
    return ok / len(seeds)


@pytest.mark.parametrize("name", ["close 15, then up", "down, close, up", "+x 5, down, close, up", "+x+y 5, down, close, up"])
def test_open_loop_actions_rarely_succeed(name):
    """No constant action sequence solves the task: measured over 40 seeds on the soft env, the
    twelve tried succeed in 0-2 of 40 (at most 5 %; the rigid twin: at most 3 of 40). Asserted
    here on 20 seeds: at most 2 (10 %)."""
    env = gym.make("SoftGrasp-v1")
    try:
        rate = _success_rate(env, _open_loop(name), range(1000, 1020))
    finally:
        env.close()
    assert rate <= 0.10, f"open-loop {name!r} succeeded in {rate:.0%}"


def test_scripted_policy_solves_the_soft_task():
    """The scripted policy (observation only) succeeds in >= 90 % of seeded episodes with soft
    fingers. Measured: 30 of 30 (seeds 0-29); the rigid twin 14 of 30 - its fingers lose the
    cylinder under the jaw wedge (docs/RESULTS.md), which is what the task is to show."""
    env = gym.make("SoftGrasp-v1")
    try:
        rate = _success_rate(env, ScriptedGraspPolicy(), range(2000, 2020))
    finally:
        env.close()
    assert rate >= 0.9, f"scripted policy: {rate:.0%}"


def test_reach_start_is_above_and_away_and_options_fix_it():
    env = gym.make("SoftGrasp-v1")
    try:
        for seed in range(5):
            env.reset(seed=seed)
            sc = env.unwrapped.scene
            cfg = sc.config
            d = np.hypot(*np.subtract(cfg.gripper_xy, (0.0, 0.0)))
            assert 0.04 - 1e-12 <= d <= 0.10 + 1e-12
            assert abs(cfg.cylinder_xy[0]) <= 0.04 and abs(cfg.cylinder_xy[1]) <= 0.04
            tips = sc.start_palm[2] - sc.palm_offset - cfg.finger_half_extents[2]
            assert tips == pytest.approx(cfg.cylinder_height + 0.02)  # 2 cm above its top
        env.reset(seed=0, options={"gripper_xy": (0.05, -0.02), "cylinder_xy": (0.0, 0.0), "jaw_wedge": 0.1})
        cfg = env.unwrapped.scene.config
        assert cfg.gripper_xy == (0.05, -0.02) and cfg.jaw_wedge == 0.1
    finally:
        env.close()


def test_task_is_validated():
    with pytest.raises(ValueError, match="task must be one of"):
        gym.make("SoftGrasp-v1", task="fly")
    with pytest.raises(ValueError, match="approach_range"):
        gym.make("SoftGrasp-v1", approach_range=(0.05, 0.2))
