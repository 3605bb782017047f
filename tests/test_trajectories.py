"""Behaviour does not change under restructuring or speed work: the v3 ids (random actions and the
scripted policy) and the settings reached through kwargs replay bit-identically against the
trajectories 0.5.0 recorded (tests/trajectories.py says what each case runs)."""

from __future__ import annotations

import numpy as np
import pytest

import softgrasp_env  # noqa: F401  (registers the ids)
from tests.trajectories import SETS, fingerprint, record

_GOLDEN = {set_name: dict(np.load(path).items()) for set_name, (_, path) in SETS.items()}
_CASES = [(set_name, *case) for set_name, (cases, _) in SETS.items() for case in cases]


@pytest.mark.parametrize(("set_name", "name", "env_id", "kwargs", "policy", "steps"), _CASES,
                         ids=[f"{c[0]}:{c[1]}" for c in _CASES])  # fmt: skip
def test_trajectory_is_bit_identical_to_the_recording(set_name, name, env_id, kwargs, policy, steps):
    golden = _GOLDEN[set_name]
    here, there = fingerprint(), str(golden["fingerprint"])
    if here != there:
        pytest.skip(f"recorded on {there!r}, this is {here!r}: bit-identity is promised on the same machine and "
                    f"libraries only (re-record with python -m tests.trajectories at the recording's commit)")  # fmt: skip
    got = record(env_id, kwargs, policy, steps)
    for key, arr in got.items():
        want = golden[f"{name}/{key}"]
        assert arr.shape == want.shape, f"{name}/{key}: shape {arr.shape} != recorded {want.shape}"
        if arr.tobytes() != want.tobytes():
            first = int(np.flatnonzero((arr != want).reshape(len(arr), -1).any(axis=1))[0])
            pytest.fail(f"{name}/{key} differs from the recording first at row {first}: {arr[first]!r} != {want[first]!r}")
