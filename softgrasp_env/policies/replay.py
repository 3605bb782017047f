"""Replay buffers that keep scripted demonstrations in every batch, for stable-baselines3's
off-policy learners (the repository's training script fills them with its ``--demo-share``
option).

The first ``kept`` transitions of the buffer (the demonstrations) are never overwritten, and a
fixed fraction ``demo_share`` of each sampled batch comes from them, the rest from the learner's own
transitions: the symmetric sampling of Ball et al. 2023 ("Efficient online reinforcement learning
with offline data", RLPD: 0.5) and the kept demonstrations of Vecerik et al. 2017. The classes live
in the package, not beside it, because SB3 saves a model's ``replay_buffer_class`` with the model:
a model trained with one loads with ``SAC.load`` wherever the package is installed (with the
``[train]`` extra: stable-baselines3 and torch).
"""

from __future__ import annotations

from typing import Any

from ._sb3 import require_sb3

require_sb3("softgrasp_env.policies.replay")  # a clear ImportError on a core install

import numpy as np  # noqa: E402
from stable_baselines3.common.buffers import DictReplayBuffer, ReplayBuffer  # noqa: E402
from stable_baselines3.common.vec_env import VecNormalize  # noqa: E402


class KeptDemonstrations:
    """What :class:`DemoReplayBuffer` and :class:`DictDemoReplayBuffer` add to SB3's buffers: the
    first ``kept`` transitions (the demonstrations, marked by :meth:`keep_demonstrations`) are never
    overwritten, and ``demo_share`` of each sampled batch comes from them (module docstring)."""

    demo_share: float
    kept: int
    buffer_size: int
    pos: int
    full: bool

    def __init__(self, *args: Any, demo_share: float, optimize_memory_usage: bool = False, **kwargs: Any) -> None:
        if not 0.0 < demo_share < 1.0:  # refused before the SB3 buffer allocates its arrays
            raise ValueError(f"demo_share: the fraction of each batch drawn from the demonstrations, in (0, 1); "
                             f"got {demo_share}")  # fmt: skip
        if optimize_memory_usage:  # its next observation is the following slot: a kept block breaks that
            raise ValueError("demo_share needs optimize_memory_usage=False")
        super().__init__(*args, optimize_memory_usage=optimize_memory_usage, **kwargs)  # the SB3 buffer's
        self.demo_share = float(demo_share)
        self.kept = 0

    def keep_demonstrations(self) -> int:
        """Keep the transitions stored so far (the demonstrations) for the rest of training; returns
        their number. Call it once, after the demonstrations are added and before the learner's own."""
        if self.kept:
            raise RuntimeError(f"the buffer keeps {self.kept} demonstration transitions already")
        if self.full or self.pos == 0 or self.pos >= self.buffer_size - 1:
            raise ValueError(f"keep_demonstrations: {self.pos} transitions stored in a buffer of "
                             f"{self.buffer_size}{' (full)' if self.full else ''}; the demonstrations must leave room "
                             "for the learner's own")  # fmt: skip
        self.kept = self.pos
        return self.kept

    def add(self, *args: Any, **kwargs: Any) -> None:
        super().add(*args, **kwargs)  # type: ignore[misc]
        # SB3 wrapped to slot 0 after filling the last one: the learner's own transitions go round
        # behind the kept block instead
        if self.full and self.pos == 0 and self.kept:
            self.pos = self.kept

    def sample(self, batch_size: int, env: VecNormalize | None = None) -> Any:
        return self._get_samples(self._batch_indices(batch_size), env=env)  # type: ignore[attr-defined]

    def sample_kept(self, batch_size: int, env: VecNormalize | None = None) -> Any:
        """A batch of the kept demonstrations alone (for behaviour cloning toward them)."""
        if not self.kept:
            raise RuntimeError("the buffer keeps no demonstrations (keep_demonstrations was not called)")
        return self._get_samples(np.random.randint(0, self.kept, size=batch_size), env=env)  # type: ignore[attr-defined]

    def _batch_indices(self, batch_size: int) -> np.ndarray:
        upper = self.buffer_size if self.full else self.pos
        own = upper - self.kept
        if own <= 0:  # nothing of the learner's yet
            return np.random.randint(0, max(upper, 1), size=batch_size)
        if self.kept == 0:
            return np.random.randint(0, upper, size=batch_size)
        # a fixed count per batch, not a draw per sample: every update sees the same share
        n_demo = int(round(self.demo_share * batch_size))
        return np.concatenate([np.random.randint(0, self.kept, size=n_demo),
                               np.random.randint(self.kept, upper, size=batch_size - n_demo)])  # fmt: skip


class DemoReplayBuffer(KeptDemonstrations, ReplayBuffer):
    """SB3's ReplayBuffer keeping the demonstrations in every batch (module docstring): ``demo_share``
    of each batch from them. SB3 builds it from ``replay_buffer_class`` and
    ``replay_buffer_kwargs={"demo_share": F}``."""


class DictDemoReplayBuffer(KeptDemonstrations, DictReplayBuffer):
    """:class:`DemoReplayBuffer` for dict observations (an asymmetric learner's)."""


def demo_buffer(asymmetric: bool, demo_share: float) -> dict[str, Any]:
    """The SB3 keywords of a buffer that keeps the demonstrations in every batch (``demo_share`` of
    it), for dict observations if ``asymmetric``: ``replay_buffer_class`` and
    ``replay_buffer_kwargs``."""
    cls = DictDemoReplayBuffer if asymmetric else DemoReplayBuffer
    return {"replay_buffer_class": cls, "replay_buffer_kwargs": {"demo_share": demo_share}}


__all__ = ["DemoReplayBuffer", "DictDemoReplayBuffer", "KeptDemonstrations", "demo_buffer"]
