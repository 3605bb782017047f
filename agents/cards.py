"""The trained baselines shipped in ``softgrasp_env/policies/trained/`` (package data, loaded by
``softgrasp_env.policies.load_baseline``; ``agents/trained`` is a link to it): publishing a train.py
run there with its model card, reading the cards back, and the results table.

    python -m agents.cards publish runs/SoftGrasp-v5_ppo_0 runs/SoftGraspRigid-v3_ppo_0 ...
    python -m agents.cards table                 # the results table (scripted measured live)
    python -m agents.cards objects --versions 1  # success per object on the object-set ids

``publish`` evaluates each run over 100 seeded episodes (seeds 1000-1099, the seeds
``agents.evaluate`` uses, so scripted and learned policies meet the same starts), then copies into
``softgrasp_env/policies/trained/<env>_<algo>_<seed>/`` what loading and the learning curves need: ``model.zip``,
``vecnormalize.pkl`` (not for HER), ``run.json``, ``progress.csv`` (train.py's periodic
evaluations) and ``training.csv`` (the columns of SB3's log the curves use). The replay buffer
stays behind: it is hundreds of MB and only needed to resume. The card is ``card.json`` (read by
the tests and the table) and ``README.md`` (the same, for people).
"""

from __future__ import annotations

import argparse
import csv
import json
import platform
import shlex
import shutil
import sys
from pathlib import Path
from typing import Any

from softgrasp_env.policies.baselines import TRAINED  # the package data folder the baselines ship in

EPISODES, SEED = 100, 1000
HYPERPARAMS_FILE = {"ppo": "agents/hyperparams/ppo.yml", "sac": "agents/hyperparams/sac.yml",
                    "her-sac": "agents/hyperparams/sac.yml"}  # fmt: skip
TRAINING_COLUMNS = ("time/total_timesteps", "time/time_elapsed", "rollout/success_rate", "rollout/ep_rew_mean",
                    "rollout/ep_len_mean")  # fmt: skip


def shipped() -> list[Path]:
    """The directories of the shipped models, sorted by name."""
    return sorted(p.parent for p in TRAINED.glob("*/card.json"))


def read_card(model_dir: Path) -> dict[str, Any]:
    return json.loads((Path(model_dir) / "card.json").read_text())


CONVERGED_POINTS = 5.0
"""The cards' convergence rule: a run has converged when its evaluation success changes by less than 5 points
over the last 20 % of its budget."""
CONVERGED_WINDOW = 0.2


