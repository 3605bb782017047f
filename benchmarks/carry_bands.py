"""The v3 carry test per band: soft vs rigid vs rigid with torsional friction.

The scripted grasp on the reach task (SoftGrasp-v3, SoftGraspRigid-v3, SoftGraspRigidTorsion-v3),
the sway fixed per episode by reset options on a grid: frequency from below to above the
two-point grasp's pendulum frequency (~1.9 Hz with the cylinder's own inertia), peak
acceleration, and direction (across the jaw, where a two-point grasp swings about the line
through its contacts; along the closing axis; between). Each cell runs the same seeds for every
kind; an episode counts for the carry only if the cylinder was held when the carry began, so the
table separates "lost in the carry" from "never got a grip".

    PYTHONPATH=. python benchmarks/carry_bands.py                  # 10 seeds per cell
    PYTHONPATH=. python benchmarks/carry_bands.py --seeds 3 --kinds tissue,rigid
    PYTHONPATH=. python benchmarks/carry_bands.py --policy rigid=runs/SoftGraspRigid-v3_sac_0   # a learned policy

``--policy KIND=SPEC`` replaces the scripted grasp of one kind by any policy ``agents.evaluate``
loads (a train.py run or shipped baseline, an RLlib trial, ``random``): the learned soft /
rigid / torsional gap per band. A run is evaluated on its kind's id here (the band is set by the
reset options), so it must have been trained on that id.

Prints, per kind and cell: held when the carry began / episodes, held through it (v3 success) /
those, the median in-hand slide and the largest tilt [deg] over the held-at-start episodes.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.registration import make_as as make

IDS = {"tissue_v4": "SoftGrasp-v4", "tissue": "SoftGrasp-v3", "rigid": "SoftGraspRigid-v3",
       "rigid_torsion": "SoftGraspRigidTorsion-v3"}  # fmt: skip
FREQUENCIES = (1.2, 1.6, 1.9, 2.3, 3.0)
ACCELERATIONS = (0.5, 1.0)
DIRECTIONS = {"across": 0.0, "diagonal": math.pi / 4, "along": math.pi / 2}


def episode(env, policy, seed: int, options: dict) -> tuple[bool, bool, float, float]:
    """(held when the carry began, success, in-hand slide [m], largest tilt during the carry [deg])."""
    obs, _ = env.reset(seed=seed, options=options)
    held_at_start, tilt, done = None, 0.0, False
    while not done:
        obs, _, term, trunc, info = env.step(policy(obs))
        done = term or trunc
        if info["carrying"]:
            if held_at_start is None:
                held_at_start = bool(info["held"])
            tilt = max(tilt, math.degrees(env.unwrapped.scene.cylinder_tilt()))
    return bool(held_at_start), bool(info["is_success"]), env.unwrapped.task.slide, tilt


def add_kind_arguments(parser: argparse.ArgumentParser) -> None:
    """``--kinds`` (which of IDS, comma-separated) and ``--policy KIND=SPEC`` (repeatable)."""
    parser.add_argument("--kinds", default=",".join(IDS))
    parser.add_argument("--policy", action="append", default=[], metavar="KIND=SPEC",
                        help="the policy of one kind (default: the scripted grasp): a train.py run, a shipped "
                             "baseline's name, an RLlib trial, or 'random'")  # fmt: skip


def kinds_and_policies(parser: argparse.ArgumentParser, ns: argparse.Namespace) -> tuple[list[str], dict[str, str]]:
    """The kinds asked for and the policy spec of each kind given one; a parser error naming a
    kind that is not one of IDS or a --policy for a kind not asked for."""
    kinds = ns.kinds.split(",")
    for kind in kinds:
        if kind not in IDS:
            parser.error(f"--kinds: {kind!r} is not one of {sorted(IDS)}")
    specs: dict[str, str] = {}
    for item in ns.policy:
        kind, sep, spec = item.partition("=")
        if not sep or kind not in IDS or not spec:
            parser.error(f"--policy takes KIND=SPEC with KIND one of {sorted(IDS)}, got {item!r}")
        if kind not in kinds:
            parser.error(f"--policy {item!r}: {kind!r} is not among --kinds {ns.kinds!r}")
        specs[kind] = spec
    return kinds, specs


def make_policy(spec: str | None, env):
    """The scripted grasp for ``env`` (spec None), else what ``agents.evaluate`` loads for ``spec``."""
    if spec is None:
        return ScriptedGraspPolicy.for_env(env)
    from agents.evaluate import load_policy

    return load_policy(spec, env)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=10, help="episodes per cell (seeds 1000, 1001, ...)")
    add_kind_arguments(parser)
    ns = parser.parse_args(argv)
    kinds, specs = kinds_and_policies(parser, ns)
    seeds = range(1000, 1000 + ns.seeds)
    named = ", ".join(f"{k}: {v}" for k, v in specs.items()) or "none"
    print(f"reach task, seeds {seeds.start}-{seeds.stop - 1}; 1 process; the scripted grasp but for ({named})")
    print(f"{'kind':<15}{'f Hz':>6}{'a m/s2':>8}{'direction':>10}{'held@start':>12}{'held through':>14}"
          f"{'slide mm':>10}{'tilt deg':>10}")  # fmt: skip
    totals: dict[str, list[int]] = {}
    for kind in kinds:
        env = make(IDS[kind])
        policy = make_policy(specs.get(kind), env)
        tic = time.perf_counter()
        tot = totals.setdefault(kind, [0, 0, 0])
        try:
            for f in FREQUENCIES:
                for a in ACCELERATIONS:
                    for name, angle in DIRECTIONS.items():
                        opts = {"carry_frequency": f, "carry_acceleration": a, "carry_direction": angle}
                        rows = [episode(env, policy, s, opts) for s in seeds]
                        started = [r for r in rows if r[0]]
                        through = sum(r[1] for r in started)
                        slide = np.median([r[2] for r in started]) * 1e3 if started else math.nan
                        tilt = max((r[3] for r in started), default=math.nan)
                        tot[0] += len(rows)
                        tot[1] += len(started)
                        tot[2] += through
                        print(f"{kind:<15}{f:>6.1f}{a:>8.1f}{name:>10}{len(started):>6}/{len(rows):<5}"
                              f"{through:>8}/{len(started):<5}{slide:>10.2f}{tilt:>10.1f}", flush=True)  # fmt: skip
        finally:
            env.close()
        print(f"{kind}: {time.perf_counter() - tic:.0f} s", flush=True)
    for kind, (n, started, through) in totals.items():
        print(f"{kind:<15} all cells: held when the carry began {started}/{n}, held through it {through}/{started}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
