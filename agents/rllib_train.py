"""Train with Ray RLlib (its new API stack: PPO or SAC) on any SoftGrasp id, on this machine or a
Ray cluster; Ray Tune runs several seeds or a small grid as parallel trials.

    scripts/setup.sh --rllib                      # .venv-rllib: RLlib pins its own gymnasium
    .venv-rllib/bin/python -m agents.rllib_train --env SoftGrasp-v5 --timesteps 200000 --num-env-runners 2
    .venv-rllib/bin/python -m agents.rllib_train --seeds 0 1 2 --grid lr=1e-4,3e-4   # 6 trials
    # a cluster: `ray start --head --port 6379` on one node, `ray start --address HEAD:6379` on the others, then
    .venv-rllib/bin/python -m agents.rllib_train --address HEAD:6379 --num-env-runners 62 --timesteps 10000000
    .venv-rllib/bin/python -m agents.evaluate --policy runs-rllib/SoftGrasp-v5_rllib-ppo/seed_0   # same table as SB3

Every trial's directory gets a ``run.json`` (``"backend": "rllib"``: env, env kwargs, algo, seed,
hyperparameters, steps, wall time, the command, the checkpoint) beside Tune's own files
(``progress.csv``, ``result.json``, ``checkpoint_<N>/``); ``agents.evaluate`` loads it as it loads an
SB3 run. The success rate over the last 100 episodes is a reported metric
(``env_runners/success_rate``), as is the share of diverged episodes. An env runner that dies is
restarted (``restart_failed_env_runners``) and training goes on.

RLlib's env runners do not read the gymnasium registry: each id is registered with
``ray.tune.registry.register_env`` under its own name, and the creator imports softgrasp_env in the
worker. Each env runner is one process with one env (or ``--num-envs-per-env-runner``) and one
numba/torch thread; each trial's learner ``--torch-threads`` (default 1, agents/threads.py).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import softgrasp_env
from agents.cards import quote_arg
from agents.cli import kwargs_dict, parse_kwarg
from agents.threads import DEFAULT_TORCH_THREADS, child_environment, threads_error

ALGOS = ("ppo", "sac")

PRESETS: dict[str, dict[str, Any]] = {
    # The SB3 presets' counterparts (agents/baselines.py): same network, discount and learning rate;
    # PPO's rollout of 1,024 steps per update, 10 epochs of minibatches of 256.
    "ppo": {"gamma": 0.98, "lambda_": 0.95, "lr": 3e-4, "train_batch_size_per_learner": 1024, "minibatch_size": 256,
            "num_epochs": 10, "fcnet_hiddens": [64, 64]},
    "sac": {"gamma": 0.98, "tau": 0.02, "actor_lr": 1e-3, "critic_lr": 1e-3, "alpha_lr": 1e-3,
            "train_batch_size_per_learner": 256, "num_steps_sampled_before_learning_starts": 1000,
            "replay_capacity": 300_000, "fcnet_hiddens": [128, 128]},
}
"""Hyperparameters per algo; ``--grid`` and ``--algo-kwargs`` override training() arguments."""

SUCCESS_METRIC = "env_runners/success_rate"
STEPS_METRIC = "num_env_steps_sampled_lifetime"


def env_name(env_id: str) -> str:
    """The name an id is registered under in Ray's registry (the id itself)."""
    return env_id


def _make_env(config: dict[str, Any]):
    """RLlib's env creator, run in each env runner: one numba thread (set before numba loads, as
    train.py does for its subprocesses), the id made through gymnasium with its time limit."""
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    if "torch" in sys.modules:  # the env runner's own module (RLlib's torch policy): one thread
        sys.modules["torch"].set_num_threads(1)
    import gymnasium as gym

    import softgrasp_env  # noqa: F401  (in the worker: registers the ids)

    config = dict(config)
    env_id = config.pop("_env_id")
    return gym.make(env_id, **config)


def register(env_id: str) -> None:
    """Register ``env_id`` with Ray's registry (RLlib's workers look there, not in gymnasium's).
    Call it after ``ray.init``: Ray's registry, asked for its job id before, starts Ray itself."""
    if env_id not in softgrasp_env.ENV_IDS:
        raise ValueError(f"env must be one of {softgrasp_env.ENV_IDS}, got {env_id!r}")
    import ray
    from ray.tune import registry

    # Ray's registry keys its entries by the job id it saw first in this process and keeps it: a
    # later ray.init (a second job from the same process: a notebook, a test) would register under
    # the old job's key and the new job's workers would not find the env (they fell back to
    # gym.make with our env_config). Re-key for the current job. (Ray 2.60.0.)
    if ray.is_initialized() and registry._global_registry._prefix not in (None, ray.get_runtime_context().get_job_id()):
        registry._global_registry._prefix = None
    registry.register_env(env_name(env_id), _make_env)


