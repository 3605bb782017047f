"""Scripted policies for the grip-force task (SoftGraspGrip-v6, v5 and their rigid twins).

All read only what the gripper senses (the grip ids observe neither the cylinder's pose nor its
motion): from the easy start around the cylinder's top they go down 3 cm with the fingers open,
squeeze, lift the grip 6.5 cm once both fingers press, hold it there, and set the squeeze
themselves (in the order of what they feel):

- :class:`ConstantGripPolicy`, the force-blind baseline: one squeeze throughout. It holds every
  cylinder whose least force lies below it, and succeeds only where that least force is within
  the task's factor of it: no constant suits an episode whose mass and friction are not observed.
- :class:`TactileGripPolicy` reads the pads' taxels (``tactile=(rows, cols)``, on by default on the
  grip ids): it lifts with ``start_force``, reads the cylinder's weight on the pads as their
  traction, then lowers the squeeze until the traction falls below that weight - the pads begin to
  slip - and holds with ``margin`` times the last squeeze that held (Johansson & Westling
  1984: humans grip with a safety margin over the slip force they sense). It knows nothing of the
  episode's mass or friction: the weight it reads, the slip it feels.
- :class:`ShearLagGripPolicy` reads the tissue pads' shear as well: it lowers the squeeze until
  the edges of the contact lag its centre (slip on its way, before it happens), reads mu off the
  sliding edges and holds with a margin over the least squeeze that gives.

All are stateful within an episode (``reset()`` between episodes; ``predict`` resets on SB3's
``episode_start``).
"""

from __future__ import annotations

import numpy as np

from ..fingers.tactile import edge_friction, shear_lag
from ..observation import tactile_view
from ..tasks.easy import EASY_START_HEIGHT
from ..tasks.lift import MIN_GRIP_FORCE
from ..validation import check_int, check_range
from .scripted import ScriptedGraspPolicy


def _env_plan(env):
    """The env's plan (softgrasp_env.arguments.EnvPlan; its ``args`` the arguments)."""
    plan = getattr(env.unwrapped, "plan", None)
    if plan is None:
        raise TypeError(f"needs a SoftGrasp env, got {env!r}")
    if plan.args.control.finger_action != "force":
        raise ValueError("a grip-force policy sets the squeeze: make the env with finger_action='force' (the "
                         f"SoftGraspGrip ids), got finger_action={plan.args.control.finger_action!r}")  # fmt: skip
    return plan


class _GripPolicy:
    """The arm and the squeeze from what the gripper itself senses (the grip ids observe neither the
    cylinder's pose nor its motion). The grip starts around the cylinder's top (the easy start, 5
    cm above its middle): go down ``descend`` [m] (to 2 cm above the middle) with the fingers open,
    squeeze, and once both fingers press lift ``lift_to`` [m] and hold there; the squeeze from
    :meth:`squeeze` [N]."""

    def __init__(self, env, *, descend: float = 0.03, lift_to: float = 0.065) -> None:
        plan = _env_plan(env)
        self.mover = ScriptedGraspPolicy.for_env(env)  # its speed profile (toward): stops where it is sent
        self.descend = float(descend)
        self.lift_to = float(lift_to)
        self.names = env.unwrapped.obs_names
        self.index = {n: k for k, n in enumerate(self.names)}
        self.finger_force = float(plan.args.control.finger_force)
        self.reset()

    def reset(self) -> None:
        """A new episode begins."""
        self.grasp_z: float | None = None
        self.down = False
        self.gripped = False

    def squeeze(self, obs: np.ndarray) -> float:
        raise NotImplementedError

    def lifted(self, obs: np.ndarray) -> bool:
        """The grip is at its lift height and still."""
        i = self.index
        return bool(self.gripped and obs[i["grip_z"]] >= self.grasp_z + self.lift_to - 0.002
                    and abs(obs[i["grip_vz"]]) < 0.005)  # fmt: skip

    def __call__(self, obs) -> np.ndarray:
        obs = np.asarray(obs, dtype=np.float64)
        i = self.index
        z, vz = float(obs[i["grip_z"]]), float(obs[i["grip_vz"]])
        if self.grasp_z is None:
            if "shape_extent_z" in i:
                # another object (the grip starts above the tallest of a set): as far above its
                # middle as the cylinder's grip, or at the arm's lowest grip for a low one
                above = EASY_START_HEIGHT - self.descend
                self.grasp_z = max(float(obs[i["shape_extent_z"]]) + above, self.mover.min_grip_height or -np.inf)
            else:
                self.grasp_z = z - self.descend
        self.down = self.down or (abs(z - self.grasp_z) < 0.002 and abs(vz) < 0.005)
        self.gripped = self.gripped or (self.down and min(obs[i["force_left"]], obs[i["force_right"]]) >= MIN_GRIP_FORCE)
        action = np.zeros(4, dtype=np.float32)
        target = self.grasp_z + (self.lift_to if self.gripped else 0.0)
        action[:3] = self.mover.toward(np.array([0.0, 0.0, target - z]))
        force = min(max(self.squeeze(obs), 0.0), self.finger_force) if self.down else 0.0  # open on the way down
        action[3] = 2.0 * force / self.finger_force - 1.0
        return action

    def predict(self, observation, state=None, episode_start=None, deterministic: bool = True):
        """SB3's policy interface for one env (a leading batch axis of 1 is accepted): resets when
        ``episode_start`` says an episode begins."""
        obs = np.asarray(observation)
        batched = obs.ndim == 2
        if batched and obs.shape[0] != 1:
            raise ValueError(f"{type(self).__name__} keeps one episode's state: one env at a time, got a batch of "
                             f"{obs.shape[0]}")  # fmt: skip
        if episode_start is not None and bool(np.asarray(episode_start).ravel()[0]):
            self.reset()
        action = self(obs[0] if batched else obs)
        return (action[None] if batched else action), state


