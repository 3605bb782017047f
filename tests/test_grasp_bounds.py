"""The env's own scripted grasp against Coulomb, at the defaults users get (the accuracy targets):
the aligned gentle start (SoftGraspEasy-v4 with the thesis tissue, TISSUE_V3 / SoftGraspEasyRigid-v3,
yaw, wedge, offset and position 0), 3 N per finger, mu_s = mu_k = 0.9, dt 1/240 unless stated;
every figure from one physics step to the next (benchmarks/grasp_checks.py, which also bisects the
bounds)."""

from __future__ import annotations

import pytest

from benchmarks.grasp_checks import KINDS, NO_SLIP, scripted_episode
from softgrasp_env.config import DEFAULT_MAX_DEVIATION

G, MU, FORCE = 9.81, 0.9, 3.0
A_ARM = 1.5
"""The arm's acceleration limit: the lift's peak acceleration (measured 1.49 m/s^2 at 1/240 s)."""


@pytest.mark.parametrize("hz", [1000, 480, 240, 120])
@pytest.mark.parametrize("kind", ["soft", "soft-v5", "rigid"])
def test_the_scripted_grasp_holds_with_little_in_hand_motion_at_every_dt(kind, hz):
    """Held at every dt from 1/1000 to 1/120 s with in-hand motion (lift-off to the end) under
    1 mm and the palm under 2 m/s^2. Measured soft 0.29 / 0.41 / 0.35 / 0.30 mm (the soft ids'
    latest physics, the v4 tissue solved globally: 0.24 / 0.37 / 0.33 / 0.25 mm; the per-step
    material of 0.4.0: 0.15 / 0.34 / 1.10 / 0.04, its pad crushed at 1/120), rigid <= 0.01 mm,
    palm 1.0-1.5 m/s^2 (release 0.6.0's v1 ids' arm: dropped at 1/1000, 48.7 / 3.7 / 3.0 mm soft, 71 / 31 /
    7.4 / 0 mm rigid, 500 / 344 / 86 / 22 m/s^2)."""
    r = scripted_episode(KINDS[kind], "v3", dt=1.0 / hz)
    assert r["held"] and not r["diverged"]
    assert r["in_hand"] < 0.001, f"{r['in_hand'] * 1e3:.2f} mm"
    # the tissue's strain limit (TissueConfig.max_deviation, 2 cm) is for snags, never reached in a
    # grasp (measured: the largest deviation 5.5 mm at 0.45 kg, 5.2 mm through the carry)
    assert r["deviation"] < DEFAULT_MAX_DEVIATION / 2
    assert r["peak_accel"] <= 2.0


def _held(kind: str, **options) -> bool:
    r = scripted_episode(KINDS[kind], "v3", options=options)
    return r["held"] and r["in_hand"] < NO_SLIP


BOUNDS = {"soft": (0.95, 1.05), "soft-consistent": (0.95, 1.05), "soft-contact": (1.0, 1.12), "soft-v4": (1.05, 1.15),
          "soft-v4-16k": (1.03, 1.13), "soft-v5": (1.05, 1.15), "soft-v5-16k": (1.03, 1.13), "rigid": (1.0, 1.12),
          "rigid_torsion": (1.0, 1.12)}  # fmt: skip
"""Held at the first multiple of Coulomb's bound, not at the second. Bisected (benchmarks/
grasp_checks.py): soft and consistent 0.463 kg (-3.0 % against this bound; -4.5 % with the palm's
peak measured at the boundary, 1.33 m/s^2; +1.3 / -1.0 % with the cylinder's own, 2.00 / 1.74),
within 5 % (the per-step material of release 0.6.0's v1/v2: 0.433, -9.3 %: the cylinder bounced on
pads whose stiffness was a per-step number); rigid and torsional 0.515 (+7.8 %: the cylinder
leaves the ground part-way through the arm's acceleration, its own peak 1.1 m/s^2:
2 mu F / (g + 1.1) = 0.494 kg, +4.2 %). Coulomb per contact (friction_law "contact") 0.522 kg
(+9.2 %; +7.6 % with the palm's measured 1.33 m/s^2): each contact's friction is bounded by mu
times its own normal force, and on pads wrapped round the cylinder those sum to more than the
squeeze (6.19 N for 2F = 6 N, contacts up to ~60 degrees round it), so the bound is
mu sum N / (g + a) = 0.500 kg, +4.3 %. The v4 tissue (SoftGraspEasy-v4's: the continuum material,
Coulomb per contact) 0.529 kg (+10.7 %): +7.6 % with the palm's measured peak, 1.18 m/s^2, +5.3 %
with the cylinder's own, 0.95, and +3.2 % against mu sum N / (g + a), its contacts pressing
6.25 N in all. Refined to 16,000 per m^2 (``preset="fine"``): 0.515 kg (+7.8 %; +5.5 % with the
palm's 1.26 m/s^2, +4.0 % with the cylinder's 1.10, +3.0 % against mu sum N / (g + a)). The same
tissue solved globally (SoftGraspEasy-v5's, ``soft-v5``): 0.529 kg, as swept (+10.7 %; +4.6 %
against mu sum N / (g + a), its contacts pressing 6.26 N); at 16,000 per m^2 0.508 kg (+6.3 %;
+3.1 % against mu sum N / (g + a), 6.10 N)."""


