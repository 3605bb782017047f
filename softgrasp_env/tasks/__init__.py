"""Tasks behind one interface (base.py): the lift task both starts share (lift.py), its two starts
``TASKS`` names - the reach task (reach.py) and the gentle start (easy.py) - and the compositions
over them: the carry test (carry.py), the grip-force task over it (grip.py) and the goal variant (goal.py)."""

from __future__ import annotations

from .base import Outcome, Task, TaskWrapper
from .carry import CarryTest
from .easy import EasyTask
from .goal import GoalTask
from .grip import LeastSqueeze
from .lift import RESET_OPTIONS, LiftTask, StartRanges, check_option
from .reach import ReachTask

TASKS: dict[str, type[LiftTask]] = {task.name: task for task in (ReachTask, EasyTask)}
"""The starts ``gym.make(..., task=name)`` takes; each class's ``defaults`` are its ranges."""

__all__ = ["RESET_OPTIONS", "TASKS", "CarryTest", "EasyTask", "GoalTask", "LeastSqueeze", "LiftTask", "Outcome", "ReachTask",
           "StartRanges", "Task", "TaskWrapper", "check_option"]