def wilson(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """Wilson's score interval for a binomial proportion (Wilson 1927; 95 % at z = 1.96): unlike the
    normal approximation it stays inside [0, 1] and is not empty at 0 or n successes."""
    if n < 1 or not 0 <= successes <= n:
        raise ValueError(f"need 0 <= successes <= n and n >= 1, got successes={successes!r}, n={n!r}")
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * (p * (1 - p) / n + z * z / (4 * n * n)) ** 0.5
    return max(0.0, centre - half), min(1.0, centre + half)


def change_text(change: float, stderr: float, points: float = CONVERGED_POINTS) -> str:
    """A convergence's change and its standard error as a card prints them: one decimal, or two
    where one would round the change onto or past the rule's bound (+4.96 printed "+5.0" beside
    "converged")."""
    digits = 2 if (abs(round(change, 1)) >= points) != (abs(change) >= points) else 1
    return f"{change:+.{digits}f} ± {stderr:.{digits}f}"


def convergence(progress: list[dict[str, str]], budget: int, *, window: float = CONVERGED_WINDOW,
                points: float = CONVERGED_POINTS) -> dict[str, Any]:  # fmt: skip
    """Whether a run's evaluation success settled: the change over the last ``window`` of its
    ``budget`` (env steps), read off a least-squares line through train.py's periodic evaluations
    in that window (a line, not the two end points: each evaluation is a small sample, and its
    noise would decide otherwise), in percentage points, with its standard error. Converged when
    the change is below ``points`` in magnitude. Fewer than 3 evaluations in the window: not
    decided (``converged`` None)."""
    start = budget * (1.0 - window)
    pts = [(float(r["timesteps"]), float(r["success_rate"])) for r in progress
           if r.get("timesteps") and float(r["timesteps"]) >= start - 1e-9]  # fmt: skip
    out: dict[str, Any] = {"rule": f"|change| < {points:g} points over the last {window:.0%} of {budget:,} steps "
                                   "(least-squares line through the evaluations there)",
                           "evaluations": len(pts), "change_points": None, "stderr_points": None,
                           "converged": None}  # fmt: skip
    if len(pts) < 3:
        return out
    import numpy as np

    x, y = np.array(pts).T
    slope, intercept = np.polyfit(x, y, 1)
    resid = y - (slope * x + intercept)
    sxx = float(np.sum((x - x.mean()) ** 2))
    se = float(np.sqrt(np.sum(resid**2) / max(1, len(x) - 2) / sxx)) if sxx > 0 else float("nan")
    span = budget * window
    # + 0.0: a flat line's slope rounds to -0.0, which a card would print as "-0.0"
    out.update(change_points=round(float(slope * span * 100), 2) + 0.0, stderr_points=round(se * span * 100, 2) + 0.0,
               converged=bool(abs(slope * span * 100) < points), final_evaluation=float(y[-1]))  # fmt: skip
    return out


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, type):
        return value.__name__
    return value


def hyperparameters(meta: dict[str, Any]) -> dict[str, Any]:
    """Every keyword the SB3 class got: as train.py recorded them, else the preset of
    ``agents/baselines.py`` as it stands updated by the run's ``--algo-kwargs`` (and
    ``--learning-starts``)."""
    from agents.baselines import PRESETS

    if meta.get("hyperparameters"):  # recorded by train.py since the baselines were shipped
        return meta["hyperparameters"]
    out = {**PRESETS[meta["algo"]], **meta.get("algo_kwargs", {})}
    if meta.get("asymmetric"):
        from agents.baselines import asymmetric_policy

        out["policy"] = asymmetric_policy(meta["algo"])
    if meta.get("learning_starts") is not None and meta["algo"] != "ppo":
        out["learning_starts"] = meta["learning_starts"]
    if meta.get("demo_share") is not None:
        from agents.demos import demo_buffer

        out.update(demo_buffer(bool(meta.get("asymmetric")), meta["demo_share"]))
    if meta.get("demo_bc") is not None:
        out["demo_bc"] = meta["demo_bc"]
    return _jsonable(out)


def quote_arg(arg: str) -> str:
    """``arg`` as a POSIX shell word: bare when safe, in double quotes when it holds single quotes
    (a dict literal such as ``policy_kwargs={'net_arch': [64, 64]}``), else as shlex quotes it."""
    if "'" in arg and not any(c in arg for c in '"$`\\!'):
        return f'"{arg}"'
    return shlex.quote(arg)


def command(meta: dict[str, Any]) -> str:
    """The train.py command that made the run: recorded by train.py, else rebuilt from run.json."""
    if meta.get("command"):  # re-quoted: runs before quote_arg recorded shlex's '"'"' quoting
        return " ".join(quote_arg(a) for a in shlex.split(meta["command"]))
    args = ["python", "train.py", "--env", meta["env"], "--algo", meta["algo"], "--seed", str(meta["seed"]),
            "--timesteps", str(meta["timesteps"]), "--eval-every", str(meta["eval_every"]),
            "--eval-episodes", str(meta["eval_episodes"])]  # fmt: skip
    if meta.get("env_kwargs"):
        args += ["--env-kwargs", *(f"{k}={v!r}" for k, v in meta["env_kwargs"].items())]
    if meta.get("algo_kwargs"):
        args += ["--algo-kwargs", *(f"{k}={v!r}" for k, v in meta["algo_kwargs"].items())]
    return " ".join(quote_arg(a) for a in args)


