"""What hindsight experience replay had to learn from on the goal id (the target: HER to a
success above 50 % "or the evidence why not").

HER (Andrychowicz et al. 2017) relabels a stored transition with a goal the episode reached later
(strategy "future"): it learns to put the cylinder wherever its own exploration once put it. On
``SoftGraspGoal-v3`` every desired goal is 5-8 cm above the cylinder's resting centre (2 cm
tolerance), so a relabelled goal teaches the task only if exploration lifted the cylinder at least
3 cm. This reads a HER run's replay buffer (``replay_buffer.pkl`` or a checkpoint's) and prints,
per block of stored episodes in the order they were collected: how many episodes raised the
cylinder by 1 cm and by 3 cm at any step, the share of stored steps 3 cm up (what "future"
relabelling can draw goals from), and how many episodes reached their own goal. The lift is the
achieved goal's height over its first value in the episode (the cylinder starts at rest).

    PYTHONPATH=. python benchmarks/her_exploration.py /work/runs22/SoftGraspGoal-v3_her-sac_0
    PYTHONPATH=. python benchmarks/her_exploration.py RUN/checkpoints/model_replay_buffer_75000_steps.pkl
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from softgrasp_env.tasks.goal import DISTANCE_THRESHOLD, GOAL_HEIGHT_RANGE

RELABEL_USEFUL = GOAL_HEIGHT_RANGE[0] - DISTANCE_THRESHOLD
"""Lift [m] from which an achieved position lies within tolerance of some desired goal (3 cm)."""


def episodes(buffer) -> list[tuple[np.ndarray, np.ndarray]]:
    """(achieved goals, desired goals) of every complete stored episode, in the order they were
    collected (the buffer is a ring: after it wrapped, the oldest start at ``pos``)."""
    n = buffer.buffer_size if buffer.full else buffer.pos
    if buffer.n_envs != 1:
        raise ValueError(f"this reads single-env buffers; the buffer has {buffer.n_envs} envs")
    order = np.r_[buffer.pos : n, 0 : buffer.pos] if buffer.full else np.arange(n)
    ach = buffer.observations["achieved_goal"][:, 0]
    des = buffer.observations["desired_goal"][:, 0]
    start, length = buffer.ep_start[:, 0], buffer.ep_length[:, 0]
    out, seen = [], set()
    for i in order:
        s, k = int(start[i]), int(length[i])
        if k == 0 or s in seen:  # length 0: the episode still running when the buffer was saved
            continue
        seen.add(s)
        idx = (s + np.arange(k)) % buffer.buffer_size
        out.append((ach[idx].astype(np.float64), des[idx].astype(np.float64)))
    return out


def summary(eps: list[tuple[np.ndarray, np.ndarray]]) -> dict[str, float]:
    """Counts over ``eps`` (see the module docstring)."""
    lift = [a[:, 2] - a[0, 2] for a, _ in eps]
    top = np.array([x.max() for x in lift])
    steps_up = np.concatenate(lift) >= RELABEL_USEFUL
    reached = [np.any(np.linalg.norm(a - d, axis=1) <= DISTANCE_THRESHOLD) for a, d in eps]
    return {"episodes": len(eps), "lift_1cm": int(np.sum(top >= 0.01)), "lift_3cm": int(np.sum(top >= RELABEL_USEFUL)),
            "steps_3cm": float(steps_up.mean()), "reached": int(np.sum(reached)),
            "top_cm": float(100 * top.max())}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("path", type=Path, help="a HER run directory or a replay buffer .pkl")
    parser.add_argument("--blocks", type=int, default=6, help="blocks of stored episodes, oldest first")
    ns = parser.parse_args(argv)
    from stable_baselines3.common.save_util import load_from_pkl

    path = ns.path / "replay_buffer.pkl" if ns.path.is_dir() else ns.path
    if not path.is_file():
        parser.error(f"no replay buffer at {str(path)!r} (train.py saves replay_buffer.pkl at the end of a run)")
    buffer = load_from_pkl(path)
    if not isinstance(getattr(buffer, "observations", None), dict) or "achieved_goal" not in buffer.observations:
        parser.error(f"{str(path)!r} is not a goal-conditioned (HER) replay buffer")
    eps = episodes(buffer)
    print(f"{path}: {len(eps)} complete episodes stored; a relabelled goal is useful from {100 * RELABEL_USEFUL:.0f} cm "
          f"of lift (goals {100 * GOAL_HEIGHT_RANGE[0]:.0f}-{100 * GOAL_HEIGHT_RANGE[1]:.0f} cm, "
          f"tolerance {100 * DISTANCE_THRESHOLD:.0f} cm)")  # fmt: skip
    print(f"{'block':>12}  {'episodes':>8}  {'lift>=1cm':>9}  {'lift>=3cm':>9}  {'steps>=3cm':>10}  {'reached goal':>12}  "
          f"{'top lift':>8}")  # fmt: skip
    for chunk in np.array_split(np.arange(len(eps)), ns.blocks):
        if len(chunk) == 0:
            continue
        s = summary([eps[i] for i in chunk])
        print(f"{f'{chunk[0]}-{chunk[-1]}':>12}  {s['episodes']:8d}  {s['lift_1cm']:9d}  {s['lift_3cm']:9d}  "
              f"{100 * s['steps_3cm']:9.2f}%  {s['reached']:12d}  {s['top_cm']:6.1f}cm")  # fmt: skip
    s = summary(eps)
    print(f"{'all':>12}  {s['episodes']:8d}  {s['lift_1cm']:9d}  {s['lift_3cm']:9d}  {100 * s['steps_3cm']:9.2f}%  "
          f"{s['reached']:12d}  {s['top_cm']:6.1f}cm")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
