"""Where the grip-force task's reward peaks over constant grips: the squeeze charge measured.

    PYTHONPATH=. python benchmarks/squeeze_charge.py run [--seeds 12] [--factors 0.8,1,...,3]
        [--ids SoftGraspGrip-v6,SoftGraspGripRigidTorsion-v5,SoftGraspGripRigid-v5] [--out CSV]
    PYTHONPATH=. python benchmarks/squeeze_charge.py curves [--csv CSV] [--plot PNG] [--plot-charges v5,v6]
    PYTHONPATH=. python benchmarks/squeeze_charge.py policies [--ids ...] [--seeds 10] [--weight-carry 1.0]

``run``: each episode squeezes with one constant force (policies/grip.py ``ConstantGripPolicy``),
``factor`` times the static least m g / (2 mu_s) of the episode's drawn mass and friction (read
from the env's privileged state), capped at the finger's 6 N. Per episode it records the sum of
the reward's other terms (lift, reach), the squeeze the fingers measured (sum over the steps of F,
of F / F_static and of (F / F_static)^2), the carry's success without the squeeze bound, and the
task's ``carry_squeeze`` / ``least_squeeze`` and, on the object-set ids, the episode's object. The
squeeze term does not act on the physics, so ``curves`` re-prices the same episodes under any
charge: the expected return per factor, each kind, and where it peaks (the grip ids' charges and
the candidates), then the carried episodes per factor and, on the object-set ids, per object and
factor (which shapes need more than the static least). The ids only name the rows: the ids of one
kind run the same physics.

``policies``: what a learner compares - the return of the tactile grip script the demonstrations
come from (softgrasp_env.policies.grip.grip_script), of the same script letting go when the carry begins, of a
hand held open and of one left half closed, under the id's own charge and under charges on the carry's
steps alone (weight ``--weight-carry``: on the squeeze, or on its margin over the least), the same
episodes re-priced.
"""

from __future__ import annotations

import argparse
import csv
import math
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

import softgrasp_env  # noqa: F401
from benchmarks.slip_warning_grip import constant_grip
from softgrasp_env.registration import SQUEEZE_WEIGHT_LEAST

FIELDS = ("id", "factor", "seed", "mass", "mu", "static_least", "force", "steps", "base", "sum_f", "sum_r", "sum_r2",
          "carried", "success", "carry_squeeze", "least_squeeze", "sum_r_carry",
          "sum_m_carry", "object")  # fmt: skip
SQUEEZE_FACTOR = 2.0
"""The grip ids' bound on the carry's mean squeeze, in least forces (registration.GRIP_TASK)."""
OUT = Path("docs/results/squeeze_charge.csv")


def episode(env: gym.Env, factor: float, seed: int) -> dict:
    base = env.unwrapped
    policy, mu, mass, static, force = constant_grip(env, factor, seed)
    obs, _ = env.reset(seed=seed)
    row = {"factor": factor, "seed": seed, "mass": mass, "mu": mu, "static_least": static, "force": force, "steps": 0,
           "base": 0.0, "sum_f": 0.0, "sum_r": 0.0, "sum_r2": 0.0, "sum_r_carry": 0.0,
           "sum_m_carry": 0.0}  # fmt: skip
    done, info = False, {}
    while not done:
        obs, _, term, trunc, info = env.step(policy(obs))
        done = term or trunc
        terms = info["reward_terms"]
        f = float(np.mean([obs[base.obs_names.index("force_left")], obs[base.obs_names.index("force_right")]]))
        row["steps"] += 1
        row["base"] += sum(v for k, v in terms.items() if k != "squeeze")
        row["sum_f"] += f
        row["sum_r"] += f / static
        row["sum_r2"] += (f / static) ** 2
        if base.task.task.phase(base.scene.steps) is not None:  # the carry's steps as the task charges them
            row["sum_r_carry"] += f / static
            row["sum_m_carry"] += max(0.0, f / static - 1.0)
    least, mean = float(info["least_squeeze"]), float(info["carry_squeeze"])
    row["object"] = info.get("object", "")  # the object-set ids name the episode's object
    row["carried"] = bool(info["is_success"])  # the env is made without the squeeze bound: the carry's own
    row["success"] = row["carried"] and mean <= SQUEEZE_FACTOR * least
    row["carry_squeeze"] = mean
    row["least_squeeze"] = least
    return row


def run(ids: list[str], factors: list[float], seeds: int, out: Path, first_seed: int = 1000) -> None:
    rows = []
    for env_id in ids:
        env = gym.make(env_id, squeeze_factor=None)  # success: the carry's alone (the bound applied here)
        tic = time.perf_counter()
        for factor in factors:
            for seed in range(first_seed, first_seed + seeds):
                rows.append({"id": env_id, **episode(env, factor, seed)})
            got = [r for r in rows if r["id"] == env_id and r["factor"] == factor]
            print(f"{env_id} x{factor:.2f}: carried {sum(r['carried'] for r in got)}/{len(got)}, success "
                  f"{sum(r['success'] for r in got)}, {time.perf_counter() - tic:.0f} s", flush=True)  # fmt: skip
        env.close()
    out.parent.mkdir(parents=True, exist_ok=True)
    with out.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=FIELDS)
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {out}")


