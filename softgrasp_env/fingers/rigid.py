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

**A lever that follows the load** (``spinning_friction="patch"``). The patch, and so l, depends on
the object and the squeeze: on the upright cylinder the pad wraps the whole face and l hardly
moves, on a sphere the patch is a disc growing with the indentation, on a cone's slanted side a
strip. :data:`PATCH_LEVERS` is the tissue's own l against its normal force per named object
(measured: the package's documentation, Finger kinds); with "patch" each core's lever is l(N) of its own normal force on
the object in the last physics step, interpolated linearly in that table, and set before every
step (Ciocarlie, Lackner & Allen 2007 make the soft-finger contact's torsion limit a function of
the normal load the same way). Bullet stores the combined coefficient on a contact point when its
narrow phase makes or replaces the point (btPersistentManifold::replaceContactPoint copies it,
refreshContactPoints keeps it), so a new value reaches the manifold's points as they are renewed
over the next steps, not all at once.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass

import numpy as np
import pybullet as p

from ..validation import check_range
from .base import FingerConfig, FingerKind, FingerSite

PATCH_SPINNING_FRICTION = 0.0167
"""The tissue's own torsional lever on the cylinder [m]: the pressure-weighted radius
l = sum N_i |r_i - c| / sum N_i of its particle contacts, in the default soft grasp
(SoftGraspEasy-v4 with the thesis tissue, TISSUE_V3; aligned and centred, the scripted policy's squeeze). Measured, not tuned; the
package's documentation (Finger kinds, "The rigid kinds' contact model") gives the measurement
and how little misalignment and the tissue's resolution move it."""

PATCH = "patch"
"""``spinning_friction=PATCH``: the lever of the scene's object from :data:`PATCH_LEVERS`, following
each core's normal force (module docstring)."""

PATCH_LEVERS: dict[str, tuple[tuple[float, float], ...]] = {
    "cylinder": ((0.50, 0.01567), (1.00, 0.01656), (2.90, 0.01696), (5.77, 0.01708)),
    "rod": ((0.50, 0.01514), (1.15, 0.01488), (2.97, 0.01460), (4.33, 0.01426)),
    "sphere": ((0.57, 0.00762), (1.04, 0.00981), (2.97, 0.01092), (5.65, 0.01182)),
    "cube": ((0.50, 0.01465), (1.00, 0.01473), (3.00, 0.01497), (6.00, 0.01501)),
    "slab": ((0.43, 0.00943), (1.14, 0.01601), (2.93, 0.01607), (6.15, 0.01649)),
    "capsule": ((0.50, 0.00791), (1.03, 0.00776), (2.94, 0.01024), (5.90, 0.00699)),
    "cone": ((0.47, 0.00575), (0.91, 0.00907), (2.77, 0.01137), (5.62, 0.01433)),
    "elliptic": ((0.50, 0.01559), (1.00, 0.01537), (2.65, 0.01588), (5.19, 0.01599)),
    "pebble-0": ((0.46, 0.01027), (0.99, 0.01192), (2.78, 0.01478), (5.51, 0.01525)),
    "pebble-1": ((0.43, 0.00504), (0.98, 0.00792), (2.80, 0.01066), (5.55, 0.00973)),
    "pebble-2": ((0.43, 0.00733), (1.02, 0.00936), (2.66, 0.01020), (5.41, 0.00807)),
}
"""The tissue's own torsional lever per named object (softgrasp_env.scene.objects.PRESETS) against
its normal force: object -> ((N [N], l [m]), ...), N increasing. Measured on
the default v4 tissue (SoftGraspEasy-v4, 4,000 particles per m^2,
the default finger face and pad): the scripted grasp, aligned and centred, with the squeeze as the
action at 0.5, 1, 3 and 6 N per finger, N and l = sum N_i |r_i - c| / sum N_i the two fingers'
mean over the hold (lifted; at 0.5 N, where that squeeze does not hold the object aloft, squeezed
standing on the ground; the sphere lifts). N is the tissue's measured normal force, not the
command (the rod's 6 N reads 4.3 N: the fingers reach their stop). The rod was measured 12 mm
across; a 10 mm rod reads within 0.2 mm of it at every squeeze. The shapes are matched by value:
an object scaled from a preset by at most :data:`PATCH_SCALE_RANGE` takes the preset's (not
re-measured at its size), one scaled further has none. Measured, not tuned; the
package's documentation (Finger kinds, "The lever per object, following the load") gives the
table with the converged tissue's beside it."""

PATCH_SCALE_RANGE = 0.15
"""A named object scaled by at most this either way (every dimension alike: the object-set ids'
``object_scale_range``) takes its own size's table [-]; beyond it there is no measured lever."""

LEVER_QUANTUM = 1e-5
"""Resolution of the load-following lever [m]: the table's own (0.01 mm). l(N) is rounded to it, so
a steady hold's normal force, which pybullet's solver moves a little every step, does not call
``changeDynamics`` every step for changes the table does not resolve."""

SPINNING_FRICTION_MAX = 0.1
"""Largest ``spinning_friction`` taken [m]: 10 cm (the scene checks the lever against its own
finger face, :meth:`RigidFingers.check`)."""


@dataclass(frozen=True, eq=False)
class RigidConfig(FingerConfig):
    """Settings of the rigid fingers."""

    kind = "rigid"
    spinning_friction: float | str = 0.0
    """Torsional lever l of each core's contact [m]: the contact resists spin about its normal up
    to mu * l * N (mu the contact's lateral coefficient, N its normal force), as a patch of
    pressure-weighted radius l would. 0: pybullet's point contacts (the plain twin, unchanged).
    Applied as pybullet's ``spinningFriction = friction_static * l`` on the core links only (the
    module docstring gives the rule). ``"patch"``: the tissue's measured lever of the scene's object
    (:data:`PATCH_LEVERS`; a named object only), following each core's normal force: l(N) linear
    in the table between its loads; below its lowest load and above its highest l is that end's
    value (the model's choice: the tissue was not measured there), not a limit on the load."""

    def __post_init__(self) -> None:
        if _is_patch(self.spinning_friction):
            return
        if isinstance(self.spinning_friction, str):
            raise ValueError(f"{type(self).__name__}.spinning_friction must be a finite number, got "
                             f"{self.spinning_friction!r}: a lever in metres, or {PATCH!r} (the tissue's measured "
                             "lever of the scene's object)")  # fmt: skip
        check_range("spinning_friction", self.spinning_friction, 0.0, SPINNING_FRICTION_MAX, owner=type(self).__name__)


class RigidFingers(FingerKind):
    name = "rigid"
    config_type = RigidConfig
    description = "the bare cores through pybullet's rigid contacts (the rigid-only twin)"

    def __init__(self, scene_config) -> None:
        super().__init__(scene_config)
        self._loads: tuple[float, ...] = ()
        """With "patch": the table's loads N [N], increasing (empty: a fixed lever)."""
        self._levers: tuple[float, ...] = ()
        """With "patch": the table's levers l [m] at those loads."""
        if _is_patch(self.config.spinning_friction):
            table = PATCH_LEVERS[patch_object(scene_config)]
            self._loads = tuple(n for n, _ in table)
            self._levers = tuple(lv for _, lv in table)
        self._mu = (0.0, 0.0)
        self._spin = [0.0, 0.0]
        """With "patch": the spinning coefficient each core link has now (changeDynamics only on a change)."""

    @classmethod
    def check(cls, scene_config) -> None:
        """The lever of any pressure on the face is at most the face's half diagonal (pressure at
        two opposite corners): a larger one describes no patch the core can have. ``"patch"``: the
        scene's object must be one with a measured lever (:data:`PATCH_LEVERS`), whose largest
        lever is checked so."""
        lever = scene_config.fingers.spinning_friction
        if _is_patch(lever):
            lever = max(lv for _, lv in PATCH_LEVERS[patch_object(scene_config)])
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
        if self._loads:
            # "patch": start at the lever of no load (the table's lowest load's, held below it)
            c, g = site.client, site.gripper
            self._mu = tuple(c.getDynamicsInfo(g, link)[1] for link in site.core_links)
            lever0 = self.lever(0.0)
            for k, link in enumerate(site.core_links):
                self._set_spin(k, link, self._mu[k] * lever0)
                if c.getDynamicsInfo(g, link)[7] != self._spin[k]:
                    raise RuntimeError(f"pybullet did not take the spinning friction of gripper link {link}")
            return specs
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

    def lever(self, load: float) -> float:
        """With "patch": the lever l(N) [m] at a core's normal force ``load`` [N]: linear between the
        table's loads, the end value outside them, rounded to :data:`LEVER_QUANTUM`."""
        loads, levers = self._loads, self._levers
        if load <= loads[0]:
            lever = levers[0]
        elif load >= loads[-1]:
            lever = levers[-1]
        else:
            i = bisect.bisect_right(loads, load)
            t = (load - loads[i - 1]) / (loads[i] - loads[i - 1])
            lever = levers[i - 1] + t * (levers[i] - levers[i - 1])
        return round(lever / LEVER_QUANTUM) * LEVER_QUANTUM

    def before_step(self) -> None:
        """With "patch": each core's lever from its normal force on the object in the last physics step
        (pybullet's contact points of the core link with the object, their normal forces summed),
        set as ``spinningFriction = mu_core * l(N)`` when it changed. A fixed lever: nothing."""
        if not self._loads:
            return
        s = self.site
        # one query for both cores, by position (as FingerKind.contact_force: this runs every step)
        points = p.getContactPoints(s.cylinder, s.gripper, -1, -2, s.client._client)
        for k, link in enumerate(s.core_links):
            load = 0.0
            for pt in points:
                if pt[4] == link:
                    load += pt[9]
            spin = self._mu[k] * self.lever(load)
            if spin != self._spin[k]:
                self._set_spin(k, link, spin)

    def _set_spin(self, k: int, link: int, spin: float) -> None:
        # in a call of its own, as mount's (pybullet drops a whole call that also asks for damping)
        self.site.client.changeDynamics(self.site.gripper, link, spinningFriction=spin)
        self._spin[k] = spin


@dataclass(frozen=True, eq=False)
class TorsionalRigidConfig(RigidConfig):
    """Settings of the torsional rigid fingers: the rigid ones with the tissue's patch lever."""

    kind = "rigid_torsion"
    spinning_friction: float | str = PATCH_SPINNING_FRICTION
    """Torsional lever l of each core's contact [m] (as ``RigidConfig.spinning_friction``); the
    default is the tissue's own patch on the cylinder, :data:`PATCH_SPINNING_FRICTION` (16.7 mm);
    ``"patch"``: the tissue's lever of the scene's object, following the load
    (:data:`PATCH_LEVERS`)."""


def _is_patch(lever) -> bool:
    return isinstance(lever, str) and lever == PATCH


def patch_object(scene_config) -> str:
    """The name of the scene's object in :data:`PATCH_LEVERS` (the preset whose shape it is), or
    ValueError naming the objects that have a measured lever."""
    # the scene's config knows which named object it holds and at what size (SceneConfig.preset_scale)
    named = scene_config.preset_scale()
    if named is not None:
        name, factor = named
        # a preset drawn at another size (object_scale_range): its own table, not re-measured
        # there. Over +-15 % a sphere's Hertzian patch a ~ sqrt(R delta) moves by at most 7.5 %, a
        # face-long contact's lever (set by the pad's height) hardly at all.
        if name in PATCH_LEVERS and abs(factor - 1.0) <= PATCH_SCALE_RANGE + 1e-12:
            return name
    shape = scene_config.object_shape
    owner = type(scene_config.fingers).__name__
    raise ValueError(f"{owner}.spinning_friction='patch' takes the tissue's measured lever of a named object, one of "
                     f"{tuple(PATCH_LEVERS)}, at its own size or scaled by at most {PATCH_SCALE_RANGE:g} either way; "
                     f"the scene's object {shape!r} has none: give the lever in metres")  # fmt: skip


class TorsionalRigidFingers(RigidFingers):
    name = "rigid_torsion"
    config_type = TorsionalRigidConfig
    description = "the bare cores with torsional friction of the tissue's contact patch (the faithful rigid twin)"


__all__ = ["LEVER_QUANTUM", "PATCH", "PATCH_LEVERS", "PATCH_SCALE_RANGE", "PATCH_SPINNING_FRICTION", "SPINNING_FRICTION_MAX", "RigidConfig", "RigidFingers", "TorsionalRigidConfig",
           "TorsionalRigidFingers"]  # fmt: skip
