"""Changing tissue state: struct of float64 arrays, copied whole for save/restore."""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from .model import TissueModel

ANCHOR_SLOTS = 2
"""Friction anchors kept per particle: one per shape it touches (a particle at the cylinder's
bottom edge can touch the cylinder and the ground at once)."""


@dataclass(eq=False)
class TissueState:
    particle_x: np.ndarray
    """(N, 3) world position [m]."""
    particle_v: np.ndarray
    """(N, 3) world velocity [m/s]."""
    particle_q: np.ndarray
    """(N, 4) world orientation [x, y, z, w]."""
    particle_omega: np.ndarray
    """(N, 3) world angular velocity [rad/s]."""
    group_q: np.ndarray
    """(N, 4) last extracted rotation of each group (rest frame -> world): the warm start of
    Mueller et al. 2016, so degenerate groups keep their rotation instead of snapping to identity."""
    particle_anchor_shape: np.ndarray
    """(N, K) int32: the shape each of a particle's K friction anchors sticks to, -1 for none."""
    particle_anchor_x: np.ndarray
    """(N, K, 3) the anchor in its shape's frame [m]: where the particle's centre was, relative to
    the shape, when its contact began to stick (see tissue/friction.py)."""
    particle_anchor_slide: np.ndarray
    """(N, K) bool: the anchor's contact patch was sliding at the end of the last step."""

    def copy(self) -> TissueState:
        return TissueState(**{f.name: getattr(self, f.name).copy() for f in fields(self)})

    def assign(self, other: TissueState) -> None:
        """Overwrite this state's arrays in place with ``other``'s values."""
        for f in fields(self):
            getattr(self, f.name)[...] = getattr(other, f.name)

    def is_finite(self) -> bool:
        return all(bool(np.isfinite(getattr(self, f.name)).all()) for f in fields(self))


def state_at_rest(model: TissueModel, body_x: np.ndarray, body_q: np.ndarray) -> TissueState:
    """State with every body's particles at their rest configuration placed at pose (x, q) per body.

    ``body_x`` is (B, 3) and ``body_q`` (B, 4): the pose of each body's rest frame in the world.
    """
    from .rotation import quat_to_matrix

    n = model.particle_count
    x = np.empty((n, 3))
    q = np.empty((n, 4))
    group_q = np.empty((n, 4))
    for b in range(model.body_count):
        s = model.body_slice(b)
        rot = quat_to_matrix(body_q[b])
        x[s] = model.particle_rest_x[s] @ rot.T + body_x[b]
        q[s] = _quat_mul_batch(np.asarray(body_q[b], dtype=np.float64), model.particle_rest_q[s])
        group_q[s] = body_q[b]
    return TissueState(
        particle_x=x,
        particle_v=np.zeros((n, 3)),
        particle_q=q,
        particle_omega=np.zeros((n, 3)),
        group_q=group_q,
        particle_anchor_shape=np.full((n, ANCHOR_SLOTS), -1, dtype=np.int32),
        particle_anchor_x=np.zeros((n, ANCHOR_SLOTS, 3)),
        particle_anchor_slide=np.zeros((n, ANCHOR_SLOTS), dtype=np.bool_),
    )


def _quat_mul_batch(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a (4,) times each row of b (K, 4), Hamilton product, [x, y, z, w]."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b[:, 0], b[:, 1], b[:, 2], b[:, 3]
    return np.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        axis=1,
    )