def load(path: Path) -> list[dict]:
    with path.open() as fh:
        rows = list(csv.DictReader(fh))
    for r in rows:
        r["object"] = r.get("object") or ""  # text; empty in a file from before the column or on a cylinder id
        for k in (k for k in FIELDS[1:] if k != "object"):
            if k not in r:  # a file from before the column: NaN, so a charge that needs it says so
                r[k] = math.nan
                continue
            r[k] = r[k] == "True" if r[k] in ("True", "False") else float(r[k])
    return rows


def expected(rows: list[dict], price) -> dict[str, dict[float, tuple[float, float]]]:
    """Per id and factor: the mean return under ``price(row)`` (the squeeze term's episode sum) and
    its standard error."""
    out: dict[str, dict[float, tuple[float, float]]] = {}
    for r in rows:
        out.setdefault(r["id"], {}).setdefault(r["factor"], []).append(r["base"] - price(r))
    return {i: {f: (float(np.mean(v)), float(np.std(v) / np.sqrt(len(v)))) for f, v in sorted(d.items())}
            for i, d in out.items()}  # fmt: skip


CHARGES = {
    "v4 (retired): 0.5 F / finger_force": lambda r: 0.5 * r["sum_f"] / 6.0,
    f"v5: {SQUEEZE_WEIGHT_LEAST:g} F / F_least": lambda r: SQUEEZE_WEIGHT_LEAST * r["sum_r"],
    "0.2 F / F_least": lambda r: 0.2 * r["sum_r"],
    "0.4 F / F_least": lambda r: 0.4 * r["sum_r"],
    "0.15 (F / F_least)^2": lambda r: 0.15 * r["sum_r2"],
    "carry only: 0.5 F / F_least": lambda r: 0.5 * r["sum_r_carry"],
    "carry only: 0.75 F / F_least": lambda r: 0.75 * r["sum_r_carry"],
    "carry only: 1.0 F / F_least": lambda r: 1.0 * r["sum_r_carry"],
    "v6, carry only, the margin: 1.0 max(0, F / F_least - 1)": lambda r: 1.0 * r["sum_m_carry"],
}
"""Charges to price the episodes under (the soft grip id's versions; the rigid kinds' are one
lower): the retired v4's, v5's (registration.GRIP_TASK_LEAST), v6's (GRIP_TASK_CARRY),
neighbours of it, and charges on the carry's steps alone (``squeeze_charge_steps="carry"``, on the
squeeze or, with ``squeeze_free=1``, on its margin over the least; they need the ``sum_r_carry`` and
``sum_m_carry`` columns)."""


def plotted_charges(prefixes: str | None) -> list[str]:
    """The charges ``curves --plot`` draws: those of :data:`CHARGES` whose name starts with one of the
    comma-separated ``prefixes`` (in that order), or the first two (the retired v4's and v5's)."""
    if not prefixes:
        return list(CHARGES)[:2]
    out = []
    for prefix in prefixes.split(","):
        found = [n for n in CHARGES if n.startswith(prefix)]
        if len(found) != 1:
            raise ValueError(f"--plot-charges: {prefix!r} names {len(found)} of the charges {list(CHARGES)}")
        out.append(found[0])
    return out


def curves(path: Path, plot: Path | None = None, names: list[str] | None = None) -> None:
    rows = load(path)
    for name, price in CHARGES.items():
        print(f"\n{name}: expected return (+- standard error) per factor of the static least")
        for env_id, d in expected(rows, price).items():
            best = max(d, key=lambda f: d[f][0])
            line = "  ".join(f"{f:.2f}: {m:5.1f}+-{e:.1f}" for f, (m, e) in d.items())
            print(f"  {env_id:30s} peak x{best:.2f} | {line}")
    print("\ncarried through the carry, per factor:")
    for env_id in dict.fromkeys(r["id"] for r in rows):
        got: dict[float, list[bool]] = {}
        for r in rows:
            if r["id"] == env_id:
                got.setdefault(r["factor"], []).append(r["carried"])
        print(f"  {env_id:30s} " + "  ".join(f"{f:.2f}: {sum(v)}/{len(v)}" for f, v in sorted(got.items())))
    by_object(rows)
    if plot is not None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        names = names or plotted_charges(None)
        fig, axes = plt.subplots(1, len(names), figsize=(10, 3.8), sharey=False)
        for ax, name in zip(axes, names, strict=True):
            for env_id, d in expected(rows, CHARGES[name]).items():
                f = np.array(list(d))
                m = np.array([v[0] for v in d.values()])
                e = np.array([v[1] for v in d.values()])
                ax.errorbar(f, m, yerr=e, marker="o", ms=3, capsize=2, label=env_id)
            ax.axvspan(1.2, 1.5, color="0.9", zorder=0)
            ax.set_xlabel("constant squeeze / static least force m g / (2 mu_s)")
            ax.set_title(f"charge {name}", fontsize=9)
        axes[0].set_ylabel("expected return (100 env steps)")
        axes[0].legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(plot, dpi=120)
        print(f"wrote {plot}")


