"""The goal variant (SoftGraspGoal-v6, -v5), a composition over a lift task for hindsight experience
replay: the cylinder centre is the achieved goal, a point above the cylinder's start the desired
one, and the reward is -1 while they are farther apart than ``distance_threshold``, else 0
(``compute_reward``, vectorised over leading batch dimensions as HER needs). Success is exactly
"compute_reward gives 0" on the goals the agent sees, so relabelled and online rewards agree.
It has no carry test: HER relabels goals alone, and a time-bound test would break that.

Nor does it end an episode when the cylinder is knocked over or pushed out of the workspace, as
the lift task does: with -1 on every step until the goal is reached, an episode that ends early
pays less, so ending it becomes the thing to learn, and HER + SAC on SoftGraspGoal-v3 learned
exactly that (the package's documentation, Results: learned baselines, "HER on the goal id"). The
goal-conditioned
tasks HER was made on run a fixed number of steps (Andrychowicz et al. 2017; Plappert et al.
2018, the Fetch tasks); here only a physics failure ends one early: the cylinder below the
ground or flung above the workspace (lift.py's LOWEST, HIGHEST), and a diverged step (the env's).
That is every registered goal id (since SoftGraspGoal-v4); ``end_when_knocked_over=True`` keeps
the lift task's ends, as SoftGraspGoal-v3 was released with."""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from .base import Outcome, Task, TaskWrapper
from .lift import HIGHEST, LOWEST

if TYPE_CHECKING:
    from ..observation import Reading
    from ..scene import GraspScene

DISTANCE_THRESHOLD = 0.02
"""Default goal tolerance [m]."""
GOAL_HEIGHT_RANGE = (0.05, 0.08)
"""Default range of the goal's height above the cylinder's resting height [m]."""


class GoalTask(TaskWrapper):
    """``task`` with a goal drawn per episode (see the module docstring)."""

    def __init__(self, task: Task, *, distance_threshold: float = DISTANCE_THRESHOLD,
                 goal_height_range: tuple[float, float] = GOAL_HEIGHT_RANGE,
                 end_when_knocked_over: bool = False) -> None:  # fmt: skip
        super().__init__(task)
        self.end_when_knocked_over = bool(end_when_knocked_over)
        self.diverged_reward = -1.0
        self.distance_threshold = float(distance_threshold)
        self.goal_height_range = (float(goal_height_range[0]), float(goal_height_range[1]))
        self.goal = np.zeros(3)
        """The desired goal of the running episode [m]."""

    def begin(self, scene: GraspScene, rng: np.random.Generator) -> None:
        """The goal: above the cylinder's start, its resting height plus U(goal_height_range)
        (drawn after the scene's draws, from the same generator)."""
        self.task.begin(scene, rng)
        h = float(rng.uniform(*self.goal_height_range))
        x, y = scene.config.cylinder_xy
        self.goal = np.array([x, y, scene.cylinder_rest_z + h])

    @staticmethod
    def achieved_goal(reading: Reading) -> np.ndarray:
        """The cylinder centre, as the observation gives it: grip point plus the cylinder's offset
        from it (float64)."""
        return reading.cyl_rel + reading.grip

    def compute_reward(self, achieved_goal, desired_goal, info) -> np.ndarray | float:
        d = np.linalg.norm(np.asarray(achieved_goal, dtype=np.float64) - np.asarray(desired_goal, dtype=np.float64),
                           axis=-1)  # fmt: skip
        r = -(d > self.distance_threshold).astype(np.float32)
        return float(r) if np.ndim(r) == 0 else r

    def evaluate(self, reading: Reading, scene: GraspScene) -> Outcome:
        out = self.task.evaluate(reading, scene)
        # the goals as the agent sees them (float32), so that a relabelled reward equals this one
        reward = float(self.compute_reward(self.achieved_goal(reading).astype(np.float32), self.goal.astype(np.float32),
                                           None))  # fmt: skip
        if self.end_when_knocked_over:
            return replace(out, reward=reward, success=reward == 0.0)
        z = reading.cylinder_x[2]
        lost = bool(z < LOWEST or z > HIGHEST)  # a physics failure, not something to learn (module docstring)
        return replace(out, reward=reward, success=reward == 0.0, terminated=lost)


__all__ = ["DISTANCE_THRESHOLD", "GOAL_HEIGHT_RANGE", "GoalTask"]