@pytest.mark.parametrize("kind", list(BOUNDS))
def test_the_heaviest_cylinder_held_is_near_coulombs_bound(kind):
    """2 mu_s F / (g + a) = 0.478 kg with the lift's a = 1.5 m/s^2; held: at the end, with at most
    5 mm of in-hand motion (the v3 success's slide limit)."""
    bound = 2 * MU * FORCE / (G + A_ARM)
    low, high = BOUNDS[kind]
    assert _held(kind, cylinder_mass=low * bound)
    assert not _held(kind, cylinder_mass=high * bound)


SLIP_ONSET = 0.001
"""In-hand motion [m] past which a grasp counts as slipping, for the onset test below (the v3
success allows 5 mm)."""


@pytest.mark.parametrize("kind", ["rigid", "rigid_torsion"])
def test_the_rigid_grip_begins_to_slip_at_coulombs_bound(kind):
    """The rigid kinds' +7.8 % above (held with up to 5 mm in the hand) is a slow slip that starts
    at Coulomb's bound: measured in-hand motion 0.03 / 0.07 / 0.78 / 2.45 / 4.56 / 6.27 mm at 0.47 /
    0.48 / 0.49 / 0.50 / 0.51 / 0.515 kg (bound 0.478 kg): held still within 5 % below the bound,
    slipping more than 1 mm within 5 % above it. (The tissue shears elastically by up to 1.3 mm
    long before it slips, so its onset is not this sharp: the 5 mm test above is the soft one.)"""
    bound = 2 * MU * FORCE / (G + A_ARM)
    still = scripted_episode(KINDS[kind], "v3", options={"cylinder_mass": 0.95 * bound})
    assert still["held"] and still["in_hand"] < SLIP_ONSET, still
    slipping = scripted_episode(KINDS[kind], "v3", options={"cylinder_mass": 1.05 * bound})
    assert slipping["in_hand"] > SLIP_ONSET, slipping


FRICTION = {"soft": (1.05, 0.95), "soft-consistent": (1.05, 0.95), "soft-contact": (1.0, 0.85), "soft-v4": (0.95, 0.85),
            "soft-v4-16k": (0.97, 0.87), "rigid": (1.05, 0.9), "rigid_torsion": (1.05, 0.9)}  # fmt: skip
"""Lifts at the first multiple of Coulomb's lowest friction, not at the second. Bisected: soft
0.210 x the default (+0.3 %), consistent 0.207 x (-1.1 %) (the per-step material: 0.225 x,
+7.5 %), rigid and torsional 0.205 x (-2.2 %), Coulomb per contact 0.191 x (-8.6 %: its contacts'
normal forces sum to 1.03 x the squeeze, as above), the v4 tissue 0.189 x (-9.9 %; -7.1 % with the
palm's measured peak, 1.16 m/s^2), at 16,000 per m^2 0.193 x (-7.8 %; -5.7 % with the palm's
1.25 m/s^2); the target is 10 %."""


@pytest.mark.parametrize("kind", list(FRICTION))
def test_the_lowest_friction_that_lifts_is_near_coulombs(kind):
    """m (g + a) / 2F mu = 0.209 x the default friction lifts 0.1 kg."""
    bound = 0.1 * (G + A_ARM) / (2 * FORCE) / MU
    lifts, slips = FRICTION[kind]
    assert _held(kind, friction_scale=lifts * bound)
    assert not _held(kind, friction_scale=slips * bound)
