"""Minari datasets (Farama's standard for offline RL) of recorded episodes: the scripted grasp and
the best shipped learned baseline on the soft id with one (SoftGrasp-v4) and the rigid twin and
the torsional peer (SoftGraspRigid-v3, SoftGraspRigidTorsion-v3): SAC models. An id with no shipped
baseline has no learned dataset (asking for one is an error). (The v2 ids' datasets were retired
with them, release 0.6.0 has them; SoftGrasp-v3's, release 0.8.0.)

    .venv/bin/python scripts/make_dataset.py                                   # 100 episodes each
    .venv/bin/python scripts/make_dataset.py --episodes 3 --out datasets/minari --force   # the shipped sample
    MINARI_DATASETS_PATH=datasets/minari .venv/bin/python -c \\
        "import minari; print(minari.load_dataset('softgrasp/SoftGrasp-v4/scripted-v0'))"

Writes ``softgrasp/<env id>/scripted-v0`` and ``softgrasp/<env id>/learned-v0`` (the baseline with
the best success rate on its card; its name is the dataset's algorithm) under ``--out`` (default:
minari's own folder, ``MINARI_DATASETS_PATH`` or ``~/.minari/datasets``). Each step keeps the
observation, action, reward, termination and truncation, and from ``info``: ``is_success``,
``held``, ``carrying``, ``lift_height``, ``diverged``. Episodes use seeds ``--seed``,
``--seed + 1``, ... (default 0: apart from the cards' evaluation seeds 1000-1099). Needs the
``[offline]`` extra (minari with h5py); the learned policies need ``[train]``.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import softgrasp_env
from softgrasp_env.policies import ScriptedGraspPolicy, baseline_card, list_baselines
from softgrasp_env.policies.baselines import best_per_env

ENVS = ("SoftGrasp-v4", "SoftGraspRigid-v3", "SoftGraspRigidTorsion-v3")
POLICIES = ("scripted", "learned")
INFO_KEYS = {"is_success": bool, "held": bool, "carrying": bool, "lift_height": float, "diverged": bool}
"""What each step keeps of ``info`` (Minari needs the same keys and types at every step; the rest
of info varies: reward terms only after a step, the divergence reason only when one happens)."""


def best_baseline(env_id: str) -> str:
    """The shipped baseline of ``env_id`` with the best success rate on its card (ties: the last
    name; softgrasp_env.policies.baselines.best_per_env, what the wheel ships)."""
    names = list_baselines(env=env_id)
    if not names:
        raise ValueError(f"no shipped baseline for {env_id!r}")
    return best_per_env([baseline_card(n) for n in names])[env_id]


def run_episode(env: gym.Env, act, seed: int):
    """One episode as Minari's EpisodeBuffer (the whole episode at once: minari's own step-by-step
    DataCollector needs jax, hundreds of MB, for its tree maps) and whether it succeeded."""
    from minari.data_collector import EpisodeBuffer

    obs, info = env.reset(seed=seed)
    observations, infos = [obs], [info]
    actions, rewards, terminations, truncations = [], [], [], []
    done = False
    while not done:
        action = np.asarray(act(obs), dtype=np.float32)
        obs, reward, terminated, truncated, info = env.step(action)
        done = terminated or truncated
        observations.append(obs)
        infos.append(info)
        actions.append(action)
        rewards.append(float(reward))
        terminations.append(bool(terminated))
        truncations.append(bool(truncated))
    kept = {k: np.array([t(i.get(k, t())) for i in infos]) for k, t in INFO_KEYS.items()}
    buffer = EpisodeBuffer(seed=seed, observations=np.stack(observations), actions=np.stack(actions), rewards=rewards,
                           terminations=terminations, truncations=truncations, infos=kept)  # fmt: skip
    return buffer, bool(info["is_success"])


def record(env_id: str, policy_name: str, *, episodes: int, seed: int, force: bool) -> Any:
    """Record ``episodes`` episodes of ``policy_name`` on ``env_id`` as a Minari dataset."""
    import minari

    dataset_id = f"softgrasp/{env_id}/{policy_name}-v0"
    if dataset_id in minari.list_local_datasets():
        if not force:
            raise SystemExit(f"make_dataset.py: error: {dataset_id!r} exists; --force replaces it")
        minari.delete_dataset(dataset_id)
    env = gym.make(env_id)
    if policy_name == "scripted":
        act, algorithm = ScriptedGraspPolicy.for_env(env), "ScriptedGraspPolicy (softgrasp_env.policies)"
        about = "the scripted grasp, which reads only the observation"
    else:
        from softgrasp_env.policies import load_baseline

        name = best_baseline(env_id)
        act, algorithm = load_baseline(name).policy, f"{name} (softgrasp_env.policies.load_baseline, deterministic)"
        rate = baseline_card(name)["evaluation"]["success_rate"]
        about = f"the shipped baseline {name} ({rate:.0%} success on its card), deterministic"
    buffers, successes = [], 0
    try:
        for k in range(episodes):
            buffer, success = run_episode(env, act, seed + k)
            buffers.append(buffer)
            successes += success
        dataset = minari.create_dataset_from_buffers(
            dataset_id=dataset_id,
            buffer=buffers,
            env=env,
            eval_env=env_id,
            algorithm_name=algorithm,
            author="softgrasp maintainers",
            code_permalink="scripts/make_dataset.py in the softgrasp repository",
            description=(f"{episodes} episodes of {about} on {env_id} (softgrasp-env {softgrasp_env.__version__}), "
                         f"seeds {seed}-{seed + episodes - 1}; {successes} succeeded. infos: {', '.join(INFO_KEYS)}."),
            data_format="hdf5",
            requirements=[f"softgrasp-env=={softgrasp_env.__version__}"],
        )  # fmt: skip
    finally:
        env.close()
    print(f"{dataset_id}: {episodes} episodes, {dataset.total_steps} steps, {successes} successes")
    return dataset


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python scripts/make_dataset.py", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    parser.add_argument("--envs", nargs="+", default=list(ENVS), choices=softgrasp_env.ENV_IDS)
    parser.add_argument("--policies", nargs="+", default=list(POLICIES), choices=POLICIES)
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=None, help="the datasets folder (MINARI_DATASETS_PATH)")
    parser.add_argument("--force", action="store_true", help="replace datasets that exist")
    ns = parser.parse_args(argv)
    if ns.episodes < 1:
        parser.error(f"--episodes must be >= 1, got {ns.episodes}")
    try:
        import minari  # noqa: F401
    except ImportError:
        parser.error("needs minari: pip install 'softgrasp-env[offline]'")
    if ns.out is not None:
        ns.out.mkdir(parents=True, exist_ok=True)
        os.environ["MINARI_DATASETS_PATH"] = str(ns.out.resolve())
    jobs = []
    for env_id in ns.envs:
        for policy in ns.policies:
            if policy == "learned" and not list_baselines(env=env_id):
                if "--policies" in (argv if argv is not None else sys.argv):  # asked for by name
                    have = sorted({n.rsplit("_", 2)[0] for n in list_baselines()})
                    parser.error(f"no shipped baseline for {env_id!r}, so no learned dataset; ids with one: {', '.join(have)}")
                print(f"{env_id}: no shipped baseline, no learned dataset")
                continue
            jobs.append((env_id, policy))
    for env_id, policy in jobs:
        record(env_id, policy, episodes=ns.episodes, seed=ns.seed, force=ns.force)
    return 0


if __name__ == "__main__":
    sys.exit(main())