class ConstantGripPolicy(_GripPolicy):
    """The force-blind baseline: squeeze with ``force`` [N] throughout (module docstring)."""

    def __init__(self, env, force: float, **kwargs) -> None:
        self.force = check_range("force", force, 0.0, float(_env_plan(env).args.control.finger_force), owner="ConstantGripPolicy")
        super().__init__(env, **kwargs)

    def squeeze(self, obs: np.ndarray) -> float:
        return self.force


class TactileGripPolicy(_GripPolicy):
    """Lower the squeeze until the pads feel the cylinder slip, then hold with a margin (module
    docstring). ``start_force`` [N] lifts any cylinder of the task; once the grip is up and still
    for ``settle`` env steps, the pads' traction is the cylinder's weight W. The squeeze falls by
    ``fast`` per step to W / ``mu_min`` (no cylinder with friction at least ``mu_min`` slips above
    it), then by ``step`` every ``1 + wait`` steps (a squeeze counts as holding once it has held
    that long); the first step at which the traction falls below W by more than ``tolerance``
    (relative) is the slip - sliding, friction carries less than the weight - and the squeeze
    becomes ``margin`` times the last one that held. A rise of the traction is not slip: the pads
    relaxing as the squeeze falls push the cylinder up for a step. At ``deadline`` [s] (default:
    just before the carry) the search stops where it is."""

    def __init__(self, env, *, start_force: float = 4.0, fast: float = 0.8, step: float = 0.85, wait: int = 1,
                 settle: int = 2, tolerance: float = 0.05, mu_min: float = 0.45, margin: float = 1.5,
                 deadline: float | None = None, **kwargs) -> None:  # fmt: skip
        plan = _env_plan(env)
        if plan.taxel_grid is None:
            raise ValueError("TactileGripPolicy reads the pads' taxels: make the env with tactile=(rows, cols)")
        self.area = plan.taxel_grid.area
        self.start_force = check_range("start_force", start_force, 0.0, plan.args.control.finger_force, lo_open=True,
                                       owner="TactileGripPolicy")  # fmt: skip
        self.fast = check_range("fast", fast, 0.0, 1.0, lo_open=True, hi_open=True, owner="TactileGripPolicy")
        self.step = check_range("step", step, 0.0, 1.0, lo_open=True, hi_open=True, owner="TactileGripPolicy")
        self.wait = check_int("wait", wait, 0, 100, owner="TactileGripPolicy")
        self.settle = check_int("settle", settle, 1, 100, owner="TactileGripPolicy")
        self.tolerance = check_range("tolerance", tolerance, 0.0, 1.0, lo_open=True, owner="TactileGripPolicy")
        self.mu_min = check_range("mu_min", mu_min, 0.0, 10.0, lo_open=True, owner="TactileGripPolicy")
        self.margin = check_range("margin", margin, 1.0, 10.0, owner="TactileGripPolicy")
        self.deadline = float(deadline) if deadline is not None else float(plan.args.carry_test.start_time) - 0.05
        super().__init__(env, **kwargs)

    def reset(self) -> None:
        super().reset()
        self.force = self.start_force
        self.phase = "lift"
        self.still = 0
        self.weight = np.nan
        self.floor = np.nan
        self.held = self.start_force
        self.judged = 0

    def traction(self, obs: np.ndarray) -> float:
        """The pads' mean upward traction [N]: the weight they carry while the cylinder sticks."""
        taxels = tactile_view(obs, self.names)
        return float(-taxels[..., 2].sum(axis=(1, 2)).mean() * self.area)

    def _lift(self, obs: np.ndarray) -> bool:
        """The lift phase's step: True once the grip has been up and still for ``settle`` env
        steps - the weight W read then as the pads' traction, the search's floor W / mu_min - and
        the lowering begins."""
        self.still = self.still + 1 if self.lifted(obs) else 0
        if self.still < self.settle:
            return False
        self.phase, self.weight = "lower", self.traction(obs)
        self.floor = self.weight / self.mu_min
        return True

    def squeeze(self, obs: np.ndarray) -> float:
        i = self.index
        if self.phase == "lift":
            self._lift(obs)
        elif self.phase == "lower":
            if obs[i["time"]] >= self.deadline:
                self.phase = "hold"
            elif self.force > self.floor:  # above W / mu_min nothing of the task slips
                self.force = max(self.force * self.fast, self.floor * (1.0 - 1e-9))
                self.judged, self.held = 0, self.force  # the floor holds whatever the friction
            else:
                self.judged += 1
                if self.judged <= self.settle:  # the pads settle at the floor: the weight read there
                    self.weight = self.traction(obs)
                elif self.traction(obs) < (1.0 - self.tolerance) * self.weight:  # slipping: friction < weight
                    self.phase, self.force = "hold", min(self.margin * self.held, self.finger_force)
                elif self.judged % (1 + self.wait) == 0:  # this squeeze held through its steps: lower it
                    self.held = self.force
                    self.force *= self.step
        return self.force