def _success_callback():
    from ray.rllib.callbacks.callbacks import RLlibCallback

    class SuccessMetrics(RLlibCallback):
        """Logs, per finished episode, whether its last step had ``info["is_success"]`` and
        whether it diverged; RLlib reports their means over the last 100 episodes."""

        def on_episode_end(self, *, episode, metrics_logger=None, **kwargs) -> None:
            info = episode.get_infos(-1) or {}
            metrics_logger.log_value("success_rate", float(bool(info.get("is_success", False))), reduce="mean",
                                     window=100)  # fmt: skip
            metrics_logger.log_value("diverged_rate", float(bool(info.get("diverged", False))), reduce="mean",
                                     window=100)  # fmt: skip

    return SuccessMetrics


def make_config(env_id: str, *, algo: str = "ppo", seed: int = 0, env_kwargs: dict[str, Any] | None = None,
                num_env_runners: int = 2, num_envs_per_env_runner: int = 1, num_cpus_per_env_runner: float = 1.0,
                training: dict[str, Any] | None = None):  # fmt: skip
    """The RLlib ``AlgorithmConfig`` for ``algo`` on ``env_id``: the preset, ``training`` on top,
    observations normalised by a running mean/std filter (as SB3's VecNormalize), failed env
    runners restarted. The id must be :func:`register`-ed (after ``ray.init``) before an
    algorithm is built from it."""
    if algo not in ALGOS:
        raise ValueError(f"algo must be one of {ALGOS}, got {algo!r}")
    if env_id.startswith("SoftGraspGoal"):
        raise ValueError(f"{env_id} has dict observations for HER; RLlib training here takes the vector ids")
    if not isinstance(num_cpus_per_env_runner, (int, float)) or not 0.0 < num_cpus_per_env_runner <= 64:
        raise ValueError(f"num_cpus_per_env_runner must be in (0, 64], got {num_cpus_per_env_runner!r}")
    for name, value in (("num_env_runners", num_env_runners), ("num_envs_per_env_runner", num_envs_per_env_runner)):
        if isinstance(value, bool) or not isinstance(value, int) or value < (0 if name == "num_env_runners" else 1):
            raise ValueError(f"{name} must be an integer >= {0 if name == 'num_env_runners' else 1}, got {value!r}")
    from ray.rllib.core.rl_module.default_model_config import DefaultModelConfig

    preset = {**PRESETS[algo], **(training or {})}
    hidden = preset.pop("fcnet_hiddens")
    if algo == "ppo":
        from ray.rllib.algorithms.ppo import PPOConfig as Config
    else:
        from ray.rllib.algorithms.sac import SACConfig as Config
    if algo == "sac":
        # Uniform replay, as SB3's SAC (RLlib's default is prioritised).
        preset["replay_buffer_config"] = {"type": "EpisodeReplayBuffer", "capacity": preset.pop("replay_capacity")}
    config = (
        Config()
        .environment(env_name(env_id), env_config={"_env_id": env_id, **(env_kwargs or {})})
        .env_runners(num_env_runners=num_env_runners, num_envs_per_env_runner=num_envs_per_env_runner,
                     num_cpus_per_env_runner=num_cpus_per_env_runner, env_to_module_connector=_mean_std_filter,
                     rollout_fragment_length="auto")
        .training(**preset)
        # SB3's MlpPolicy: tanh for PPO, relu for SAC, separate policy and value networks.
        .rl_module(model_config=DefaultModelConfig(fcnet_hiddens=hidden, fcnet_activation="tanh" if algo == "ppo" else "relu",
                                                   vf_share_layers=False))
        .callbacks(_success_callback())
        .fault_tolerance(restart_failed_env_runners=True)
        .reporting(metrics_num_episodes_for_smoothing=100)
        .debugging(seed=seed)
    )
    return config


def _mean_std_filter(env=None, spaces=None, device=None):
    from ray.rllib.connectors.env_to_module import MeanStdFilter

    return MeanStdFilter()


def build_algorithm(env_id: str, **kwargs: Any):
    """``make_config(env_id, **kwargs).build_algo()`` with the id registered (Ray must be
    initialised: registering before would make Ray connect on its own)."""
    import ray

    if not ray.is_initialized():
        raise RuntimeError("build_algorithm needs Ray initialised (ray.init) first")
    register(env_id)
    return make_config(env_id, **kwargs).build_algo()


