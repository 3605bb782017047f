"""Behaviour does not change under restructuring or speed work: every registered id (random
actions and the scripted policy) and the finger kinds reached through kwargs replay
bit-identically against the trajectories recorded before issue 18 (v1/v2) and before issue 20
(v3; tests/trajectories.py says what each case runs)."""

from __future__ import annotations

import numpy as np
import pytest

import softgrasp_env  # noqa: F401  (registers the ids)
from tests.trajectories import CASES, DATA, DATA_V3, V3_CASES, fingerprint, record

_GOLDEN = {**{k: v for k, v in np.load(DATA).items()},
           **{f"v3:{k}": v for k, v in np.load(DATA_V3).items()}}
REPLAY_STEPS = {"fem/scripted": 4}
"""Cases replayed over a prefix of their recording: pybullet's FEM pads run ~0.6 s per env step
(every recorded row is a prefix of the next, so a shorter replay is compared row for row)."""


_ALL = [("", *c) for c in CASES] + [("v3:", *c) for c in V3_CASES]


@pytest.mark.parametrize(("prefix", "name", "env_id", "kwargs", "policy", "steps"), _ALL, ids=[c[0] + c[1] for c in _ALL])
def test_trajectory_is_bit_identical_to_the_recording(prefix, name, env_id, kwargs, policy, steps):
    here, there = fingerprint(), str(_GOLDEN[f"{prefix}fingerprint"])
    if here != there:
        pytest.skip(f"recorded on {there!r}, this is {here!r}: bit-identity is promised on the same machine and "
                    f"libraries only (re-record with python -m tests.trajectories at the recording's commit)")  # fmt: skip
    got = record(env_id, kwargs, policy, REPLAY_STEPS.get(name, steps))
    for key, arr in got.items():
        want = _GOLDEN[f"{prefix}{name}/{key}"][: len(arr)]
        assert arr.shape == want.shape, f"{name}/{key}: shape {arr.shape} != recorded {want.shape}"
        if arr.tobytes() != want.tobytes():
            first = int(np.flatnonzero((arr != want).reshape(len(arr), -1).any(axis=1))[0])
            pytest.fail(f"{name}/{key} differs from the recording first at row {first}: {arr[first]!r} != {want[first]!r}")
