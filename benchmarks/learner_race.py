"""Learners against wall-clock time (success; learners.py measures speed): SB3's SAC, sb3-contrib's
TQC and sbx's (JAX) SAC, TQC and CrossQ, each trained on a SoftGrasp id for the same wall-clock
budget, seeds side by side, success of the deterministic policy sampled at fixed training times.

    PYTHONPATH=. python benchmarks/learner_race.py [--env SoftGrasp-v5] [--minutes 15] [--seeds 0,1]
        [--learners sac,tqc,sbx-sac,sbx-tqc,sbx-crossq] [--every 90] [--episodes 20] [--out runs/race]

Every run is set up as train.py sets up its runs (one env, SB3's Monitor, observations normalised
by VecNormalize, the SAC preset of agents/baselines.py where the learner takes it: learners.py's
``preset``) and runs in its own process pinned to one core (``os.sched_setaffinity``), so that no learner gets
more of the machine than another (JAX's CPU pools ignore a one-thread request; the pin holds them),
two at a time on this 2-core machine. The clock is the process's CPU time (all its threads): on its
own core that is its wall-clock time, and a third process sharing the core for a while (a test run
beside the race) does not shorten one learner's budget against another's. The budget counts
training time only: every ``--every`` seconds of it the run stops the clock and evaluates the deterministic policy on ``--episodes``
fixed seeds (10,000 on, as train.py's evaluations) of a separate env. Prints, per learner and seed,
env steps reached and the success rate at each quarter of the budget, and the mean over seeds;
writes ``<out>/<learner>_<seed>.json`` and, with matplotlib, ``<out>/learner_race.png``.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from learners import LEARNERS, ONE_THREAD, preset  # noqa: E402 (benchmarks/ on the path first)

LEARNING_STARTS = 1000
"""train.py's SAC preset: random env steps before the first gradient step (they count in the budget)."""


def worker(name: str, env_id: str, seed: int, minutes: float, every: float, episodes: int, out: Path) -> None:
    """Train ``name`` on ``env_id`` for ``minutes`` of training time; write the curve to ``out``."""
    import importlib

    import gymnasium as gym
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecNormalize

    import softgrasp_env  # noqa: F401
    from agents.evaluate import evaluate
    from agents.runs import deterministic_policy
    from agents.threads import set_threads

    threads = set_threads(1)
    module, cls_name = LEARNERS[name]
    cls = getattr(importlib.import_module(module), cls_name)
    venv = make_vec_env(f"softgrasp_env:{env_id}", n_envs=1, seed=seed,
                        monitor_kwargs={"info_keywords": ("is_success",)})  # fmt: skip
    norm = VecNormalize(venv, norm_obs=True, norm_reward=False)
    eval_env = gym.make(env_id)
    model = cls("MlpPolicy", norm, seed=seed, verbose=0, **preset(name, learning_starts=LEARNING_STARTS))
    budget = minutes * 60.0
    rows: list[dict] = []

    class Clock(BaseCallback):
        """Training time (CPU time of this process) on a clock that stops while the policy is
        evaluated; ends the run at the budget."""

        def __init__(self) -> None:
            super().__init__()
            self.trained = 0.0
            self.next_eval = every
            self.since = time.process_time()

        def evaluate_now(self) -> None:
            ev = evaluate(eval_env, deterministic_policy(self.model, norm), episodes=episodes, seed=10_000)
            train_success = [float(i["is_success"]) for i in self.model.ep_info_buffer if "is_success" in i]
            rows.append({"train_seconds": self.trained, "timesteps": self.model.num_timesteps,
                         "success_rate": ev.success_rate, "mean_return": ev.mean_return,
                         "diverged": ev.diverged,
                         "train_success_last": sum(train_success) / len(train_success) if train_success else None})  # fmt: skip
            print(json.dumps(rows[-1]), flush=True)

        def _on_training_start(self) -> None:
            self.since = time.process_time()

        def _on_step(self) -> bool:
            now = time.process_time()
            self.trained += now - self.since
            self.since = now
            if self.trained >= self.next_eval or self.trained >= budget:
                self.next_eval += every
                self.evaluate_now()
                self.since = time.process_time()  # the evaluation is not training time
            return self.trained < budget

    clock = Clock()
    wall = time.perf_counter()
    model.learn(total_timesteps=10**9, callback=clock, log_interval=10**9)
    wall = time.perf_counter() - wall
    result = {"learner": name, "env": env_id, "seed": seed, "minutes": minutes, "every": every, "episodes": episodes,
              "threads": threads, "preset": {k: repr(v) for k, v in preset(name, learning_starts=LEARNING_STARTS).items()},
              "versions": _versions(), "wall_seconds_with_evaluations": wall, "curve": rows}  # fmt: skip
    out.write_text(json.dumps(result, indent=1))
    eval_env.close()
    norm.close()


