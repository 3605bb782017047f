"""Finger kinds 'rigid' and 'rigid_torsion': the bare cores touch the cylinder through pybullet's
own contacts - the rigid-only twin the thesis compares the tissue against, and that twin made as
faithful as pybullet allows. The friction of the core links is the finger surface's static
coefficient (``SceneConfig.tissue.friction_static``), pybullet having one coefficient per body.

**Why a torsional coefficient.** A point contact carries no moment about its normal: misaligned
flat fingers touch a round cylinder at two points, and it swings about the line through them
(tests/tasks/test_carry.py). A real fingertip - and the tissue - touches over a patch, whose
Coulomb friction resists spin about the normal up to mu * integral p |r - c| dA = mu * l * N
(p the pressure, c the centre of pressure, N the normal force, l the pressure-weighted radius of
the patch). ``RigidConfig.spinning_friction`` is that lever l; 'rigid_torsion' defaults it to the
tissue's own patch (:data:`PATCH_SPINNING_FRICTION`), measured, not tuned.

**What Bullet does with it** (bullet3 at the pybullet 3.2.7 release, commit 6c888f4ab; read in
the source, and checked against the physics in tests/fingers/test_torsion.py):

- ``btManifoldResult::calculateCombinedSpinningFriction`` (src/BulletCollision/CollisionDispatch/
  btManifoldResult.cpp) combines the two bodies' coefficients as ``spin0 * friction1 + spin1 *
  friction0``, clamped to [-10, 10]; lateral friction combines as ``friction0 * friction1``
  (``calculateCombinedFriction``). ``btManifoldResult::addContactPoint`` stores both on every
  contact point when it is made. The cylinder's spinning coefficient is 0 (btCollisionObject's
  default), so setting the core link's to ``friction_core * l`` gives the contact ``friction_core *
  friction_cylinder * l = mu * l``, mu the contact's combined lateral coefficient: the torque limit
  follows mu as the patch's does, whatever the cylinder's friction or a ``friction_scale``.
- The gripper is a btMultiBody, so its contacts go through ``btMultiBodyConstraintSolver::
  convertMultiBodyContact`` (src/BulletDynamics/Featherstone/btMultiBodyConstraintSolver.cpp): every
  point of the manifold (at most 4, MANIFOLD_CACHE_SIZE in btPersistentManifold.h; the counter
  ``rollingFriction`` starts at 4) with ``m_combinedSpinningFriction > 0`` gets a spinning row
  (``addMultiBodySpinningFrictionConstraint``): a purely angular constraint about the contact
  normal (``setupMultiBodyTorsionalFrictionConstraint``: zero linear Jacobian, the normal as the
  torque axis), an angular impulse bounded in ``solveSingleIteration`` by +-(combined coefficient
  x that point's normal impulse). So the coefficient is a length [m], the torque limit is
  ``mu * l * N_i`` per point and ``mu * l * N`` over the contact, and the row is a box limit of its
  own, solved before the lateral rows - not coupled to them in one limit surface as the tissue's
  patch friction is (softgrasp_env/tissue/friction.py). No contact flag is needed.
- Those rows are solved only when the solver mode has SOLVER_USE_2_FRICTION_DIRECTIONS and not
  SOLVER_DISABLE_IMPLICIT_CONE_FRICTION: btMultiBodyDynamicsWorld's constructor sets the first,
  the second is pybullet's ``setPhysicsEngineParameter(enableConeFriction=0)``, which the scene never
  sends (pybullet's ``getPhysicsEngineParameters`` does not report it). With cone friction off the
  coefficient would be silently ignored.
- (Contacts between maximal-coordinate bodies go through ``btSequentialImpulseConstraintSolver::
  convertContact`` instead, which adds the spinning row only if the *rolling* coefficient is
  positive too, and whose ``solveSingleIteration`` also caps the row's impulse at the coefficient
  itself; the gripper and the cylinder are multibodies, so none of that applies.)
- pybullet takes ``changeDynamics(..., spinningFriction=)`` (values >= 0) and reports it as
  ``getDynamicsInfo(...)[7]``.
- A box core against the cylinder: GJK/EPA gives one point per step, the persistent manifold
  keeps up to 4; measured in the scripted rigid grasp: 3-4 points per finger along an aligned
  face's line contact (whose lateral friction at the separate points resists spin already), 1 at
  a misaligned face's edge (jaw wedge -0.1; tests/fingers/test_torsion.py), where only the
  spinning row does.

Rolling friction (``rollingFriction``, the rows about the two tangents, combined the same way) is
not set: a pad resists rolling by its pressure's shift, which Coulomb friction does not bound.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..validation import check_range
from .base import FingerConfig, FingerKind, FingerSite

PATCH_SPINNING_FRICTION = 0.0167
"""The tissue's own torsional lever on the cylinder [m]: l = sum N_i |r_i - c| / sum N_i over its
particle contacts (benchmarks/contact_patch.py), in the default soft grasp (SoftGraspEasy-v3,
aligned, centred, the scripted policy's squeeze, 2.89 N per finger) measured 16.67 / 16.66 mm on
the two fingers over the hold (steady to 0.01 mm); 15.6 mm at a two-point misaligned start (jaw
wedge -0.1 rad): the pad wraps the cylinder either way, 12 particle contacts spanning 44.9 mm
along its axis and 23.2 mm around it. A uniformly pressed disc of the patch's largest radius
(26.7 mm) would give (2/3) a = 17.8 mm. Finer or coarser tissue hardly moves it: 17.0 mm at 2,500
particles per m^2, 16.1 at 8,000, 17.0 at 16,000. (0.4.0's per-step material, its pad pressed
7 mm deep at 1/240 s against the compliant one's 4.3 mm, wrapped more of the cylinder: 17.75 mm,
the default then.) The tissue's patch friction bounds torsion by mu times this radius
(tissue/friction.py, its ``e``), so the rigid peer resists spin as the tissue does - though
Bullet bounds torsion and lateral friction each on its own, where the tissue's limit surface
makes them share mu N."""

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
    module docstring gives Bullet's rule)."""

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
