"""Finger kinds 'rigid' and 'rigid_torsion': the bare cores touch the cylinder through pybullet's
own contacts - the rigid-only twin the thesis compares the tissue against, and that twin made as
faithful as pybullet allows. The friction of the core links is the finger surface's static
coefficient (``SceneConfig.tissue.friction_static``), pybullet having one coefficient per body.

**Why a torsional coefficient.** A point contact carries no moment about its normal: misaligned
flat fingers touch a round cylinder at two points, and it swings about the line through them. A
real fingertip - and the tissue - touches over a patch, whose Coulomb friction resists spin about
the normal up to mu * integral p |r - c| dA = mu * l * N (p the pressure, c the centre of
pressure, N the normal force, l the pressure-weighted radius of the patch).
``RigidConfig.spinning_friction`` is that lever l [m]; 'rigid_torsion' defaults it to the tissue's
own patch (:data:`PATCH_SPINNING_FRICTION`).

**The contract with Bullet.** The lever is applied as pybullet's ``spinningFriction =
friction_static * l`` on the core links only; Bullet multiplies it by the cylinder's friction, so
each contact resists spin up to mu * l * N, mu its combined lateral coefficient (the limit follows
mu whatever the cylinder's friction or a ``friction_scale``). Bullet bounds that torque and the
lateral friction each on its own, where the tissue's patch law makes them share mu N; the rows
are solved only with pybullet's implicit cone friction on (its default, which the scene never
changes). Rolling friction is not set: a pad resists rolling by its pressure's shift, which
Coulomb friction does not bound. The package's documentation (Finger kinds, "The rigid kinds'
contact model") follows Bullet's source to this rule and gives the measurements.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..validation import check_range
from .base import FingerConfig, FingerKind, FingerSite

PATCH_SPINNING_FRICTION = 0.0167
"""The tissue's own torsional lever on the cylinder [m]: the pressure-weighted radius
l = sum N_i |r_i - c| / sum N_i of its particle contacts, in the default soft grasp
(SoftGraspEasy-v3, aligned and centred, the scripted policy's squeeze). Measured, not tuned; the
package's documentation (Finger kinds, "The rigid kinds' contact model") gives the measurement
and how little misalignment and the tissue's resolution move it."""

SPINNING_FRICTION_MAX = 0.1
"""Largest ``spinning_friction`` taken [m]: 10 cm (the scene checks the lever against its own
finger face, :meth:`RigidFingers.check`)."""


@dataclass(frozen=True, eq=False)
class RigidConfig(FingerConfig):
    """Settings of the rigid fingers."""

    kind = "rigid"
    spinning_friction: float = 0.0
    """Torsional lever l of each core's contact [m]: the contact resists spin about its normal up
    to mu * l * N (mu the contact's lateral coefficient, N its normal force), as a patch of
    pressure-weighted radius l would. 0: pybullet's point contacts (the plain twin, unchanged).
    Applied as pybullet's ``spinningFriction = friction_static * l`` on the core links only (the
    module docstring gives the rule)."""

    def __post_init__(self) -> None:
        check_range("spinning_friction", self.spinning_friction, 0.0, SPINNING_FRICTION_MAX, owner=type(self).__name__)


class RigidFingers(FingerKind):
    name = "rigid"
    config_type = RigidConfig
    description = "the bare cores through pybullet's rigid contacts (the rigid-only twin)"

    @classmethod
    def check(cls, scene_config) -> None:
        """The lever of any pressure on the face is at most the face's half diagonal (pressure at
        two opposite corners): a larger one describes no patch the core can have."""
        lever = scene_config.fingers.spinning_friction
        fh = scene_config.finger_half_extents
        reach = float(np.hypot(fh[1], fh[2]))
        if lever > reach:
            name = type(scene_config.fingers).__name__
            raise ValueError(f"{name}.spinning_friction={lever!r} m is more than the finger face's half diagonal "
                             f"{reach:.4g} m: no contact patch on the face has that lever")  # fmt: skip

    def mount(self, site: FingerSite):
        """Give the core links their torsional coefficient (none for l = 0: pybullet's default, so
        the plain twin's contacts stay exactly what they were)."""
        specs = super().mount(site)
        lever = self.config.spinning_friction
        if lever > 0.0:
            c, g = site.client, site.gripper
            for link in site.core_links:
                # mu_core * l: Bullet multiplies it by the cylinder's friction (module docstring), so
                # the contact's limit is mu * l * N with mu = mu_core * mu_cylinder, its lateral one.
                # In a call of its own: pybullet drops a whole changeDynamics call on a link that
                # also asks for damping (softgrasp_env/scene/gripper.py).
                spin = c.getDynamicsInfo(g, link)[1] * lever
                c.changeDynamics(g, link, spinningFriction=spin)
                if c.getDynamicsInfo(g, link)[7] != spin:
                    raise RuntimeError(f"pybullet did not take the spinning friction of gripper link {link}")
        return specs


@dataclass(frozen=True, eq=False)
class TorsionalRigidConfig(RigidConfig):
    """Settings of the torsional rigid fingers: the rigid ones with the tissue's patch lever."""

    kind = "rigid_torsion"
    spinning_friction: float = PATCH_SPINNING_FRICTION
    """Torsional lever l of each core's contact [m] (as ``RigidConfig.spinning_friction``); the
    default is the tissue's own patch, :data:`PATCH_SPINNING_FRICTION` (16.7 mm)."""


class TorsionalRigidFingers(RigidFingers):
    name = "rigid_torsion"
    config_type = TorsionalRigidConfig
    description = "the bare cores with torsional friction of the tissue's contact patch (the faithful rigid twin)"


__all__ = ["PATCH_SPINNING_FRICTION", "SPINNING_FRICTION_MAX", "RigidConfig", "RigidFingers", "TorsionalRigidConfig",
           "TorsionalRigidFingers"]  # fmt: skip
