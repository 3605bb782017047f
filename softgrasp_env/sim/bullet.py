"""pybullet side: one BulletClient per world, and the rigid bodies the tissue sees.

Never the module-level ``pybullet.*`` global client: every world owns its own physics server
connection, so several envs live in one process without sharing state.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pybullet as p
from pybullet_utils.bullet_client import BulletClient


def connect(*, gui: bool = False) -> BulletClient:
    """A new physics server of our own (DIRECT unless a GUI is asked for)."""
    return BulletClient(connection_mode=p.GUI if gui else p.DIRECT)


@dataclass(frozen=True)
class RigidRef:
    """A pybullet body or link seen by the tissue as one rigid slot."""

    body: int
    link: int
    """-1 for the base."""
    gravity: bool
    """Predicted under gravity (free body) or not (held by joints/constraints)."""
    in_solve: bool
    """Takes its mass-weighted share of tissue corrections inside the solve."""
    free_base: bool
    """A free base body: tissue impulses change its velocity directly; otherwise they become an
    external force and torque for pybullet's next step (links, constrained bases)."""


def read_mass_properties(client: BulletClient, refs: list[RigidRef]) -> tuple[np.ndarray, np.ndarray]:
    """(inverse mass (R,), inverse principal inertia (R, 3)) of each slot; 0 where mass is 0."""
    inv_m = np.zeros(len(refs))
    inv_i = np.zeros((len(refs), 3))
    for k, r in enumerate(refs):
        info = client.getDynamicsInfo(r.body, r.link)
        mass = float(info[0])
        inertia = np.asarray(info[2], dtype=np.float64)
        orn = info[4]
        if abs(orn[3]) < 1.0 - 1e-9:
            raise ValueError(
                f"body {r.body} link {r.link}: inertial frame must be aligned with the link frame "
                f"(got orientation {orn}); build cores with their principal axes on the link axes"
            )
        if mass > 0.0:
            inv_m[k] = 1.0 / mass
            inv_i[k] = np.where(inertia > 0.0, 1.0 / np.maximum(inertia, 1e-300), 0.0)
    return inv_m, inv_i


def read_states(
    client: BulletClient,
    refs: list[RigidRef],
    x: np.ndarray,
    q: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
) -> None:
    """Fill centre-of-mass pose and velocity of every slot into the given (R, ...) arrays."""
    for k, r in enumerate(refs):
        if r.link < 0:
            pos, orn = client.getBasePositionAndOrientation(r.body)
            lin, ang = client.getBaseVelocity(r.body)
        else:
            s = client.getLinkState(r.body, r.link, computeLinkVelocity=1)
            pos, orn, lin, ang = s[0], s[1], s[6], s[7]
        x[k] = pos
        q[k] = orn
        v[k] = lin
        w[k] = ang


def world_inverse_inertia(q: np.ndarray, inv_inertia_local: np.ndarray) -> np.ndarray:
    """R diag(I^-1) R^T for one body."""
    from ..tissue.rotation import quat_to_matrix

    rot = quat_to_matrix(q)
    return (rot * inv_inertia_local) @ rot.T
