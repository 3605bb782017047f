"""Task 'reach' (every id but the Easy ones): the open gripper starts above the cylinder's top and
away from it, the fingers only approximately aligned; a policy has to find the cylinder, come down
over it, grip it through the misalignment and lift it.

The grip starts uniformly over the annulus ``approach`` (4-14 cm) around the origin, the
fingertips REACH_CLEARANCE above the cylinder's top; the cylinder stands anywhere within +-7 cm;
the fingers are misaligned by a jaw wedge of up to +-0.15 rad and a yaw of up to +-pi/4. The spread
of start and cylinder (as wide as the workspace allows) keeps every constant action sequence at or
below 10 % success. Why these ranges: rigid fingers lose the cylinder from a small jaw wedge on,
while the tissue holds it far beyond the range; offset and yaw alone break neither, and the
cylinder is round, so the yaw only turns the grasp (the package's documentation, Results: the
env's design and the stability maps).
"""

from __future__ import annotations

import math

from .lift import LiftTask, StartRanges

REACH_CLEARANCE = 0.02
"""The open fingertips start this far above the cylinder's top [m]."""
PAD_CLEARANCE = 0.005
"""A pad thicker than REACH_CLEARANCE - PAD_CLEARANCE starts this far above the top instead [m]."""
APPROACH = (0.04, 0.14)
"""Default annulus the grip starts in, around the origin [m]."""


def clearance(pad: float) -> float:
    """How far above the cylinder's top the cores' tips start with a pad ``pad`` thick [m]: 2 cm,
    but a pad thicker than 1.5 cm would reach the top (the cylinder may stand right under the
    start), so it keeps 5 mm of clearance instead."""
    return max(REACH_CLEARANCE, pad + PAD_CLEARANCE)


class ReachTask(LiftTask):
    name = "reach"
    defaults = dict(cylinder_position=0.07, yaw=math.pi / 4, jaw_wedge=0.15, carry=True)

    def __init__(self, ranges: StartRanges, *, approach: tuple[float, float] = APPROACH, **kwargs) -> None:
        super().__init__(ranges, **kwargs)
        self.approach = (float(approach[0]), float(approach[1]))

    @classmethod
    def start_height(cls, cylinder_height: float, finger_half_height: float, pad: float) -> float:
        return 0.5 * cylinder_height + finger_half_height + clearance(pad)

    @classmethod
    def tallest_cylinder(cls, top: float, finger_half_height: float, pad: float) -> float:
        return top - finger_half_height - clearance(pad)

    def gripper_xy(self, u: tuple[float, float]) -> tuple[float, float]:
        lo, hi = self.approach
        # uniform over the annulus' area, not over r: a uniform r crowds the starts near the
        # inner radius, where one constant move finds the cylinder far more often
        r = math.sqrt(lo * lo + 0.5 * (u[0] + 1.0) * (hi * hi - lo * lo))
        phi = math.pi * u[1]
        return (r * math.cos(phi), r * math.sin(phi))


__all__ = ["APPROACH", "REACH_CLEARANCE", "ReachTask"]
