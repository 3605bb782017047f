"""The v3 task's ranges against the stability map: scripted success of the soft
fingers, the rigid twin and the torsional peer with today's ranges and with others, and whether an
open-loop action sequence solves them.

    PYTHONPATH=. python benchmarks/v3_ranges.py [--seeds 1000-1029] [--sets today,wide,...] [--no-open-loop]

Each range set is a dict of gym.make keywords (EnvArguments' range fields, RANGE_SETS below); the
defaults in the code are not changed. For every set and every id (SoftGrasp-v3,
SoftGraspRigid-v3, SoftGraspRigidTorsion-v3) the scripted policy
(``ScriptedGraspPolicy.for_env(env)``) runs one episode per seed, and each episode is counted as
success, or failed because the cylinder was never lifted, lost (held once, not held through the
carry) or slid (held through the carry but more than the slide limit in the hand). The open-loop
check records the scripted policy's actions on the soft env for each of ``--record-seeds`` and
replays each sequence, unchanged, on every seed and id: a task an open-loop sequence solves in
many episodes measures no grasp. One process, one thread (pybullet and the tissue's numba kernels
run single-threaded). Writes benchmarks/out/v3_ranges.csv.
"""

from __future__ import annotations

import argparse
import csv
import math
import time
from pathlib import Path

import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.registration import make_as as make

OUT = Path(__file__).resolve().parent / "out"
IDS = ("SoftGrasp-v3", "SoftGraspRigid-v3", "SoftGraspRigidTorsion-v3")
RANGE_SETS: dict[str, dict] = {
    "today": {},
    # the stability map's region (benchmarks/stability_map.py --maps v3): the widest wedge and yaw
    # the scene takes, and the cylinder's friction, size and mass where the soft fingers still lift it
    "wide": dict(yaw_range=math.pi / 4, jaw_wedge_range=math.pi / 6, friction_range=0.25,
                 cylinder_radius_range=0.01, cylinder_mass_range=0.5),
    "wedge": dict(jaw_wedge_range=math.pi / 6),
    "small": dict(cylinder_radius=0.0125, cylinder_radius_range=0.0075, jaw_wedge_range=math.pi / 6),
    "weak": dict(finger_force=1.0, jaw_wedge_range=math.pi / 6),
    # where the map has the soft fingers lose: heavier cylinders near Coulomb's bound
    "heavy": dict(cylinder_mass=0.3, cylinder_mass_range=0.33, friction_range=0.25, jaw_wedge_range=math.pi / 6),
}
"""Candidate ranges (gym.make keywords on top of each id's); ``today`` is the code's defaults."""


def parse_seeds(spec: str) -> list[int]:
    lo, _, hi = spec.partition("-")
    return list(range(int(lo), int(hi or lo) + 1))


def run(env, seed: int, policy=None, actions=None) -> tuple[str, list]:
    """One episode, closed loop (``policy``) or open loop (``actions``, repeated past its end with
    its last action): its verdict and the actions taken."""
    obs, _ = env.reset(seed=seed)
    taken, ever, k = [], False, 0
    while True:
        a = policy(obs) if policy is not None else actions[min(k, len(actions) - 1)]
        taken.append(np.asarray(a, dtype=np.float32).copy())
        obs, _, term, trunc, info = env.step(a)
        ever |= bool(info["held"])
        k += 1
        if term or trunc:
            break
    if info["is_success"]:
        return "success", taken
    if not ever:
        return "never lifted", taken
    task = env.unwrapped.task
    limit = getattr(task, "slide_limit", None)
    if limit is not None and task.slide > limit:
        return "slid", taken
    return "lost", taken


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", default="1000-1029")
    parser.add_argument("--sets", default="today,wide", help=f"comma-separated, of {', '.join(RANGE_SETS)}")
    parser.add_argument("--ids", default=",".join(IDS))
    parser.add_argument("--record-seeds", default="1000-1002", help="seeds whose scripted actions are replayed")
    parser.add_argument("--no-open-loop", action="store_true")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    seeds, record = parse_seeds(args.seeds), parse_seeds(args.record_seeds)
    ids = args.ids.split(",")
    rows = []
    t_start = time.perf_counter()
    for set_name in args.sets.split(","):
        kwargs = RANGE_SETS[set_name]
        print(f"\n== {set_name}: {kwargs or 'the defaults'}")
        for env_id in ids:
            t0 = time.perf_counter()
            env = make(env_id, **kwargs)
            policy = ScriptedGraspPolicy.for_env(env)
            verdicts = [run(env, s, policy=policy)[0] for s in seeds]
            n = sum(v == "success" for v in verdicts)
            why = {k: verdicts.count(k) for k in ("never lifted", "lost", "slid") if k in verdicts}
            print(f"{env_id:>26}: scripted success {n:>2} / {len(seeds)}  {why}  "
                  f"({time.perf_counter() - t0:.0f} s)", flush=True)  # fmt: skip
            rows.append((set_name, env_id, "scripted", "", n, len(seeds), repr(why)))
            env.close()
        if args.no_open_loop:
            continue
        src = make(ids[0], **kwargs)
        src_policy = ScriptedGraspPolicy.for_env(src)
        for rs in record:
            verdict, actions = run(src, rs, policy=src_policy)
            for env_id in ids:
                env = make(env_id, **kwargs)
                verdicts = [run(env, s, actions=actions)[0] for s in seeds]
                n = sum(v == "success" for v in verdicts)
                why = {k: verdicts.count(k) for k in ("never lifted", "lost", "slid") if k in verdicts}
                print(f"{env_id:>26}: open loop (scripted on {ids[0]} seed {rs}, {verdict} there) {n:>2} / "
                      f"{len(seeds)}  {why}", flush=True)  # fmt: skip
                rows.append((set_name, env_id, "open loop", rs, n, len(seeds), repr(why)))
                env.close()
        src.close()
    args.out.mkdir(parents=True, exist_ok=True)
    with open(args.out / "v3_ranges.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["set", "env_id", "policy", "recorded_seed", "success", "episodes", "failures"])
        w.writerows(rows)
    print(f"\n{time.perf_counter() - t_start:.0f} s; wrote {args.out / 'v3_ranges.csv'}")


if __name__ == "__main__":
    main()
