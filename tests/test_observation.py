"""The observation by name: every entry of every id's observation is the Reading's field of that
name, and the named slices find them."""

from __future__ import annotations

import numpy as np
import pytest

from softgrasp_env import ENV_IDS
from softgrasp_env.observation import CARRY_OBS_NAMES, OBS_GROUPS, OBS_NAMES, SHAPE_GROUPS, SHAPE_OBS_NAMES, obs_slice
from tests.helpers import obs_vector


def test_names_and_groups_agree():
    assert OBS_NAMES == tuple(n for g, names in OBS_GROUPS.items() if g not in ("time", *SHAPE_GROUPS) for n in names)
    assert SHAPE_OBS_NAMES == tuple(n for g in SHAPE_GROUPS for n in OBS_GROUPS[g]) and len(SHAPE_OBS_NAMES) == 10
    assert CARRY_OBS_NAMES == OBS_NAMES + ("time",) and len(OBS_NAMES) == 23
    assert obs_slice(OBS_NAMES, "force") == slice(19, 21) and obs_slice(CARRY_OBS_NAMES, "time") == slice(23, 24)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_every_entry_is_the_reading_of_its_name(env_id, make_env, scripted):
    env = make_env(env_id)
    obs, _ = env.reset(seed=1)
    if env.unwrapped.args.control.finger_action == "force":  # the grip ids: their own policy drives them
        from softgrasp_env.policies.grip import ConstantGripPolicy

        scripted = ConstantGripPolicy(env, 3.0)
    for _ in range(25):
        obs, *_ = env.step(scripted(obs))
    u = env.unwrapped
    vec, reading = obs_vector(obs), u._last
    names = u.obs_names
    assert env.observation_space.contains(obs) and len(vec) == len(names)
    for group, members in OBS_GROUPS.items():
        if members[0] not in names:
            continue
        want = np.atleast_1d(np.asarray(getattr(reading, group), dtype=np.float64)).astype(np.float32)
        np.testing.assert_array_equal(vec[obs_slice(names, group)], want, err_msg=group)
    np.testing.assert_allclose(reading.cyl_rel + reading.grip, reading.cylinder_x, rtol=0, atol=1e-15)


@pytest.mark.parametrize("fingers", ["tissue", "rigid"])
def test_tactile_entries_are_the_pads_taxels(fingers, make_env):
    """``tactile=(rows, cols)`` appends the pads' taxels (fingers/tactile.py) after every other
    entry, named by finger, row, column and channel; ``tactile_view`` gives them back as the grid;
    the env passes gymnasium's checker; seeded episodes reproduce them exactly."""
    from gymnasium.utils.env_checker import check_env

    from softgrasp_env.fingers.tactile import TAXEL_CHANNELS
    from softgrasp_env.observation import tactile_names, tactile_view
    from softgrasp_env.policies import ScriptedGraspPolicy

    def run(env):
        policy = ScriptedGraspPolicy.for_env(env)
        obs, _ = env.reset(seed=3)
        for _ in range(50):
            obs, *_ = env.step(policy(obs))
        return obs

    env = make_env("SoftGrasp-v5", fingers=fingers, tactile=(4, 3))
    u = env.unwrapped
    base = make_env("SoftGrasp-v5", fingers=fingers)
    assert u.obs_names == base.unwrapped.obs_names + tactile_names(4, 3)
    assert u.obs_names[-1] == f"tactile_right_r3_c2_{TAXEL_CHANNELS[-1]}" and env.observation_space.shape == (144,)
    obs = run(env)
    grid = tactile_view(obs, u.obs_names)
    assert grid.shape == (2, 4, 3, len(TAXEL_CHANNELS))
    np.testing.assert_array_equal(grid, u._last.tactile.astype(np.float32))
    np.testing.assert_array_equal(obs[: len(base.unwrapped.obs_names)], run(base))  # the rest as without taxels
    assert (grid[..., 0].sum(axis=(1, 2)) * u.plan.taxel_grid.area > 1.0).all()  # the grasp presses both pads
    np.testing.assert_array_equal(run(env), obs)  # seeded: the same again
    check_env(u, skip_render_check=True)


@pytest.mark.parametrize("bad", [(0, 3), (4, 33), (4,), 5, (2.0, 3), "4x3"])
def test_tactile_refuses_a_bad_grid(bad, make_env):
    with pytest.raises(ValueError, match="tactile"):
        make_env("SoftGrasp-v5", tactile=bad)


@pytest.mark.parametrize("fingers", ["tissue", "rigid"])
def test_tactile_history_keeps_the_frames_before(fingers, make_env):
    """``tactile_history=k`` appends the k - 1 taxel frames before this env step's, the last first
    (``tactile_past<d>_``); a new episode's first observation repeats its frame; the frames follow
    the env steps across a reset and through a copy (pickle replays the episode); ``tactile_view``
    still gives this step's grid, and the rest of the observation is the one-frame env's."""
    import pickle

    from gymnasium.utils.env_checker import check_env

    from softgrasp_env.observation import tactile_frames, tactile_names, tactile_view
    from softgrasp_env.policies import ScriptedGraspPolicy

    env = make_env("SoftGrasp-v5", fingers=fingers, tactile=(3, 2), tactile_history=3)
    one = make_env("SoftGrasp-v5", fingers=fingers, tactile=(3, 2))
    u, names = env.unwrapped, env.unwrapped.obs_names
    assert names == one.unwrapped.obs_names + tactile_names(3, 2, 3)[60:]
    assert names[-1].startswith("tactile_past2_right_r2_c1_") and env.observation_space.shape == (len(names),)
    policy = ScriptedGraspPolicy.for_env(env)
    for seed in (3, 4):  # the second episode starts from fresh frames
        obs, _ = env.reset(seed=seed)
        obs1, _ = one.reset(seed=seed)
        first = tactile_frames(obs, names)
        assert first.shape == (3, 2, 3, 2, 5)
        np.testing.assert_array_equal(first[1], first[0])
        np.testing.assert_array_equal(first[2], first[0])
        seen = [obs]
        for _ in range(40):
            obs, *_ = env.step(policy(obs))
            obs1, *_ = one.step(policy(obs1))
            seen.append(obs)
        np.testing.assert_array_equal(obs[: len(obs1)], obs1)
        np.testing.assert_array_equal(tactile_view(obs, names), tactile_view(obs1, one.unwrapped.obs_names))
        frames = tactile_frames(np.array(seen), names)
        for t in range(2, len(seen)):
            np.testing.assert_array_equal(frames[t, 1], frames[t - 1, 0])
            np.testing.assert_array_equal(frames[t, 2], frames[t - 2, 0])
        assert np.abs(frames[-1, 0] - frames[-3, 0]).max() > 0.0  # the taxels change as the grasp closes
    copy = pickle.loads(pickle.dumps(u))
    np.testing.assert_array_equal(copy._format_obs(copy._last), u._format_obs(u._last))
    check_env(u, skip_render_check=True)


@pytest.mark.parametrize("bad", [0, 17, 2.5, "3", True])
def test_tactile_history_refuses_a_bad_count(bad, make_env):
    with pytest.raises((ValueError, TypeError), match="tactile_history"):
        make_env("SoftGraspGripRigid-v5", tactile_history=bad)


def test_tactile_history_needs_the_taxels(make_env):
    with pytest.raises(ValueError, match=r"tactile_history=2 keeps earlier taxel frames: give tactile"):
        make_env("SoftGraspRigid-v3", tactile_history=2)
