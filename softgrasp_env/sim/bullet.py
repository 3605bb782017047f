"""pybullet side: one BulletClient per world, and the rigid bodies the tissue sees.

Never the module-level ``pybullet.*`` global client: every world owns its own physics server
connection, so several envs live in one process without sharing state.
"""

from __future__ import annotations

import contextlib
import functools
import os
import sys
from dataclasses import dataclass

import numba as nb
import numpy as np
import pybullet as p
from pybullet_utils.bullet_client import BulletClient


class Client(BulletClient):
    """pybullet_utils' BulletClient, with each function's wrapper made once: BulletClient builds a
    ``functools.partial`` with the client id on every attribute access (~1.4 us a call: getattr,
    ``inspect.isbuiltin``, a new partial), and the scene calls pybullet a few times per physics
    step. Here the first access stores the partial on the instance, where later accesses find it
    without ``__getattr__``. ``disconnect`` is not stored (BulletClient marks the client closed
    when it is looked up)."""

    def __getattr__(self, name: str):
        attribute = super().__getattr__(name)
        if name != "disconnect" and isinstance(attribute, functools.partial):
            self.__dict__[name] = attribute
        return attribute


def connect(*, gui: bool = False) -> BulletClient:
    """A new physics server of our own (DIRECT unless a GUI is asked for).

    pybullet's C code prints "argv[0]=" to the process's stdout on every connect; with one client
    per env that line would interleave with a user's own output, so it is swallowed here (only the
    connect call's C-level stdout, and only in DIRECT mode)."""
    mode = p.GUI if gui else p.DIRECT
    if gui:
        return Client(connection_mode=mode)
    with _quiet_c_stdout():
        return Client(connection_mode=mode)


@contextlib.contextmanager
def _quiet_c_stdout():
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # no real stdout (e.g. captured): nothing to hide
        yield
        return
    sys.stdout.flush()
    saved = os.dup(fd)
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), fd)
            try:
                yield
            finally:
                os.dup2(saved, fd)
    finally:
        os.close(saved)


@dataclass(frozen=True)
class RigidRef:
    """A pybullet body or link seen by the tissue as one rigid slot."""

    body: int
    link: int
    """-1 for the base."""
    gravity: bool
    """Predicted under gravity (free body) or not (held by joints/constraints)."""
    in_solve: bool
    """Takes its mass-weighted share of tissue corrections inside the solve, whatever the coupling
    (a free body such as the cylinder)."""
    free_base: bool
    """A free base body: tissue impulses change its velocity directly; otherwise they become an
    external force and torque for pybullet's next step (links, constrained bases)."""
    core: bool = False
    """The rigid core of a combined body: it joins the solve (``in_solve``) under the consistent
    coupling. A core on a link must hang on a prismatic joint then: it moves along the joint axis
    inside the solve, under its joint motor's last force (see World)."""


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


class StateReader:
    """Reads centre-of-mass pose and velocity of every slot, in as few pybullet calls as it can:
    all links of one body come from one ``getLinkStates``. It calls pybullet's functions with the
    world's own ``physicsClientId`` directly; BulletClient's per-call wrapper costs ~1.3 us a call,
    a noticeable share of a 300 us step. Arguments go by position: pybullet parses keywords at
    ~0.4 us a call."""

    def __init__(self, client: BulletClient, refs: list[RigidRef]) -> None:
        self._cid = client._client
        self._bases: list[tuple[int, int]] = []  # (slot, body)
        links: dict[int, list[tuple[int, int]]] = {}
        for k, r in enumerate(refs):
            if r.link < 0:
                self._bases.append((k, r.body))
            else:
                links.setdefault(r.body, []).append((k, r.link))
        self._links = [(body, [k for k, _ in kl], [link for _, link in kl]) for body, kl in links.items()]
        self._order = np.array([k for k, _ in self._bases] + [k for _, ks, _ in self._links for k in ks], dtype=np.intp)
        self._count = len(refs)
        self._refs = list(refs)
        self._buf = np.zeros((self._count, 13))
        self._flat = self._buf.reshape(-1)

    def read(self, x: np.ndarray, q: np.ndarray, v: np.ndarray, w: np.ndarray) -> None:
        if self._count == 0:
            return
        cid = self._cid
        vals: tuple = ()
        for _, body in self._bases:
            pos, orn = p.getBasePositionAndOrientation(body, cid)
            lin, ang = p.getBaseVelocity(body, cid)
            vals += pos + orn + lin + ang
        for body, _, link_ids in self._links:
            # (bodyUniqueId, linkIndices, computeLinkVelocity, computeForwardKinematics, physicsClientId)
            for s in p.getLinkStates(body, link_ids, 1, 0, cid):
                vals += s[0] + s[1] + s[6] + s[7]
        # One flat copy into a fixed buffer (faster than np.array of nested rows) and one compiled
        # scatter for all slots: numpy slice assignments per field cost more than the reads.
        self._flat[:] = vals
        _scatter(self._buf, self._order, x, q, v, w)

    def position(self, slot: int) -> tuple[float, float, float]:
        """Slot ``slot``'s centre of mass [m], by itself: the value :meth:`read` gives it."""
        r = self._refs[slot]
        if r.link < 0:
            return p.getBasePositionAndOrientation(r.body, self._cid)[0]
        return p.getLinkStates(r.body, [r.link], 1, 0, self._cid)[0][0]


@nb.njit(cache=True)
def _scatter(a, order, x, q, v, w):
    for r in range(a.shape[0]):
        k = order[r]
        for c in range(3):
            x[k, c] = a[r, c]
            v[k, c] = a[r, 7 + c]
            w[k, c] = a[r, 10 + c]
        for c in range(4):
            q[k, c] = a[r, 3 + c]
