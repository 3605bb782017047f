"""Learning curves of the shipped baselines: success rate against env steps, soft vs rigid fingers,
mean and spread (min-max) over seeds, one panel per algorithm and task version (a row each), or
(``--by kind``) one panel per id name and version, in rows of four.

    PYTHONPATH=. python benchmarks/learning_curves.py --versions v3       # agents/trained/ -> docs/results/
    PYTHONPATH=. python benchmarks/learning_curves.py --versions v3,v4 --by kind --name learning_curves_v3
    PYTHONPATH=. python benchmarks/learning_curves.py --models runs --out /tmp/curves

Two measures per run, both from the files train.py writes:
- lines: ``rollout/success_rate`` of SB3's log (``training.csv`` in a shipped model, ``logs/progress.csv``
  in a run): the share of the last 100 training episodes that ended in success, stochastic actions;
- markers: train.py's periodic evaluations (``progress.csv``): deterministic policy, separate seeds.
Each seed's curve is interpolated onto a common step grid before the mean and the band are taken.
A variant trained with ``--env-kwargs`` (the grip task without taxels) is a group of its own, drawn
in grey.
Writes ``learning_curves.png`` and ``learning_curves.csv`` (the plotted means and bands).
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

import numpy as np

from agents.cards import env_label, policy_label

ROOT = Path(__file__).resolve().parents[1]
FINGERS = {"SoftGrasp": "soft (tissue)", "SoftGraspRigid": "rigid", "SoftGraspRigidTorsion": "rigid + torsional friction",
           "SoftGraspGoal": "soft, goal (HER)", "SoftGraspGrip": "grip force, soft",
           "SoftGraspGripRigid": "grip force, rigid", "SoftGraspGripRigidTorsion": "grip force, torsional"}  # fmt: skip
COLORS = {"SoftGrasp": "tab:blue", "SoftGraspRigid": "tab:red", "SoftGraspGoal": "tab:green",
          "SoftGraspRigidTorsion": "tab:orange", "SoftGraspGrip": "tab:blue", "SoftGraspGripRigid": "tab:red",
          "SoftGraspGripRigidTorsion": "tab:orange"}  # fmt: skip
ALGO_COLORS = {"ppo": "tab:purple", "sac": "tab:blue", "her-sac": "tab:green"}
VERSIONS = {"v5": "v5 (the v4 tissue solved globally)", "v4": "v4 (the v4 tissue, swept)", "v3": "v3 (the sway band)"}


def _split(env_id: str) -> tuple[str, str]:
    """``"SoftGraspRigid-v3"`` -> ``("SoftGraspRigid", "v3")``; a variant's env kwargs after the id
    (``"SoftGraspGrip-v3 tactile=None"``, agents.cards.env_label) stay out of it."""
    name, _, version = env_id.split(" ", 1)[0].rpartition("-")
    return name, version


def _base(algo: str) -> str:
    """The algo of a table label (``"her-sac + 100 demos"``, ``"sac distilled from ..."`` ->
    ``"her-sac"``, ``"sac"``)."""
    return algo.split(" + ", 1)[0].split(" ", 1)[0]


def _variant(env: str) -> str:
    """The env kwargs of a variant's group name (``"tactile=None"``), "" for the id as registered."""
    return env.split(" ", 1)[1] if " " in env else ""


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
        groups.setdefault((policy_label(meta), env_label(meta)), []).append({
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


def grid_shape(panels: int, per_row: int) -> tuple[int, int]:
    """(rows, columns) for ``panels`` panels, at most ``per_row`` to a row: 7 by 4 -> (2, 4)."""
    if panels < 1 or per_row < 1:
        raise ValueError(f"need at least one panel and one per row, got panels={panels}, per_row={per_row}")
    columns = min(per_row, panels)
    return -(-panels // columns), columns


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--models", type=Path, default=ROOT / "agents" / "trained")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "results")
    parser.add_argument("--by", choices=["algo", "kind"], default="algo",
                        help="one panel per algorithm (lines: finger kinds) or per finger kind "
                             "(lines: algorithms)")  # fmt: skip
    parser.add_argument("--name", default="learning_curves", help="file name of the .png and .csv")
    parser.add_argument("--versions", default=None, help="only these env versions, e.g. v3 or v3,v4 (default: all)")
    parser.add_argument("--per-row", type=int, default=4,
                        help="with --by kind: at most this many panels per row (default 4)")  # fmt: skip
    ns = parser.parse_args(argv)
    if ns.per_row < 1:
        parser.error(f"--per-row must be at least 1, got {ns.per_row}")
    groups = load_runs(ns.models)
    if ns.versions:
        keep = set(ns.versions.split(","))
        groups = {k: v for k, v in groups.items() if _split(k[1])[1] in keep}
    if not groups:
        parser.error(f"no runs (*/run.json) under {str(ns.models)!r}" + (f" of {ns.versions}" if ns.versions else ""))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    algos = sorted({algo for algo, _ in groups}, key=lambda a: (["ppo", "sac", "her-sac"].index(_base(a)), a))
    order = list(FINGERS)
    if ns.by == "algo":  # a row per version, a panel per algo
        versions = sorted({_split(env)[1] for _, env in groups}, reverse=True)
        columns = algos
        cells = [(v, c) for v in versions for c in columns]
        shape = (len(versions), len(columns))
    else:  # a panel per id name and version (SoftGraspGoal-v4 beside the v3 kinds), rows of --per-row
        columns = sorted({_split(env) for _, env in groups},
                         key=lambda nv: (order.index(nv[0]) if nv[0] in order else 99, nv[1]))  # fmt: skip
        cells = [("", c) for c in columns]
        shape = grid_shape(len(cells), ns.per_row)
    fig, axes = plt.subplots(*shape, figsize=(5.2 * shape[1], 3.6 * shape[0]), squeeze=False)
    for ax in axes.flat[len(cells):]:  # the last row's empty places
        ax.set_visible(False)
    table = []
    for ax, (version, column) in zip(axes.flat, cells, strict=False):

        def in_panel(algo: str, env: str, version=version, column=column) -> bool:
            name, v = _split(env)
            return v == version and algo == column if ns.by == "algo" else (name, v) == column

        if not any(in_panel(a, env) for a, env in groups):
            ax.set_visible(False)
            continue
        for (algo, env), runs in sorted(groups.items()):
            if not in_panel(algo, env):
                continue
            name, _ = _split(env)
            seeds = f"{len(runs)} seed{'s' if len(runs) > 1 else ''}"
            label = f"{FINGERS.get(name, name)} ({seeds})" if ns.by == "algo" else f"{algo.upper()} ({seeds})"
            if _variant(env):
                label = f"{label}, {_variant(env)}"
            color = COLORS.get(name) if ns.by == "algo" else ALGO_COLORS.get(_base(algo))
            if _variant(env):
                color = "tab:gray"
            b = band([r["train"] for r in runs])
            if b is not None:
                grid, mean, lo, hi = b
                ax.plot(grid, mean, color=color, label=label)
                ax.fill_between(grid, lo, hi, color=color, alpha=0.2, lw=0)
                table += [{"algo": algo, "env": env, "measure": "training episodes", "steps": f"{s:.0f}",
                           "mean": f"{m:.3f}", "min": f"{lo_:.3f}", "max": f"{hi_:.3f}"}
                          for s, m, lo_, hi_ in zip(grid[::20], mean[::20], lo[::20], hi[::20], strict=True)]  # fmt: skip
            for r in runs:
                x, y = r["eval"]
                if len(x):
                    ax.plot(x, y, "o", ms=3.5, color=color, alpha=0.6)
                    table += [{"algo": algo, "env": env, "measure": f"evaluation, seed {r['seed']}",
                               "steps": f"{s:.0f}", "mean": f"{v:.3f}", "min": "", "max": ""}
                              for s, v in zip(x, y, strict=True)]  # fmt: skip
        if ns.by == "algo":
            ax.set_title(f"{column.upper()}, {VERSIONS.get(version, version)}")
        else:
            ax.set_title(f"{FINGERS.get(column[0], column[0])}, {VERSIONS.get(column[1], column[1])}")
        ax.set_xlabel("env steps")
        ax.set_ylim(-0.03, 1.03)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    for row in axes:
        row[0].set_ylabel("success rate")
    # one line a clause on a narrow figure (a single panel), two on a wide one
    sep = "\n" if shape[1] == 1 else "; "
    fig.suptitle(f"success vs env steps{sep}lines: last 100 training episodes (mean, band: min-max over seeds)\n"
                 "dots: evaluations of the deterministic policy (train.py's --eval-episodes each)",
                 fontsize=8 if shape[1] == 1 else 9)  # fmt: skip
    fig.tight_layout()
    ns.out.mkdir(parents=True, exist_ok=True)
    fig.savefig(ns.out / f"{ns.name}.png", dpi=110)
    with open(ns.out / f"{ns.name}.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=["algo", "env", "measure", "steps", "mean", "min", "max"])
        writer.writeheader()
        writer.writerows(table)
    print(f"wrote {ns.out / (ns.name + '.png')} and {ns.name}.csv ({len(groups)} algo/env groups)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