def by_object(rows: list[dict]) -> None:
    """Carried through the carry per object and factor, for the ids whose episodes name an object
    (the object-set ids): which shapes need more than the static least."""
    for env_id in dict.fromkeys(r["id"] for r in rows if r["object"]):
        mine = [r for r in rows if r["id"] == env_id]
        factors = sorted({r["factor"] for r in mine})
        print(f"\ncarried per object, {env_id}:")
        print(f"  {'object':10s} " + " ".join(f"{f:>6.2f}" for f in factors))
        for name in sorted({r["object"] for r in mine}):
            cells = []
            for f in factors:
                v = [r["carried"] for r in mine if r["object"] == name and r["factor"] == f]
                cells.append(f"{sum(v)}/{len(v)}".rjust(6))
            print(f"  {name:10s} " + " ".join(cells))


POLICY_PRICES = ("the id's charge", "the carry's steps", "the carry's margin")
"""How ``policies`` prices each episode: the id's own return; ``w F / F_least`` on the carry's steps
alone (``squeeze_charge_steps="carry"``); ``w max(0, F / F_least - 1)`` on them (and
``squeeze_free=1``: only the margin over the least)."""


def policy_returns(env_id: str, seeds: int, weight_carry: float, first_seed: int = 1000) -> dict[str, dict]:
    """Per policy: success count and (mean, worst) return under each of POLICY_PRICES, the same
    episodes re-priced (the charge does not act on the physics). The policies: the tactile grip
    script the demonstrations come from (softgrasp_env.policies.grip.grip_script), the same script letting go when
    the carry begins (what a learner can do if carrying costs more than it pays), a hand held open
    and one left half closed (action 0)."""
    from softgrasp_env.policies.grip import grip_script

    env = gym.make(env_id)
    base = env.unwrapped
    out = {}
    for name in ("script", "script, let go at the carry", "open", "half closed"):
        prices, wins = {k: [] for k in POLICY_PRICES}, 0
        for seed in range(first_seed, first_seed + seeds):
            obs, _ = env.reset(seed=seed)
            policy = grip_script(env) if name.startswith("script") else None
            static = base.task.mass * 9.81 / (2.0 * base.task.mu_s)
            total = free = carry = margin = 0.0
            done, success = False, False
            while not done:
                in_carry_next = base.task.task.phase(base.scene.steps + base.plan.substeps) is not None
                if policy is not None and not (name.endswith("carry") and in_carry_next):
                    action = policy(obs)
                else:
                    action = np.zeros(env.action_space.shape)
                    action[-1] = 0.0 if name == "half closed" else -1.0
                obs, reward, term, trunc, info = env.step(action)
                done = term or trunc
                in_carry = base.task.task.phase(base.scene.steps) is not None
                ratio = float(np.mean(base._last.force)) / static
                total += reward
                free += reward - float(info["reward_terms"]["squeeze"])
                if in_carry:
                    carry += ratio
                    margin += max(0.0, ratio - 1.0)
                success = success or bool(info["is_success"])
            for key, value in zip(POLICY_PRICES, (total, free - weight_carry * carry, free - weight_carry * margin),
                                  strict=True):  # fmt: skip
                prices[key].append(value)
            wins += success
        out[name] = {"success": wins, **{k: (float(np.mean(v)), float(np.min(v))) for k, v in prices.items()}}
        print(f"{env_id:24s} {name:28s} success {wins}/{seeds}; return (mean / worst) "
              + "; ".join(f"{k} {out[name][k][0]:7.1f} / {out[name][k][1]:7.1f}" for k in POLICY_PRICES), flush=True)
    env.close()
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=("run", "curves", "policies"))
    ap.add_argument("--ids", default="SoftGraspGrip-v6,SoftGraspGripRigidTorsion-v5,SoftGraspGripRigid-v5")
    ap.add_argument("--factors", default="0.8,1.0,1.1,1.2,1.35,1.5,1.75,2.0,2.5,3.0")
    ap.add_argument("--seeds", type=int, default=12)
    ap.add_argument("--first-seed", type=int, default=1000)
    ap.add_argument("--out", "--csv", dest="csv", type=Path, default=OUT)
    ap.add_argument("--plot", type=Path, default=None, help="curves: draw the expected return per factor here")
    ap.add_argument("--plot-charges", default=None,
                    help="curves: the charges drawn, by the start of their names (e.g. v5,v6; default: v4 and v5)")
    ap.add_argument("--weight-carry", type=float, default=1.0, help="policies: the charge's weight on the carry's steps")
    a = ap.parse_args()
    if a.what == "run":
        run(a.ids.split(","), [float(f) for f in a.factors.split(",")], a.seeds, a.csv, a.first_seed)
    elif a.what == "policies":
        for env_id in a.ids.split(","):
            policy_returns(env_id, a.seeds, a.weight_carry, a.first_seed)
    else:
        try:
            names = plotted_charges(a.plot_charges)
        except ValueError as exc:
            ap.error(str(exc))
        curves(a.csv, a.plot, names)


if __name__ == "__main__":
    main()
