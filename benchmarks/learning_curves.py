"""Learning curves of the shipped baselines: success rate against env steps, soft vs rigid fingers,
mean and spread (min-max) over seeds, one panel per algorithm and task version (a row each: v2
with the carry test, v1 without).

    python benchmarks/learning_curves.py                       # agents/trained/ -> docs/results/
    python benchmarks/learning_curves.py --models runs --out /tmp/curves

Two measures per run, both from the files train.py writes:
- lines: ``rollout/success_rate`` of SB3's log (``training.csv`` in a shipped model, ``logs/progress.csv``
  in a run): the share of the last 100 training episodes that ended in success, stochastic actions;
- markers: train.py's periodic evaluations (``progress.csv``): deterministic policy, separate seeds.
Each seed's curve is interpolated onto a common step grid before the mean and the band are taken.
Writes ``learning_curves.png`` and ``learning_curves.csv`` (the plotted means and bands).
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
FINGERS = {"SoftGrasp": "soft (tissue)", "SoftGraspRigid": "rigid", "SoftGraspGoal": "soft, goal (HER)"}
COLORS = {"SoftGrasp": "tab:blue", "SoftGraspRigid": "tab:red", "SoftGraspGoal": "tab:green"}
VERSIONS = {"v2": "v2 (carry test)", "v1": "v1 (no carry test)"}


def _split(env_id: str) -> tuple[str, str]:
    """``"SoftGraspRigid-v2"`` -> ``("SoftGraspRigid", "v2")``."""
    name, _, version = env_id.rpartition("-")
    return name, version


def _rows(path: Path) -> list[dict[str, str]]:
    if not path.exists():
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _series(rows: list[dict[str, str]], x: str, y: str) -> tuple[np.ndarray, np.ndarray]:
    pts = [(float(r[x]), float(r[y])) for r in rows if r.get(x) not in (None, "") and r.get(y) not in (None, "")]
    if not pts:
        return np.zeros(0), np.zeros(0)
    arr = np.array(sorted(pts))
    return arr[:, 0], arr[:, 1]


def load_runs(models: Path) -> dict[tuple[str, str], list[dict]]:
    """``(algo, env) -> [{"seed", "train": (steps, rate), "eval": (steps, rate)}]`` for every run
    (shipped model or train.py run directory) under ``models``."""
    groups: dict[tuple[str, str], list[dict]] = {}
    for meta_path in sorted(models.glob("*/run.json")):
        meta = json.loads(meta_path.read_text())
        d = meta_path.parent
        training = _rows(d / "training.csv") or _rows(d / "logs" / "progress.csv")
        groups.setdefault((meta["algo"], meta["env"]), []).append({
            "seed": meta["seed"],
            "train": _series(training, "time/total_timesteps", "rollout/success_rate"),
            "eval": _series(_rows(d / "progress.csv"), "timesteps", "success_rate"),
        })  # fmt: skip
    return groups


def band(curves: list[tuple[np.ndarray, np.ndarray]], points: int = 200):
    """Common grid up to the shortest run's last step; mean, min and max over the runs."""
    curves = [c for c in curves if len(c[0]) > 0]
    if not curves:
        return None
    end = min(c[0][-1] for c in curves)
    start = max(c[0][0] for c in curves)
    if end <= start:
        return None
    grid = np.linspace(start, end, points)
    ys = np.array([np.interp(grid, x, y) for x, y in curves])
    return grid, ys.mean(0), ys.min(0), ys.max(0)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--models", type=Path, default=ROOT / "agents" / "trained")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "results")
    ns = parser.parse_args(argv)
    groups = load_runs(ns.models)
    if not groups:
        parser.error(f"no runs (*/run.json) under {str(ns.models)!r}")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    algos = sorted({algo for algo, _ in groups}, key=["ppo", "sac", "her-sac"].index)
    versions = sorted({_split(env)[1] for _, env in groups}, reverse=True)
    fig, axes = plt.subplots(len(versions), len(algos), figsize=(5.2 * len(algos), 3.6 * len(versions)), squeeze=False)
    table = []
    for ax, (version, algo) in zip(axes.flat, [(v, a) for v in versions for a in algos]):
        if not any(a == algo and _split(env)[1] == version for a, env in groups):
            ax.set_visible(False)
            continue
        for (a, env), runs in sorted(groups.items()):
            name, v = _split(env)
            if a != algo or v != version:
                continue
            label = f"{FINGERS.get(name, name)} ({len(runs)} seed{'s' if len(runs) > 1 else ''})"
            b = band([r["train"] for r in runs])
            if b is not None:
                grid, mean, lo, hi = b
                ax.plot(grid, mean, color=COLORS.get(name), label=label)
                ax.fill_between(grid, lo, hi, color=COLORS.get(name), alpha=0.2, lw=0)
                table += [{"algo": algo, "env": env, "measure": "training episodes", "steps": f"{s:.0f}",
                           "mean": f"{m:.3f}", "min": f"{lo_:.3f}", "max": f"{hi_:.3f}"}
                          for s, m, lo_, hi_ in zip(grid[::20], mean[::20], lo[::20], hi[::20])]  # fmt: skip
            for r in runs:
                x, y = r["eval"]
                if len(x):
                    ax.plot(x, y, "o", ms=3.5, color=COLORS.get(name), alpha=0.6)
                    table += [{"algo": algo, "env": env, "measure": f"evaluation, seed {r['seed']}",
                               "steps": f"{s:.0f}", "mean": f"{v:.3f}", "min": "", "max": ""}
                              for s, v in zip(x, y)]  # fmt: skip
        ax.set_title(f"{algo.upper()}, {VERSIONS.get(version, version)}")
        ax.set_xlabel("env steps")
        ax.set_ylim(-0.03, 1.03)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    for row in axes:
        row[0].set_ylabel("success rate")
    fig.suptitle("success vs env steps; lines: last 100 training episodes (mean, band: min-max over seeds)\n"
                 "dots: evaluations of the deterministic policy (20 episodes each)", fontsize=9)  # fmt: skip
    fig.tight_layout()
    ns.out.mkdir(parents=True, exist_ok=True)
    fig.savefig(ns.out / "learning_curves.png", dpi=110)
    with open(ns.out / "learning_curves.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=["algo", "env", "measure", "steps", "mean", "min", "max"])
        writer.writeheader()
        writer.writerows(table)
    print(f"wrote {ns.out / 'learning_curves.png'} and learning_curves.csv ({len(groups)} algo/env groups)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
