"""No tearing: many env steps of random actions, every divergence counted.

Two streams of actions, each over back-to-back episodes (seeded resets, the env's own ranges):
``uniform``, the action space's uniform draw (the arm mostly hovers: velocity actions average
out), and ``noisy-scripted``, the scripted grasp with Gaussian noise (sigma 0.5 per entry, clipped)
so that the fingers press on the cylinder, its rim and the ground thousands of times: the states
where the tissue has torn before (the snag over the rim, ~1 in 10^4-2*10^4 steps).

    PYTHONPATH=. python benchmarks/random_soak.py                       # 10^5 steps per stream
    PYTHONPATH=. python benchmarks/random_soak.py --steps 20000 --env SoftGraspRigidTorsion-v3
    PYTHONPATH=. python benchmarks/random_soak.py --env SoftGrasp-v4 --preset converged --threads 2 \
        --steps 10000 --seed 3          # one chunk of a long soak: seeds give disjoint episodes

Prints, per stream: steps, episodes, divergences (with the seed, step and the reason), the
largest tissue deviation from its core seen (the tear detector's quantity), steps/s.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.registration import make_as as make


def soak(env_id: str, steps: int, stream: str, *, seed: int = 0, **kwargs) -> dict:
    """``steps`` env steps of ``stream`` actions on ``env_id``; the divergences and the figures."""
    env = make(env_id, **kwargs)
    scripted = ScriptedGraspPolicy.for_env(env)
    rng = np.random.default_rng(seed)
    env.action_space.seed(seed)
    divergences, episodes, deviation = [], 0, 0.0
    episode_seed = seed * 1_000_000
    obs, _ = env.reset(seed=episode_seed)
    tic = time.perf_counter()
    k_episode = 0
    try:
        for _ in range(steps):
            if stream == "uniform":
                action = env.action_space.sample()
            else:
                action = np.clip(scripted(obs) + rng.normal(0.0, 0.5, 4), -1.0, 1.0).astype(np.float32)
            obs, _, term, trunc, info = env.step(action)
            k_episode += 1
            world = env.unwrapped.scene.world  # the scene is rebuilt at every reset
            if len(world.model.particle_radii):
                deviation = max(deviation, float(world.tissue_deviation()))
            if info["diverged"]:
                divergences.append((episode_seed, k_episode, info["divergence"]))
            if term or trunc:
                episodes += 1
                episode_seed += 1
                k_episode = 0
                obs, _ = env.reset(seed=episode_seed)
    finally:
        env.close()
    return {"steps": steps, "episodes": episodes, "divergences": divergences, "max_deviation": deviation,
            "steps_per_s": steps / (time.perf_counter() - tic)}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default="SoftGrasp-v5")
    parser.add_argument("--steps", type=int, default=100_000, help="per stream")
    parser.add_argument("--streams", default="uniform,noisy-scripted")
    parser.add_argument("--coupling", default=None, help="the tissue's coupling (default: the preset's)")
    parser.add_argument("--friction-law", default=None, choices=["patch", "contact"],
                        help="the tissue's friction law (default: the preset's, patch)")
    parser.add_argument("--preset", default=None, help="the tissue's resolution preset, e.g. converged")
    parser.add_argument("--threads", type=int, default=None, help="the tissue solver's threads (SimConfig.threads)")
    parser.add_argument("--min-rows", type=int, default=None, help="the fewest particle rows across a finger face "
                        "(gym.make's tissue_min_rows)")
    parser.add_argument("--seed", type=int, default=0,
                        help="episodes are seeded from seed * 10^6 on: chunks with different seeds never repeat one")
    ns = parser.parse_args(argv)
    kwargs = {} if ns.friction_law is None else {"friction_law": ns.friction_law}
    if ns.preset is not None:
        kwargs["preset"] = ns.preset
    if ns.threads is not None:
        kwargs["threads"] = ns.threads
    if ns.min_rows is not None:
        kwargs["tissue_min_rows"] = ns.min_rows
    if ns.coupling:
        from dataclasses import replace

        from softgrasp_env import presets

        kwargs["sim"] = replace(presets.scene_config("default").sim, coupling=ns.coupling)
    failed = 0
    for stream in ns.streams.split(","):
        r = soak(ns.env, ns.steps, stream, seed=ns.seed, **kwargs)
        label = "".join([f", {ns.preset}" if ns.preset else "", f", min rows {ns.min_rows}" if ns.min_rows else ""])
        print(f"{ns.env} {stream} (seed {ns.seed}{label}): {r['steps']} steps, "
              f"{r['episodes']} episodes, {len(r['divergences'])} divergences, largest tissue deviation "
              f"{r['max_deviation'] * 1e3:.2f} mm, {r['steps_per_s']:.1f} env steps/s (1 process, "
              f"{ns.threads or 1} solver thread(s))", flush=True)  # fmt: skip
        for seed, step, reason in r["divergences"]:
            print(f"    episode seed {seed}, step {step}: {reason}")
        failed += len(r["divergences"])
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
