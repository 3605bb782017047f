"""The observation by name: every entry of every id's observation is the Reading's field of that
name, and the named slices find them."""

from __future__ import annotations

import numpy as np
import pytest

from softgrasp_env import ENV_IDS
from softgrasp_env.observation import CARRY_OBS_NAMES, OBS_GROUPS, OBS_NAMES, obs_slice
from tests.helpers import obs_vector


def test_names_and_groups_agree():
    assert OBS_NAMES == tuple(n for g, names in OBS_GROUPS.items() if g != "time" for n in names)
    assert CARRY_OBS_NAMES == OBS_NAMES + ("time",) and len(OBS_NAMES) == 23
    assert obs_slice(OBS_NAMES, "force") == slice(19, 21) and obs_slice(CARRY_OBS_NAMES, "time") == slice(23, 24)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_every_entry_is_the_reading_of_its_name(env_id, make_env, scripted):
    env = make_env(env_id)
    obs, _ = env.reset(seed=1)
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
