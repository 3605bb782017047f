"""``gym.make`` for the benchmarks, which measured some of their figures on ids since retired: a
retired id that a registered id with keywords reproduces step for step
(softgrasp_env.registration.RETIRED_AS: the thesis tissue's SoftGrasp-v3 is SoftGrasp-v4 with
TISSUE_V3) is made as that; any other id as itself. So a benchmark keeps naming its figures' id
and still runs on this release."""

from __future__ import annotations

from typing import Any

import gymnasium as gym

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.registration import RETIRED_AS


def make(env_id: str, **kwargs: Any) -> gym.Env:
    """``gym.make(env_id, **kwargs)``, a retired id of RETIRED_AS made as its registered twin
    (``kwargs`` over the twin's keywords)."""
    made, keywords = RETIRED_AS.get(env_id, (env_id, {}))
    return gym.make(made, **{**keywords, **kwargs})