def _versions() -> dict[str, str]:
    from importlib.metadata import PackageNotFoundError, version

    found = {}
    for dist in ("softgrasp-env", "stable-baselines3", "sb3-contrib", "sbx-rl", "torch", "jax"):
        try:
            found[dist] = version(dist)
        except PackageNotFoundError:
            pass
    return found


def _launch(name: str, seed: int, core: int, ns: argparse.Namespace, out: Path) -> subprocess.Popen:
    cmd = [sys.executable, __file__, "--worker", name, "--core", str(core), "--env", ns.env, "--seeds", str(seed),
           "--minutes", str(ns.minutes), "--every", str(ns.every), "--episodes", str(ns.episodes), "--out", str(out)]  # fmt: skip
    env = {**os.environ, **ONE_THREAD, "PYTHONPATH": str(ROOT)}
    log = open(out.with_suffix(".log"), "w")  # noqa: SIM115 (closed with the process)
    return subprocess.Popen(cmd, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, env=env)


def _at(curve: list[dict], seconds: float) -> dict | None:
    """The last evaluation taken at most ``seconds`` of training time (plus a second of slack)."""
    before = [r for r in curve if r["train_seconds"] <= seconds + 1.0]
    return before[-1] if before else None


TARGET = 0.9
"""The success rate whose first evaluation the table times."""


def first_at(curve: list[dict], target: float = TARGET) -> dict | None:
    """The first evaluation with success >= ``target`` (None: none reached it)."""
    return next((r for r in curve if r["success_rate"] >= target), None)


def report(results: list[dict], minutes: float) -> None:
    quarters = [minutes * 60 * k / 4 for k in (1, 2, 3, 4)]
    head = "".join(f"{f'{q / 60:.3g} min':>16}" for q in quarters) + f"{f'first >= {TARGET:.0%}':>22}"
    print(f"success of the deterministic policy (steps reached) at each quarter of the budget\n{'run':<18}{head}")
    by_learner: dict[str, list[dict]] = {}
    for r in results:
        by_learner.setdefault(r["learner"], []).append(r)
        cells = []
        for q in quarters:
            row = _at(r["curve"], q)
            cells.append(f"{'-':>16}" if row is None else f"{row['success_rate']:>6.0%} ({row['timesteps']:>6d})")
        hit = first_at(r["curve"])
        cells.append(f"{'not reached':>22}" if hit is None else
                     f"{hit['train_seconds'] / 60:>9.1f} min ({hit['timesteps']:>6d})")  # fmt: skip
        print(f"{r['learner'] + ' ' + str(r['seed']):<18}{''.join(cells)}")
    print(f"\n{'mean over seeds':<18}{head}")
    for name, runs in by_learner.items():
        cells = []
        for q in quarters:
            rows = [_at(r["curve"], q) for r in runs]
            rows = [x for x in rows if x is not None]
            if len(rows) < len(runs):
                cells.append(f"{'-':>16}")
                continue
            s = sum(x["success_rate"] for x in rows) / len(rows)
            n = sum(x["timesteps"] for x in rows) / len(rows)
            cells.append(f"{s:>6.0%} ({n:>6.0f})")
        hits = [first_at(r["curve"]) for r in runs]
        if all(h is not None for h in hits):
            cells.append(f"{sum(h['train_seconds'] for h in hits) / 60 / len(hits):>9.1f} min "
                         f"({sum(h['timesteps'] for h in hits) / len(hits):>6.0f})")  # fmt: skip
        else:
            cells.append(f"{f'{sum(h is not None for h in hits)} of {len(hits)} reached':>22}")
        print(f"{name:<18}{''.join(cells)}")


