"""Fixtures every test folder shares (helpers.py holds the plain functions)."""

from __future__ import annotations

import gymnasium as gym
import pytest

import softgrasp_env  # noqa: F401  (registers the ids)
from agents.scripted import ScriptedGraspPolicy


@pytest.fixture
def make_env():
    """``make_env(env_id, **kwargs)``: ``gym.make``, closed after the test whatever happens."""
    made = []

    def make(env_id: str, **kwargs):
        env = gym.make(env_id, **kwargs)
        made.append(env)
        return env

    yield make
    for env in made:
        env.close()


@pytest.fixture
def scripted() -> ScriptedGraspPolicy:
    """The scripted grasp policy (stateless, observation only)."""
    return ScriptedGraspPolicy()