def _parse_grid(parser: argparse.ArgumentParser, items: list[str] | None) -> dict[str, list[Any]]:
    grid: dict[str, list[Any]] = {}
    for item in items or []:
        key, sep, values = item.partition("=")
        if not sep or not key or not values:
            parser.error(f"--grid takes KEY=V1,V2,..., got {item!r}")
        try:
            grid[key] = [parse_kwarg(f"{key}={v}")[1] for v in values.split(",")]
        except argparse.ArgumentTypeError as exc:
            parser.error(f"--grid: {exc}")
    return grid


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m agents.rllib_train", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    vector_ids = [i for i in softgrasp_env.ENV_IDS if not i.startswith("SoftGraspGoal")]
    parser.add_argument("--env", default="SoftGrasp-v5", choices=vector_ids)
    parser.add_argument("--env-kwargs", nargs="+", type=parse_kwarg, default=None, metavar="KEY=VALUE",
                        help="passed to gym.make")  # fmt: skip
    parser.add_argument("--algo", choices=ALGOS, default="ppo")
    parser.add_argument("--algo-kwargs", nargs="+", type=parse_kwarg, default=None, metavar="KEY=VALUE",
                        help="AlgorithmConfig.training() arguments over the preset, e.g. lr=1e-4")  # fmt: skip
    parser.add_argument("--timesteps", type=int, default=200_000, help="env steps to sample per trial")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0], help="one Tune trial per seed (x grid points)")
    parser.add_argument("--grid", nargs="+", default=None, metavar="KEY=V1,V2",
                        help="a hyperparameter grid: training() arguments, every combination a trial")  # fmt: skip
    parser.add_argument("--num-env-runners", type=int, default=2, help="sampling processes per trial (cluster-wide)")
    parser.add_argument("--num-envs-per-env-runner", type=int, default=1)
    parser.add_argument("--num-cpus-per-env-runner", type=float, default=1.0,
                        help="CPUs Ray reserves per env runner; 0.5 fits 2 runners and the learner on 2 cores")  # fmt: skip
    parser.add_argument("--address", default=None,
                        help="join a running Ray cluster (HEAD:6379, or 'auto'); default: start Ray on this machine")  # fmt: skip
    parser.add_argument("--num-cpus", type=int, default=None, help="CPUs of the local Ray instance (not with --address)")
    parser.add_argument("--max-concurrent-trials", type=int, default=None)
    parser.add_argument("--checkpoint-every", type=int, default=10, help="iterations between checkpoints (and one at the end)")
    parser.add_argument("--torch-threads", type=int, default=DEFAULT_TORCH_THREADS, metavar="N",
                        help="torch threads of each trial's learner (default 1; env runners take one; agents/threads.py)")
    parser.add_argument("--out", type=Path, default=Path("runs-rllib"))
    parser.add_argument("--name", default=None, help="the experiment's directory under --out; default <env>_rllib-<algo>")
    ns = parser.parse_args(argv)
    if ns.timesteps < 1:
        parser.error(f"--timesteps must be >= 1, got {ns.timesteps}")
    if ns.checkpoint_every < 1:
        parser.error(f"--checkpoint-every must be >= 1, got {ns.checkpoint_every}")
    problem = threads_error(ns.torch_threads)
    if problem:
        parser.error(f"--torch-threads: {problem}")
    if ns.address is not None and ns.num_cpus is not None:
        parser.error("--num-cpus sizes a local Ray instance; a cluster joined with --address has its own CPUs")
    env_kwargs = kwargs_dict(parser, "--env-kwargs", ns.env_kwargs)
    training = kwargs_dict(parser, "--algo-kwargs", ns.algo_kwargs)
    grid = _parse_grid(parser, ns.grid)
    ns.name = ns.name or f"{ns.env}_rllib-{ns.algo}"
    if (ns.out / ns.name).exists():
        parser.error(f"{str(ns.out / ns.name)!r} exists: give another --out or --name (Tune would mix the trials)")
    unknown = set(training) | set(grid)
    try:
        import gymnasium as gym

        gym.make(ns.env, **env_kwargs).close()  # bad env kwargs fail here, named, not in a worker
        config = make_config(ns.env, algo=ns.algo, seed=ns.seeds[0], env_kwargs=env_kwargs,
                             num_env_runners=ns.num_env_runners, num_envs_per_env_runner=ns.num_envs_per_env_runner,
                             num_cpus_per_env_runner=ns.num_cpus_per_env_runner, training=training)  # fmt: skip
        strangers = sorted(k for k in unknown if not hasattr(config, k))
        if strangers:
            raise ValueError(f"not an RLlib {ns.algo.upper()} training() argument: {strangers}")
    except (ValueError, TypeError) as exc:
        parser.error(str(exc))
    return _run_tune(ns, config, env_kwargs, training, grid, argv)