def plot(results: list[dict], path: Path) -> None:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot")
        return
    fig, ax = plt.subplots(figsize=(7, 4))
    colors = {}
    for r in results:
        c = colors.setdefault(r["learner"], f"C{len(colors)}")
        t = [x["train_seconds"] / 60 for x in r["curve"]]
        s = [x["success_rate"] * 100 for x in r["curve"]]
        ax.plot(t, s, color=c, marker=".", label=r["learner"] if r["seed"] == results[0]["seed"] else None,
                linestyle="-" if r["seed"] == results[0]["seed"] else "--")  # fmt: skip
    ax.set_xlabel("training time [min] (one core per run: its CPU time; evaluations not counted)")
    ax.set_ylabel("success [%] (deterministic policy)")
    ax.set_title(f"{results[0]['env']}: success against wall-clock time (seeds solid / dashed)")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    print(f"wrote {path}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default="SoftGrasp-v5")
    parser.add_argument("--learners", default=",".join(LEARNERS))
    parser.add_argument("--seeds", default="0,1")
    parser.add_argument("--minutes", type=float, default=15.0, help="training time per run")
    parser.add_argument("--every", type=float, default=90.0, help="training seconds between evaluations")
    parser.add_argument("--episodes", type=int, default=20, help="episodes per evaluation")
    parser.add_argument("--parallel", type=int, default=2, help="runs at a time, each pinned to its own core")
    parser.add_argument("--out", type=Path, default=ROOT / "runs" / "race")
    parser.add_argument("--report", action="store_true", help="only print the table of the runs in --out")
    parser.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    parser.add_argument("--core", type=int, default=None, help=argparse.SUPPRESS)
    ns = parser.parse_args(argv)
    if ns.minutes <= 0 or ns.every <= 0 or ns.episodes < 1 or ns.parallel < 1:
        parser.error("--minutes and --every must be > 0, --episodes and --parallel >= 1")
    seeds = [int(s) for s in ns.seeds.split(",")]
    if ns.worker:
        # pinned before torch or JAX starts a thread: every thread it makes inherits the one core
        if ns.core is not None:
            os.sched_setaffinity(0, {ns.core})
        worker(ns.worker, ns.env, seeds[0], ns.minutes, ns.every, ns.episodes, ns.out)
        return 0
    names = ns.learners.split(",")
    unknown = sorted(set(names) - set(LEARNERS))
    if unknown:
        parser.error(f"unknown learners {unknown}; choose from {', '.join(LEARNERS)}")
    ns.out.mkdir(parents=True, exist_ok=True)
    if not ns.report:
        missing = [n for n in names if importlib.util.find_spec(LEARNERS[n][0]) is None]
        for n in missing:
            print(f"{n}: skipped, {LEARNERS[n][0]} is not installed (pip install sb3-contrib sbx-rl)")
        jobs = [(n, s) for s in seeds for n in names if n not in missing]
        cores = os.sched_getaffinity(0)
        if len(cores) < ns.parallel:
            parser.error(f"--parallel {ns.parallel} needs as many cores; this process may use {sorted(cores)}")
        free = sorted(cores)[: ns.parallel]
        running: dict[int, subprocess.Popen] = {}
        print(f"{len(jobs)} runs of {ns.minutes:g} min training time, {ns.parallel} at a time, one core each",
              flush=True)  # fmt: skip
        while jobs or running:
            for core in free:
                if core not in running and jobs:
                    name, seed = jobs.pop(0)
                    running[core] = _launch(name, seed, core, ns, ns.out / f"{name}_{seed}.json")
                    print(f"started {name} seed {seed} on core {core}", flush=True)
            for core, proc in list(running.items()):
                if proc.poll() is not None:
                    if proc.returncode != 0:
                        print(f"a run on core {core} failed ({proc.returncode}); see its .log in {ns.out}")
                    del running[core]
            time.sleep(2.0)
    results = []
    for n in names:
        for s in seeds:
            path = ns.out / f"{n}_{s}.json"
            if path.exists():
                results.append(json.loads(path.read_text()))
    if not results:
        print("no finished runs")
        return 1
    report(results, ns.minutes)
    plot(results, ns.out / "learner_race.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
