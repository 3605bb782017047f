"""The grasp scene: its settings (config.py), the objects it can grasp (objects.py), the gripper
and its control (gripper.py), and the scene that builds and steps ground, object, gripper and
world (scene.py)."""

from .config import (
    FINGER_DROP,
    GEOMETRY_MARGIN,
    PALM_HALF_EXTENTS,
    SceneConfig,
    arm_force_limit,
    fit_error,
    geometry_error,
    grasp_height,
    scale_friction,
)
from .gripper import GRIP_TOP, Gripper, GripperActions, GripperControl, Workspace
from .scene import CYLINDER_SHAPE, SHAPES, SLOTS, GraspScene

__all__ = ["CYLINDER_SHAPE", "FINGER_DROP", "GEOMETRY_MARGIN", "GRIP_TOP", "PALM_HALF_EXTENTS",
           "SHAPES", "SLOTS", "GraspScene", "Gripper", "GripperActions", "GripperControl", "SceneConfig",
           "Workspace", "arm_force_limit", "fit_error", "geometry_error", "grasp_height", "scale_friction"]