class ShearLagGripPolicy(TactileGripPolicy):
    """Lower the squeeze until the pads feel slip coming, then hold with a margin over the least
    squeeze the pads read (module docstring). It is told neither the cylinder's mass nor its
    friction.

    It lifts with ``start_force`` [N], reads the weight each pad carries, W, as their traction and
    the shear lag of each pad (:func:`softgrasp_env.fingers.tactile.shear_lag`) once the lift is
    still for ``settle`` env steps, then lowers the squeeze by ``fast`` per env step to W /
    ``mu_min`` (no cylinder with friction at least ``mu_min`` slips above it) and by ``step`` below
    it, judging ``wait`` env steps after each drop (after a drop the pads relax for a step and their
    edge taxels overshoot the cone). The warning: either pad's lag has risen by ``rise`` of the way
    from its level at the lift to 1 - the edges of the contact have begun to slide, its centre
    still sticks (Cattaneo and Mindlin; Johnson, Contact Mechanics, sec. 7.2). The lag's level
    carries the grasp's geometry (a contact strip off the pad's centre) and the partial slip the
    lift locked in (a slip annulus does not stick back when the load falls: Mindlin and
    Deresiewicz), so the policy reads its rise, not its level; a pad that lifted with a lag near 1
    has no room to rise and does not warn. At the warning the sliding edges sit at the cone, so
    their traction-to-pressure ratio reads mu
    (:func:`softgrasp_env.fingers.tactile.edge_friction`, the larger of the pads'), and the squeeze
    becomes ``margin`` x W / mu read (Coulomb's least for the weight the pad carries), at most
    ``margin`` times the squeeze at the warning. If the traction falls ``tolerance`` (relative)
    below W (read again once the pads have settled at W / ``mu_min``) first - gross slip, the
    warning missed - it holds ``slip_margin`` times the last squeeze that held, as
    :class:`TactileGripPolicy` does; in the ``wait`` steps right after a drop, where the pads'
    relaxing dips the traction by a few per cent, a fall of more than ``drop_tolerance`` is that
    slip too (caught a step before the next judging one: a heavy, slippery cylinder left to slide
    that step went a centimetre down the pads and out of the task's lift). At ``deadline`` [s]
    (default: just before the carry) the search stops where it is. After the episode:
    ``fired_lag`` (the rise that warned, NaN if none) and ``mu_read``.

    On rigid pads, which do not shear, it never warns and falls back to the gross-slip rule."""

    def __init__(self, env, *, start_force: float = 4.0, fast: float = 0.8, step: float = 0.85, wait: int = 1,
                 settle: int = 2, rise: float = 0.4, margin: float = 1.3, slip_margin: float = 1.5,
                 tolerance: float = 0.05, drop_tolerance: float = 0.1, mu_min: float = 0.45, deadline: float | None = None,
                 **kwargs) -> None:  # fmt: skip
        owner = "ShearLagGripPolicy"
        self.drop_tolerance = check_range("drop_tolerance", drop_tolerance, 0.0, 1.0, lo_open=True, owner=owner)
        self.rise = check_range("rise", rise, 0.0, 1.0, lo_open=True, owner=owner)
        self.slip_margin = check_range("slip_margin", slip_margin, 1.0, 10.0, owner=owner)
        check_int("wait", wait, 1, 100, owner=owner)  # at least one step for the pads to settle after a drop
        super().__init__(env, start_force=start_force, fast=fast, step=step, wait=wait, settle=settle,
                         tolerance=tolerance, mu_min=mu_min, margin=margin, deadline=deadline, **kwargs)  # fmt: skip

    def reset(self) -> None:
        super().reset()
        self.lifted_lag = np.zeros(2)
        self.since_drop = 0
        self.fired_lag = np.nan
        self.mu_read = np.nan

    def _slipped(self) -> float:
        """Gross slip: hold ``slip_margin`` times the last squeeze that held."""
        self.phase, self.force = "hold", min(self.slip_margin * self.held, self.finger_force)
        return self.force

    def squeeze(self, obs: np.ndarray) -> float:
        i = self.index
        if self.phase == "lift":
            if self._lift(obs):
                self.lifted_lag = shear_lag(tactile_view(obs, self.names))
        elif self.phase == "lower":
            self.since_drop += 1
            if obs[i["time"]] >= self.deadline:
                self.phase = "hold"
            elif self.force > self.floor:  # above W / mu_min nothing of the task slips: no need to judge
                self.force = max(self.force * self.fast, self.floor * (1.0 - 1e-9))
                self.held, self.since_drop = self.force, 0
            elif self.since_drop <= self.wait and self.traction(obs) < (1.0 - self.drop_tolerance) * self.weight:
                # gross slip in the steps right after a drop, caught there rather than at the next
                # judging step (a slide left for one more step took a heavy cylinder a centimetre
                # down the pads), at a tolerance above the traction's dip as the pads relax
                self._slipped()
            elif self.since_drop > self.wait:  # the pads have settled since the last drop: judge
                taxels = tactile_view(obs, self.names)
                # the lag's rise as a share of the way from its level at the lift to 1 (a pad that
                # lifted near 1 has little left to rise and never warns)
                rise = (shear_lag(taxels) - self.lifted_lag) / np.maximum(1.0 - self.lifted_lag, 1e-9)
                if not self.judged:  # the first settled step at the floor: the weight read there (the
                    # fast drops leave the pads' traction a few % off the lift's for a step or two),
                    # unless it has fallen further: then the cylinder slides already, and what the
                    # pads carry is not its weight
                    self.judged = 1
                    reading = self.traction(obs)
                    if reading < (1.0 - self.drop_tolerance) * self.weight:
                        return self._slipped()
                    self.weight = reading
                if self.traction(obs) < (1.0 - self.tolerance) * self.weight:  # gross slip came first
                    self._slipped()
                elif (rise >= self.rise).any():  # the edges slide: slip is coming
                    # the sliding edges sit at the cone: they read mu, and the least squeeze that
                    # holds the weight a pad carries, W_pad, is W_pad / mu (Coulomb)
                    self.mu_read = float(edge_friction(taxels).max())
                    least = self.weight / self.mu_read if self.mu_read > 0.0 else np.inf
                    self.phase, self.fired_lag = "hold", float(rise.max())
                    self.force = min(self.margin * least, self.margin * self.force, self.finger_force)
                else:  # this squeeze held: lower it
                    self.held = self.force
                    self.force *= self.step
                    self.since_drop = 0
        return self.force


def grip_script(env) -> TactileGripPolicy:
    """The tactile grip script that does best on ``env``'s fingers (a grip-force env, wrapped or
    not): :class:`ShearLagGripPolicy` on tissue pads, which shear and so warn of slip before it
    happens; :class:`TactileGripPolicy` on rigid pads, which do not shear (there the shear-lag
    script falls back to reading gross slip with a larger margin and does worse). Measured on the
    cards' 100 episodes (seeds 1000-1099, an Intel Xeon): SoftGraspGrip-v7 92 with the shear-lag
    script against 73 with the slip script; the rigid kinds' v5 89 with the slip script against
    54-58."""
    tissue = _env_plan(env).args.physics.fingers.kind == "tissue"
    return ShearLagGripPolicy(env) if tissue else TactileGripPolicy(env)


__all__ = ["ConstantGripPolicy", "ShearLagGripPolicy", "TactileGripPolicy", "grip_script"]