def _training_log(run_dir: Path) -> list[dict[str, str]]:
    """SB3's training rows of the run, every part of it: a run resumed at step N logs on in
    ``logs/progress_from_N.csv`` (train.py). Each part is cut where the next one resumed (rows past
    that checkpoint were discarded with the steps that made them) and its ``time/time_elapsed``,
    which SB3 starts at 0 in each part, goes on from the previous part's last row."""
    logs = run_dir / "logs"
    parts = [(0, logs / "progress.csv")] if (logs / "progress.csv").exists() else []
    for path in logs.glob("progress_from_*.csv"):
        start = path.stem.removeprefix("progress_from_")
        if start.isdigit():
            parts.append((int(start), path))
    parts.sort()
    rows: list[dict[str, str]] = []
    offset = 0.0
    for i, (_, path) in enumerate(parts):
        end = parts[i + 1][0] if i + 1 < len(parts) else None
        with open(path, newline="") as f:
            # SB3 writes evaluation rows of its own (eval/* only): the curves need the training ones
            part = [{k: row.get(k, "") for k in TRAINING_COLUMNS} for row in csv.DictReader(f)
                    if row.get("time/total_timesteps")]  # fmt: skip
        part = [r for r in part if end is None or int(float(r["time/total_timesteps"])) <= end]
        for r in part:
            if r.get("time/time_elapsed"):
                r["time/time_elapsed"] = f"{float(r['time/time_elapsed']) + offset:g}"
        rows += part
        elapsed = [float(r["time/time_elapsed"]) for r in part if r.get("time/time_elapsed")]
        offset = max(elapsed, default=offset)
    return rows


def train_seconds(meta: dict[str, Any], log: list[dict[str, str]],
                  progress: list[dict[str, str]] = ()) -> float | None:  # fmt: skip
    """Wall time of the training: recorded by train.py, else the last ``time/time_elapsed`` of SB3's log.

    A run trained in parts (``sessions`` in run.json, from ``--resume``) sums its parts. A part cut
    off before train.py could record its time (the first session, when its machine stopped) counts
    up to the checkpoint the next part resumed from, read off the wall clock of train.py's
    evaluations (``progress.csv``, a clock that a resumed run continues from that checkpoint's
    evaluation); the steps trained past the checkpoint were discarded and are not counted. None if
    a part's time cannot be told."""
    sessions = meta.get("sessions") or []
    if not sessions:
        if meta.get("train_seconds") is not None:
            return float(meta["train_seconds"])
        times = [float(r["time/time_elapsed"]) for r in log if r.get("time/time_elapsed")]
        return max(times) if times else None
    rows = sorted((int(float(r["timesteps"])), float(r["wall_seconds"])) for r in progress if r.get("wall_seconds"))

    def clock(steps: int) -> float:
        """The evaluations' clock at ``steps``: its last reading at or before them (train.py's
        offset for a part resumed there)."""
        return max((w for t, w in rows if t <= steps), default=0.0)

    starts = [0] + [int(s["at_timesteps"]) for s in sessions]
    recorded = [meta.get("train_seconds")] + [s.get("train_seconds") for s in sessions]
    total = 0.0
    for i, seconds in enumerate(recorded):
        if seconds is not None:
            total += float(seconds)
        elif i + 1 < len(starts) and rows:
            total += clock(starts[i + 1]) - clock(starts[i])
        else:
            return None  # the last part unrecorded (still training, or cut with nothing resumed from it)
    return round(total, 1)


