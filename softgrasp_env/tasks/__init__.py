"""Tasks behind one interface (base.py): the lift task both starts share (lift.py), its two starts
``STARTS`` names - the reach task (reach.py) and the gentle start (easy.py) - and the compositions
over them: the carry test (carry.py), the grip-force task over it (grip.py) and the goal variant (goal.py)."""

from __future__ import annotations

from .base import Outcome, Task, TaskWrapper
from .carry import CarryTest
from .easy import EasyTask
from .goal import GoalTask
from .grip import GripForceTask
from .lift import RESET_OPTIONS, LiftTask, StartRanges, check_option
from .reach import ReachTask

STARTS: dict[str, type[LiftTask]] = {start.name: start for start in (ReachTask, EasyTask)}
"""The starts ``gym.make(..., start=name)`` takes; each class's ``defaults`` are its ranges."""

_DEPRECATED = {"TASKS": ("STARTS", lambda: STARTS), "LeastSqueeze": ("GripForceTask", lambda: GripForceTask)}
"""Names before 0.7: ``TASKS`` held the starts, ``LeastSqueeze`` was the grip-force task's class."""


def __getattr__(name: str):
    if name in _DEPRECATED:
        from ..validation import deprecated

        new, value = _DEPRECATED[name]
        deprecated(f"softgrasp_env.tasks.{name}", f"softgrasp_env.tasks.{new}", stacklevel=3)
        return value()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["RESET_OPTIONS", "STARTS", "CarryTest", "EasyTask", "GoalTask", "GripForceTask", "LiftTask", "Outcome",
           "ReachTask", "StartRanges", "Task", "TaskWrapper", "check_option"]
