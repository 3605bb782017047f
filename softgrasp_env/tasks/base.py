"""The task interface: what a task does around the scene an env steps.

A task draws each episode's start from the env's generator and the reset options (``draw``),
may take over the arm while the episode runs (``steer``, once per physics step: the carry test),
and judges every env step from the env's :class:`~softgrasp_env.observation.Reading`
(``evaluate`` -> :class:`Outcome`: held, success, terminated, the reward and its terms by name).
Tasks compose: the carry test wraps the reach task, the goal variant wraps a task too.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

if TYPE_CHECKING:
    from ..observation import Reading
    from ..scene import GraspScene, GripperControl, SceneConfig


@dataclass(frozen=True)
class Outcome:
    """A task's verdict on one env step."""

    held: bool
    """The cylinder is held: lifted to the success height, both fingers pressing, upright."""
    success: bool
    """The task is done (``info["is_success"]``)."""
    terminated: bool
    """The episode ends here (the cylinder knocked over or gone)."""
    reward: float
    terms: Mapping[str, float] = field(default_factory=dict)
    """The reward's named terms (``info["reward_terms"]``)."""
    carrying: bool = False
    """The arm, not the policy, moves the palm (``info["carrying"]``)."""
    info: Mapping[str, float] = field(default_factory=dict)
    """Measurements the task adds to ``info`` by name (the task's ``info_keys``)."""


class Task:
    """Base of every task; the lift tasks (softgrasp_env/tasks/lift.py) implement it for the
    cylinder, wrappers (carry, goal) change part of it and hand the rest to the task they wrap."""

    name: ClassVar[str] = ""
    observation_extras: tuple[str, ...] = ()
    """Observation groups the task adds after the scene's (softgrasp_env/observation.py)."""
    reward_terms: tuple[str, ...] = ()
    """Names of the reward's terms, in the order ``info["reward_terms"]`` lists them."""
    diverged_reward: float = 0.0
    """The reward of a step on which the simulation diverged."""
    reset_options: tuple[str, ...] = ()
    """Keys ``reset(options=...)`` accepts (each fixes a quantity the draw would randomise)."""
    info_keys: tuple[str, ...] = ()
    """The entries every :class:`Outcome`'s ``info`` has (0 on a diverged step)."""

    def start_height(self, cylinder_height: float, finger_half_height: float, pad: float) -> float:
        """Height of the grip point above the cylinder's mid height at the start [m], for a cylinder
        ``cylinder_height`` tall, finger cores ``finger_half_height`` high (half) and pads ``pad``
        thick; decided once, for the env's base scene."""
        raise NotImplementedError

    def tallest_cylinder(self, top: float, finger_half_height: float, pad: float) -> float:
        """The tallest cylinder whose start puts the grip point at most ``top`` high [m]."""
        raise NotImplementedError

    def draw(self, rng: np.random.Generator, options: Mapping[str, Any], base: SceneConfig) -> SceneConfig:
        """The episode's scene: ``base`` with the randomised quantities drawn from ``rng`` (always
        the same draws in the same order) and those in ``options`` fixed."""
        raise NotImplementedError

    def begin(self, scene: GraspScene, rng: np.random.Generator) -> None:
        """A new episode starts in ``scene`` (built from the last ``draw``)."""

    def steer(self, scene: GraspScene, control: GripperControl) -> GripperControl:
        """The control for the coming physics step, given the policy's: the same, unless the task
        moves the arm itself."""
        return control

    def carrying(self, steps: int) -> bool:
        """True while the task moves the arm, ``steps`` physics steps into the episode."""
        return False

    def evaluate(self, reading: Reading, scene: GraspScene) -> Outcome:
        raise NotImplementedError


class TaskWrapper(Task):
    """A task around another (the carry test, the goal variant): whatever it does not override
    goes to the task it wraps, as a Gymnasium wrapper passes an env's calls on."""

    def __init__(self, task: Task) -> None:
        self.task = task
        self.name = task.name
        self.observation_extras = task.observation_extras
        self.reward_terms = task.reward_terms
        self.diverged_reward = task.diverged_reward
        self.reset_options = task.reset_options
        self.info_keys = task.info_keys

    def start_height(self, cylinder_height: float, finger_half_height: float, pad: float) -> float:
        return self.task.start_height(cylinder_height, finger_half_height, pad)

    def tallest_cylinder(self, top: float, finger_half_height: float, pad: float) -> float:
        return self.task.tallest_cylinder(top, finger_half_height, pad)

    def draw(self, rng: np.random.Generator, options: Mapping[str, Any], base: SceneConfig) -> SceneConfig:
        return self.task.draw(rng, options, base)

    def begin(self, scene: GraspScene, rng: np.random.Generator) -> None:
        self.task.begin(scene, rng)

    def steer(self, scene: GraspScene, control: GripperControl) -> GripperControl:
        return self.task.steer(scene, control)

    def carrying(self, steps: int) -> bool:
        return self.task.carrying(steps)

    def find(self, kind: type[Task]) -> Task | None:
        """The first task of type ``kind`` in this chain of wrappers, this one included (None)."""
        task: Task = self
        while not isinstance(task, kind):
            if not isinstance(task, TaskWrapper):
                return None
            task = task.task
        return task

    def evaluate(self, reading: Reading, scene: GraspScene) -> Outcome:
        return self.task.evaluate(reading, scene)


__all__ = ["Outcome", "Task", "TaskWrapper"]