def _run_tune(ns, config, env_kwargs, training, grid, argv) -> int:
    import ray
    from ray import tune

    # Every Ray worker of this job, on every node: the trial's learner ns.torch_threads torch
    # threads, numba one (agents/threads.py); the env runners set one torch thread themselves.
    runtime_env = {"env_vars": child_environment(ns.torch_threads)}
    if ns.address is not None:
        ray.init(address=ns.address, include_dashboard=False, runtime_env=runtime_env)
    else:
        ray.init(num_cpus=ns.num_cpus, include_dashboard=False, runtime_env=runtime_env)
    try:
        # One trial takes a CPU for its learner and one per env runner as asked; a trial that does
        # not fit would wait in Tune's queue for ever, so say it now. (An autoscaling cluster
        # would grow: there, this counts only the nodes already up.)
        need = 1.0 + ns.num_env_runners * ns.num_cpus_per_env_runner
        have = ray.cluster_resources().get("CPU", 0.0)
        if need > have + 1e-9:
            print(f"error: one trial needs {need:g} CPUs (1 for the learner + {ns.num_env_runners} env runners x "
                  f"{ns.num_cpus_per_env_runner:g}), the Ray cluster has {have:g}: use fewer --num-env-runners, "
                  f"a smaller --num-cpus-per-env-runner or a bigger cluster", file=sys.stderr)  # fmt: skip
            return 2
        register(ns.env)
        param_space = config.copy(copy_frozen=False)
        param_space.debugging(seed=tune.grid_search(ns.seeds) if len(ns.seeds) > 1 else ns.seeds[0])
        if grid:
            param_space.training(**{k: tune.grid_search(v) for k, v in grid.items()})
        name = ns.name
        ns.out.mkdir(parents=True, exist_ok=True)
        start = time.time()
        tuner = tune.Tuner(
            ns.algo.upper(),
            param_space=param_space,
            tune_config=tune.TuneConfig(max_concurrent_trials=ns.max_concurrent_trials,
                                        trial_dirname_creator=lambda trial: _trial_dirname(trial, sorted(grid))),
            run_config=tune.RunConfig(
                name=name,
                storage_path=str(ns.out.resolve()),
                stop={STEPS_METRIC: ns.timesteps},
                checkpoint_config=tune.CheckpointConfig(checkpoint_frequency=ns.checkpoint_every, checkpoint_at_end=True),
                verbose=1,
            ),
        )
        results = tuner.fit()
        wall = time.time() - start
        failed = 0
        for result in results:
            if result.error is not None or result.checkpoint is None:
                failed += 1
                print(f"trial {result.path} failed: {result.error}", file=sys.stderr)
                continue
            trial_config = result.config or {}
            meta = {
                "backend": "rllib",
                "env": ns.env,
                "env_kwargs": env_kwargs,
                "algo": ns.algo,
                "seed": trial_config.get("seed", ns.seeds[0]),
                "timesteps": ns.timesteps,
                "timesteps_trained": int(result.metrics.get(STEPS_METRIC, 0)),
                "train_seconds": result.metrics.get("time_total_s"),
                "wall_seconds_all_trials": wall,
                "num_env_runners": ns.num_env_runners,
                "num_envs_per_env_runner": ns.num_envs_per_env_runner,
                "hyperparameters": {**PRESETS[ns.algo], **training, **{k: trial_config.get(k) for k in grid}},
                "success_rate": result.metrics.get("env_runners", {}).get("success_rate"),
                "checkpoint": os.path.relpath(result.checkpoint.path, result.path),
                "command": " ".join(["python", "-m", "agents.rllib_train",
                                     *map(quote_arg, sys.argv[1:] if argv is None else argv)]),
                "ray": ray.__version__,
                "softgrasp_env": softgrasp_env.__version__,
            }
            Path(result.path, "run.json").write_text(json.dumps(meta, indent=2, default=str))
            print(f"{result.path}: {meta['timesteps_trained']} steps, success {meta['success_rate']}, "
                  f"checkpoint {meta['checkpoint']}")  # fmt: skip
        return 1 if failed else 0
    finally:
        ray.shutdown()


def _trial_dirname(trial, grid_keys: list[str]) -> str:
    """``seed_<s>`` and the grid point, e.g. ``seed_0_lr_0.0001``: unique within an experiment."""
    cfg = trial.config
    return "_".join([f"seed_{cfg.get('seed')}", *(f"{k}_{cfg.get(k)}" for k in grid_keys)])


if __name__ == "__main__":
    sys.exit(main())
