"""Train a stable-baselines3 agent on a SoftGrasp environment.

    python train.py --env SoftGrasp-v0 --algo sac --timesteps 100000
    python train.py --env SoftGraspGoal-v0               # HER + SAC by default for the goal env
    python train.py --env SoftGraspRigid-v0 --algo ppo --n-envs 2

Writes ``<out>/<env>_<algo>_<seed>/``: ``model.zip``, ``vecnormalize.pkl`` (observation statistics,
except for HER), ``run.json`` (the arguments), ``monitor*.csv`` (per episode: return, length,
is_success) and ``progress.csv`` (per evaluation: timesteps, success rate, mean return, mean final
lift, wall time). Evaluate a saved model with ``python -m agents.evaluate --policy <dir>/model.zip``.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecNormalize

import softgrasp_env
from agents.baselines import ALGOS, default_algo, make_model
from agents.evaluate import evaluate


class EvalProgress(BaseCallback):
    """Every ``every`` timesteps: success rate of the deterministic policy on ``episodes`` fixed
    seeds of a separate env, appended to progress.csv."""

    def __init__(self, env_id: str, every: int, episodes: int, path: Path, norm: VecNormalize | None) -> None:
        super().__init__()
        self.env = gym.make(env_id)
        self.every, self.episodes, self.path, self.norm = every, episodes, path, norm
        self.next_at = every
        self.start = time.perf_counter()
        self.rows: list[dict] = []

    def _policy(self, obs):
        if self.norm is not None:
            obs = self.norm.normalize_obs(obs)
        return self.model.predict(obs, deterministic=True)[0]

    def evaluate_now(self) -> dict:
        ev = evaluate(self.env, self._policy, episodes=self.episodes, seed=10_000)
        if self.rows and self.rows[-1]["timesteps"] == self.num_timesteps:
            self.rows.pop()  # the final evaluation supersedes one taken at the same step count
        row = {"timesteps": self.num_timesteps, "success_rate": ev.success_rate, "mean_return": ev.mean_return,
               "mean_final_lift": ev.mean_final_lift, "diverged": ev.diverged,
               "wall_seconds": time.perf_counter() - self.start}  # fmt: skip
        self.rows.append(row)
        with open(self.path, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(row))
            w.writeheader()
            w.writerows(self.rows)
        print(f"[{row['timesteps']:>8d} steps, {row['wall_seconds']:7.0f} s] success {ev.success_rate:.0%}, "
              f"return {ev.mean_return:.2f}, final lift {ev.mean_final_lift * 100:.2f} cm", flush=True)  # fmt: skip
        return row

    def _on_step(self) -> bool:
        if self.num_timesteps >= self.next_at:
            self.next_at += self.every
            self.evaluate_now()
        return True

    def _on_training_end(self) -> None:
        self.env.close()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python train.py", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    parser.add_argument("--env", default="SoftGrasp-v0", choices=softgrasp_env.ENV_IDS)
    parser.add_argument("--algo", choices=ALGOS, default=None, help="default: her-sac for the goal env, else sac")
    parser.add_argument("--timesteps", type=int, default=100_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--n-envs", type=int, default=1, help="parallel envs (subprocesses when > 1)")
    parser.add_argument("--eval-every", type=int, default=10_000, help="timesteps between evaluations")
    parser.add_argument("--eval-episodes", type=int, default=10)
    parser.add_argument("--learning-starts", type=int, default=None, help="override the preset (off-policy algos)")
    parser.add_argument("--out", type=Path, default=Path("runs"))
    ns = parser.parse_args(argv)
    algo = ns.algo or default_algo(ns.env)
    goal = ns.env == "SoftGraspGoal-v0"
    if algo == "her-sac" and not goal:
        parser.error("--algo her-sac needs the goal-conditioned env (SoftGraspGoal-v0)")
    for name in ("timesteps", "n_envs", "eval_every", "eval_episodes"):
        if getattr(ns, name) < 1:
            parser.error(f"--{name.replace('_', '-')} must be >= 1, got {getattr(ns, name)}")
    if algo == "her-sac" and ns.n_envs != 1:
        parser.error("--algo her-sac runs with --n-envs 1")

    run = ns.out / f"{ns.env}_{algo}_{ns.seed}"
    run.mkdir(parents=True, exist_ok=True)
    (run / "run.json").write_text(json.dumps({**vars(ns), "out": str(ns.out), "algo": algo,
                                              "softgrasp_env": softgrasp_env.__version__}, indent=2))  # fmt: skip
    vec_cls = SubprocVecEnv if ns.n_envs > 1 else DummyVecEnv
    venv = make_vec_env(ns.env, n_envs=ns.n_envs, seed=ns.seed, vec_env_cls=vec_cls, monitor_dir=str(run),
                        monitor_kwargs={"info_keywords": ("is_success",)})  # fmt: skip
    # Positions (cm), velocities and forces (N) differ by orders of magnitude: normalise the
    # observations. HER relabels goals inside its buffer, so the goal env runs unnormalised.
    norm = None
    if not goal:
        venv = norm = VecNormalize(venv, norm_obs=True, norm_reward=False)
    overrides = {} if ns.learning_starts is None or algo == "ppo" else {"learning_starts": ns.learning_starts}
    model = make_model(algo, venv, seed=ns.seed, **overrides)
    progress = EvalProgress(ns.env, ns.eval_every, ns.eval_episodes, run / "progress.csv", norm)
    tic = time.perf_counter()
    model.learn(total_timesteps=ns.timesteps, callback=progress)
    seconds = time.perf_counter() - tic
    model.save(run / "model.zip")
    if norm is not None:
        norm.save(str(run / "vecnormalize.pkl"))
    progress.env = gym.make(ns.env)
    final = progress.evaluate_now()
    progress.env.close()
    venv.close()
    print(f"trained {ns.timesteps} steps in {seconds:.0f} s ({ns.timesteps / seconds:.0f} steps/s); "
          f"final success {final['success_rate']:.0%}; saved to {run}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