def publish(run_dir: Path, *, episodes: int = EPISODES, seed: int = SEED, dest: Path = TRAINED) -> Path:
    """Evaluate the run at ``run_dir`` and copy it, with its card, to ``dest/<run name>/``."""
    import numpy as np
    import stable_baselines3
    import torch

    import softgrasp_env
    from agents.evaluate import evaluate
    from agents.runs import load_run, make_env, run_files

    env = make_env(run_files(run_dir).meta)  # one env for loading (HER's buffer needs it) and evaluating
    try:
        loaded = load_run(run_dir, env=env)
        env.action_space.seed(seed)
        ev = evaluate(env, loaded.policy, episodes=episodes, seed=seed)
    finally:
        env.close()
    meta = loaded.meta
    log = _training_log(loaded.files.run_dir)
    out = dest / loaded.files.run_dir.name
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    shutil.copy2(loaded.files.model, out / "model.zip")
    if loaded.files.vecnormalize.exists():
        shutil.copy2(loaded.files.vecnormalize, out / "vecnormalize.pkl")
    for name in ("run.json", "progress.csv"):
        if (loaded.files.run_dir / name).exists():
            shutil.copy2(loaded.files.run_dir / name, out / name)
    with open(out / "training.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=TRAINING_COLUMNS)
        writer.writeheader()
        writer.writerows(log)
    successes = round(ev.success_rate * ev.episodes)
    progress: list[dict[str, str]] = []
    if (out / "progress.csv").exists():
        with open(out / "progress.csv", newline="") as f:
            progress = list(csv.DictReader(f))
    card = {
        "name": out.name,
        "env": meta["env"],
        "env_version": int(meta["env"].rsplit("-v", 1)[1]),
        "env_kwargs": meta.get("env_kwargs", {}),
        "algo": meta["algo"],
        "hyperparameters_file": HYPERPARAMS_FILE[meta["algo"]],
        "hyperparameters": hyperparameters(meta),
        "timesteps": int(loaded.model.num_timesteps),
        "seed": int(meta["seed"]),
        "train_seconds": train_seconds(meta, log, progress),
        "command": command(meta),
        "evaluation": {
            "episodes": ev.episodes,
            "seeds": f"{seed}-{seed + episodes - 1}",
            "deterministic": True,
            "success_rate": ev.success_rate,
            "successes": successes,
            "wilson95": [round(v, 4) for v in wilson(successes, ev.episodes)],
            "mean_return": round(ev.mean_return, 4),
            "mean_final_lift_m": round(ev.mean_final_lift, 5),
            "diverged": ev.diverged,
            **({"by_object": {name: list(ev.by_object[name]) for name in sorted(ev.by_object)}}
               if ev.by_object else {}),
        },
        "convergence": convergence(progress, int(loaded.model.num_timesteps)),
        **({"demonstrations": meta["demonstrations"]} if meta.get("demonstrations") else {}),
        **({"asymmetric": True} if meta.get("asymmetric") else {}),
        **({"distilled": meta["distilled"]} if meta.get("distilled") else {}),
        "versions": {"softgrasp_env": softgrasp_env.__version__, "stable_baselines3": stable_baselines3.__version__,
                     "torch": torch.__version__, "numpy": np.__version__, "python": platform.python_version()},
        "machine": "2-core x86-64 CPU, no GPU; two runs trained at a time, one torch thread each",
    }
    (out / "card.json").write_text(json.dumps(card, indent=2) + "\n")
    (out / "README.md").write_text(render_card(card))
    return out


def render_card(card: dict[str, Any]) -> str:
    ev = card["evaluation"]
    minutes = "unknown" if card["train_seconds"] is None else f"{card['train_seconds'] / 60:.1f} min"
    lines = [
        f"# {card['name']}",
        "",
        f"{card['algo'].upper()} on `{card['env']}` (version {card['env_version']}), stable-baselines3.",
        "",
        "| | |",
        "|---|---|",
        f"| env id | `{card['env']}`, kwargs `{card['env_kwargs']}` |",
        f"| algo | {card['algo']} |",
        f"| hyperparameters | `{card['hyperparameters_file']}` (the preset); as trained: `{card['hyperparameters']}` |",
        f"| steps | {card['timesteps']:,} |",
        f"| seed | {card['seed']} |",
        (
            f"| success | **{ev['success_rate']:.0%}** over {ev['episodes']} episodes (seeds {ev['seeds']}, "
            f"deterministic policy); mean return {ev['mean_return']:.2f}, mean final lift "
            f"{ev['mean_final_lift_m'] * 100:.2f} cm, diverged {ev['diverged']} |"
        ),
        *_card_extras(card),
        f"| wall time | {minutes} of training on {card['machine']} |",
        f"| command | `{card['command']}` |",
        "",
        f"Load: `softgrasp_env.policies.load_baseline({card['name']!r})` (the `[train]` extra); evaluate: "
        f"`python -m agents.evaluate --policy {card['name']} --episodes 100` (in the repository)",
        "",
    ]
    return "\n".join(lines)


def _card_extras(card: dict[str, Any]) -> list[str]:
    """The card rows of the evaluation's spread and the run's convergence (older cards have neither)."""
    rows = []
    ev = card["evaluation"]
    if "wilson95" in ev:
        lo, hi = ev["wilson95"]
        rows.append(f"| 95 % interval | {lo:.0%} - {hi:.0%} (Wilson, {ev['successes']} of {ev['episodes']}) |")
    if ev.get("by_object"):
        from agents.evaluate import object_line

        rows.append(f"| success per object | {object_line({k: tuple(v) for k, v in ev['by_object'].items()})} "
                    "(successes/episodes of the evaluation's episodes, each object as drawn) |")  # fmt: skip
    conv = card.get("convergence")
    if conv:
        if conv["converged"] is None:
            verdict = f"not decided ({conv['evaluations']} evaluations in the window)"
        else:
            verdict = (f"{'**converged**' if conv['converged'] else '**not converged**'}: "
                       f"{change_text(conv['change_points'], conv['stderr_points'])} points "
                       f"over the window, {conv['evaluations']} evaluations")  # fmt: skip
        rows.append(f"| convergence | {verdict}; rule: {conv['rule']} |")
    if card.get("asymmetric"):
        rows.append("| critic | asymmetric: in training the critic also read the privileged state (the object's pose, "
                    "mass and friction: `softgrasp_env.wrappers.PrivilegedObservation`); the actor reads the env's "
                    "observation alone |")  # fmt: skip
    distilled = card.get("distilled")
    if distilled:
        noisy = (f", then {distilled['rounds']} rounds of {distilled['round_episodes']} with its actions perturbed by "
                 f"noise of std {distilled['noise']:g}" if distilled["rounds"] else "")  # fmt: skip
        rows.append(f"| distilled | the actor fitted to {distilled['expert']}'s actions (`agents/distill.py`: behaviour "
                    f"cloning on {distilled['episodes']} of its episodes{noisy}; seeds {distilled['seeds']}, the "
                    f"expert successful in {distilled['expert_successes']}); no reinforcement learning |")  # fmt: skip
    demos = card.get("demonstrations")
    if demos:
        script = {"ShearLagGripPolicy": "the shear-lag grip script", "TactileGripPolicy": "the slip grip script"}.get(
            demos.get("policy"), "the scripted grasp")
        rows.append(f"| demonstrations | {demos['episodes']} episodes of {script} (seeds {demos['seeds']}; "
                    f"{demos['successes']} successful, {demos['transitions']:,} transitions) in the replay buffer "
                    "before training (`--demos`, agents/demos.py)"
                    + (f", kept for the whole run as {demos['share']:.0%} of every batch (`--demo-share`)"
                       if demos.get("share") else "")
                    + (f", cloned with weight {demos['bc']:g} under the Q-filter (`--demo-bc`)" if demos.get("bc") else "")
                    + " |")  # fmt: skip
    return rows


def policy_label(card: dict[str, Any]) -> str:
    """The learner as the table names it: the algo, whether its critic read privileged state
    (``sac asymmetric``) and the scripted demonstrations it started from (``her-sac + 100 demos``):
    each a group of its own."""
    demos = card.get("demonstrations")
    algo = f"{card['algo']} asymmetric" if card.get("asymmetric") else card["algo"]
    if card.get("distilled"):
        return f"{algo} distilled from {card['distilled']['expert']}"
    if not demos:
        return algo
    kept = f" ({demos['share']:.0%} of each batch{', BC %g' % demos['bc'] if demos.get('bc') else ''})" if demos.get(
        "share") else ""
    return f"{algo} + {demos['episodes']} demos{kept}"


def env_label(card: dict[str, Any]) -> str:
    """The env a card's model was trained on as the table names it: the id, and the ``--env-kwargs``
    it was made with (a variant, e.g. ``SoftGraspGrip-v6 tactile=None``, is a group of its own)."""
    kwargs = card.get("env_kwargs") or {}
    return " ".join([card["env"], *(f"{k}={v!r}" for k, v in sorted(kwargs.items()))])


SCRIPTED_IDS = ("SoftGrasp-v5", "SoftGrasp-v4", "SoftGraspRigid-v3", "SoftGraspRigidTorsion-v3", "SoftGraspGoal-v6",
                "SoftGraspGoal-v5", "SoftGraspGrip-v7", "SoftGraspGrip-v6", "SoftGraspGripRigid-v5",
                "SoftGraspGripRigidTorsion-v5", "SoftGraspGripRigid-v4", "SoftGraspGripRigidTorsion-v4",
                "SoftGraspObjects-v2", "SoftGraspObjects-v1", "SoftGraspObjectsRigid-v1", "SoftGraspObjectsRigidTorsion-v1",
                "SoftGraspObjectsGrip-v3", "SoftGraspObjectsGrip-v2", "SoftGraspObjectsGripRigid-v2",
                "SoftGraspObjectsGripRigidTorsion-v2", "SoftGraspObjectsGripRigid-v1", "SoftGraspObjectsGripRigidTorsion-v1")
"""The ids whose scripted policy the tables measure live."""


def scripted_evaluations(*, episodes: int = EPISODES, seed: int = SEED, versions: tuple[int, ...] | None = None,
                         ids: tuple[str, ...] = SCRIPTED_IDS) -> list[tuple[str, str, Any]]:  # fmt: skip
    """The scripted policy of each of ``ids`` (of ``versions`` if given) on the cards' episodes:
    ``(label, env id, Evaluation)``. The grip ids' policy (the squeeze as the action) reads the
    taxels ('scripted tactile': ``grip_script``, the shear-lag script on tissue pads, the slip script
    on rigid ones); the others run the scripted grasp."""
    import gymnasium as gym

    import softgrasp_env  # noqa: F401
    from agents.evaluate import evaluate
    from softgrasp_env.policies import ScriptedGraspPolicy
    from softgrasp_env.policies.grip import grip_script

    out = []
    for env_id in ids:
        if versions is not None and int(env_id.rsplit("-v", 1)[1]) not in versions:
            continue
        env = gym.make(env_id)
        grip = env.unwrapped.args.control.finger_action == "force"
        try:
            policy = grip_script(env) if grip else ScriptedGraspPolicy.for_env(env)
            ev = evaluate(env, policy, episodes=episodes, seed=seed)
        finally:
            env.close()
        out.append(("scripted tactile" if grip else "scripted", env_id, ev))
    return out


def objects_table(*, episodes: int = EPISODES, seed: int = SEED, scripted: bool = True,
                  versions: tuple[int, ...] | None = None) -> str:  # fmt: skip
    """Success per object (markdown) on the object-set ids: the scripted policy measured now on the
    cards' episodes, and every shipped model of those ids from its card, its seeds pooled
    (successes / episodes that drew the object)."""
    rows: list[tuple[str, str, dict[str, tuple[int, int]]]] = []
    if scripted:
        ids = tuple(i for i in SCRIPTED_IDS if "Objects" in i)
        for label, env_id, ev in scripted_evaluations(episodes=episodes, seed=seed, versions=versions, ids=ids):
            rows.append((label, env_id, dict(ev.by_object)))
    groups: dict[tuple[str, str], dict[str, tuple[int, int]]] = {}
    for model_dir in shipped():
        card = read_card(model_dir)
        by_object = card["evaluation"].get("by_object")
        if not by_object or (versions is not None and card["env_version"] not in versions):
            continue
        pooled = groups.setdefault((policy_label(card), env_label(card)), {})
        for name, (won, met) in by_object.items():
            w, m = pooled.get(name, (0, 0))
            pooled[name] = (w + won, m + met)
    rows += [(label, env, pooled) for (label, env), pooled in sorted(groups.items())]
    names = sorted({name for _, _, by_object in rows for name in by_object})
    out = ["| policy | env | " + " | ".join(names) + " |", "|---|---|" + "---|" * len(names)]
    for label, env_id, by_object in rows:
        cells = [f"{by_object[n][0]}/{by_object[n][1]}" if n in by_object else "-" for n in names]
        out.append(f"| {label} | {env_id} | " + " | ".join(cells) + " |")
    return "\n".join(out)


def table(*, episodes: int = EPISODES, seed: int = SEED, scripted: bool = True,
          versions: tuple[int, ...] | None = None) -> str:  # fmt: skip
    """The results table (markdown): the scripted policy, measured now on the same seeds, and every
    shipped model from its card; per algo and env, mean and range over seeds; only the ids of
    ``versions`` if given (e.g. ``(3,)``)."""
    import numpy as np

    rows = []
    if scripted:
        for label, env_id, ev in scripted_evaluations(episodes=episodes, seed=seed, versions=versions):
            rows.append((label, env_id, "-", "-", [ev.success_rate], "-"))
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for model_dir in shipped():
        card = read_card(model_dir)
        if versions is not None and card["env_version"] not in versions:
            continue
        groups.setdefault((policy_label(card), env_label(card)), []).append(card)
    for (algo, env_id), cards in sorted(groups.items()):
        rates = [c["evaluation"]["success_rate"] for c in cards]
        steps = sorted({c["timesteps"] for c in cards})
        minutes = [c["train_seconds"] / 60 for c in cards if c["train_seconds"] is not None]
        decided = [c["convergence"]["converged"] for c in cards if c.get("convergence")]
        converged = f"{sum(bool(d) for d in decided)} of {len(cards)}" if decided else "-"
        rows.append((algo, env_id, "/".join(f"{s:,}" for s in steps),
                     f"{np.mean(minutes):.0f}" if minutes else "-", rates, converged))  # fmt: skip
    out = [("| policy | env | env steps | train min (mean) | seeds | success, 100 episodes each (mean; per seed) "
            "| 95 % interval (Wilson, all episodes) | converged |"),
           "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for algo, env_id, steps, minutes, rates, converged in rows:
        per_seed = " / ".join(f"{r:.0%}" for r in rates)
        lo, hi = wilson(round(sum(rates) * episodes), episodes * len(rates))
        out.append(f"| {algo} | {env_id} | {steps} | {minutes} | {'-' if algo.startswith('scripted') else len(rates)} | "
                   f"**{np.mean(rates):.0%}**" + (f" ({per_seed})" if len(rates) > 1 else "") +
                   f" | {lo:.0%} - {hi:.0%} | {converged} |")  # fmt: skip
    return "\n".join(out)


def runs_table(*, versions: tuple[int, ...] | None = None) -> str:
    """One row per shipped model (markdown; of ``versions`` if given), ordered by env, algo and
    seed: steps, success with its Wilson interval, the change over the last 20 % of the budget
    with its standard error, whether the run converged, wall time."""
    rows = []
    for model_dir in shipped():
        card = read_card(model_dir)
        if versions is not None and card["env_version"] not in versions:
            continue
        ev, conv = card["evaluation"], card.get("convergence") or {}
        lo, hi = ev.get("wilson95") or wilson(round(ev["success_rate"] * ev["episodes"]), ev["episodes"])
        change = "-" if conv.get("change_points") is None else change_text(conv["change_points"], conv["stderr_points"])
        verdict = {True: "yes", False: "no"}.get(conv.get("converged"), "undecided" if conv else "-")
        minutes = "-" if card["train_seconds"] is None else f"{card['train_seconds'] / 60:.0f}"
        learner, plus, demos = policy_label(card).partition(" + ")  # the algo in capitals, the demos as they read
        label = f"{learner.upper()}{plus}{demos} {env_label(card)} seed {card['seed']}"
        row = (f"| {label} | {card['timesteps']:,} | **{ev['success_rate']:.0%}** ({lo:.0%}-{hi:.0%}) | "
               f"{change.replace('-0.0 ', '+0.0 ')} | {verdict} | {minutes} |")  # fmt: skip
        rows.append(((env_label(card), card["algo"], card["seed"]), row))
    head = ["| run | env steps | success (Wilson 95 %) | change over the last 20 % | converged | train min |",
            "|---|---|---|---|---|---|"]  # fmt: skip
    return "\n".join(head + [row for _, row in sorted(rows)])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m agents.cards", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    sub = parser.add_subparsers(dest="command", required=True)
    pub = sub.add_parser("publish", help="evaluate runs and copy them, with their cards, to softgrasp_env/policies/trained/")
    pub.add_argument("runs", nargs="+", type=Path)
    pub.add_argument("--episodes", type=int, default=EPISODES)
    pub.add_argument("--dest", type=Path, default=TRAINED)
    tab = sub.add_parser("table", help="print the results table")
    tab.add_argument("--no-scripted", action="store_true")
    tab.add_argument("--versions", type=int, nargs="+", default=None, metavar="N",
                     help="only the ids of these versions (default: every shipped one)")  # fmt: skip
    objs = sub.add_parser("objects", help="print success per object on the object-set ids (scripted measured live)")
    objs.add_argument("--no-scripted", action="store_true")
    objs.add_argument("--versions", type=int, nargs="+", default=None, metavar="N",
                      help="only the ids of these versions (default: every shipped one)")  # fmt: skip
    per_run = sub.add_parser("runs", help="print the per-run table (steps, success, convergence, wall time)")
    per_run.add_argument("--versions", type=int, nargs="+", default=None, metavar="N",
                         help="only the ids of these versions (default: every shipped one)")  # fmt: skip
    ns = parser.parse_args(argv)
    if ns.command == "objects":
        print(objects_table(scripted=not ns.no_scripted, versions=None if ns.versions is None else tuple(ns.versions)))
        return 0
    if ns.command == "runs":
        print(runs_table(versions=None if ns.versions is None else tuple(ns.versions)))
        return 0
    if ns.command == "publish":
        if ns.episodes < 1:
            parser.error(f"--episodes must be >= 1, got {ns.episodes}")
        for run in ns.runs:
            try:
                out = publish(run, episodes=ns.episodes, dest=ns.dest)
            except ValueError as exc:
                parser.error(f"{run}: {exc}")
            card = read_card(out)
            print(f"{out}: success {card['evaluation']['success_rate']:.0%} over {card['evaluation']['episodes']} "
                  f"episodes, {card['timesteps']:,} steps", flush=True)  # fmt: skip
    else:
        print(table(scripted=not ns.no_scripted, versions=None if ns.versions is None else tuple(ns.versions)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
