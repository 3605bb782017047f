"""Task 'easy' (SoftGraspEasy-v5, SoftGraspEasyRigid-v3, SoftGraspEasyRigidTorsion-v3): the gentle start, for debugging a policy
or the physics - the open fingers around the cylinder's top (the grip point 5 cm above its mid
height, over the origin), aligned (no wedge, yaw within +-5 degrees), the cylinder within +-1 cm.
An open-loop "close, then lift" succeeds here, so it is no benchmark."""

from __future__ import annotations

import math

from .lift import LiftTask

EASY_START_HEIGHT = 0.05
"""The grip point starts this far above the cylinder's mid height [m]."""


class EasyTask(LiftTask):
    name = "easy"
    defaults = dict(cylinder_position=0.01, yaw=math.radians(5.0), jaw_wedge=0.0, carry=False)

    @classmethod
    def start_height(cls, cylinder_height: float, finger_half_height: float, pad: float) -> float:
        return EASY_START_HEIGHT

    @classmethod
    def tallest_cylinder(cls, top: float, finger_half_height: float, pad: float) -> float:
        return 2.0 * (top - EASY_START_HEIGHT)


__all__ = ["EASY_START_HEIGHT", "EasyTask"]
