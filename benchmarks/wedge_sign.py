"""Why a policy holds or loses the cylinder with rigid fingers: success split by the jaw wedge's
size and sign, and how high above the cylinder's centre the fingers close, over the 100 seeded
episodes of the model cards (seeds 1000-1099).

    PYTHONPATH=. python benchmarks/wedge_sign.py                                 # scripted and every shipped rigid model
    PYTHONPATH=. python benchmarks/wedge_sign.py --env SoftGrasp-v3 --policy scripted agents/trained/SoftGrasp-v3_sac_0

A positive wedge opens the gap at the top (the faces meet the cylinder with their lower edges),
a negative one at the bottom. The grip height is the grip point above the cylinder's centre at
the first step both fingers press with more than 0.5 N. With the carry test it also counts the
episodes whose cylinder was held when the carry test began (``info["held"]`` at its first step)
and how many of those still held it at the end.
"""

from __future__ import annotations

import argparse
import sys

import gymnasium as gym
import numpy as np

import softgrasp_env  # noqa: F401
from agents import cards
from agents.evaluate import load_policy

BINS = ((0.0, 0.025), (0.025, 0.075), (0.075, 0.151))


def episodes(env_id: str, spec: str, seeds: range) -> np.ndarray:
    """Per episode: wedge, success, grip height above the cylinder centre at contact [m] (NaN if
    never), held when the carry began (NaN without a carry test)."""
    env = gym.make(env_id)
    try:
        policy = load_policy(spec, env)
        rows = []
        for seed in seeds:
            obs, _ = env.reset(seed=seed)
            wedge, grip, info = env.unwrapped.scene.config.jaw_wedge, np.nan, {}
            at_carry = 0.0 if env.unwrapped.carry else np.nan
            for _ in range(100):
                obs, _, term, trunc, info = env.step(policy(obs))
                if np.isnan(grip) and obs[19] > 0.5 and obs[20] > 0.5:
                    grip = -float(obs[9])
                if info["carrying"] and at_carry == 0.0:
                    at_carry = 1.0 if info["held"] else -1.0  # -1: the carry began, not held
                if term or trunc:
                    break
            rows.append((wedge, float(info["is_success"]), grip, float(at_carry > 0) if not np.isnan(at_carry) else np.nan))
        return np.array(rows)
    finally:
        env.close()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default="SoftGraspRigid-v3")
    parser.add_argument("--policy", nargs="+", default=None,
                        help="'scripted' and/or runs; default: scripted and every shipped model of --env")  # fmt: skip
    parser.add_argument("--episodes", type=int, default=cards.EPISODES)
    ns = parser.parse_args(argv)
    specs = ns.policy or ["scripted"] + [str(d) for d in cards.shipped() if cards.read_card(d)["env"] == ns.env]
    seeds = range(cards.SEED, cards.SEED + ns.episodes)
    print(f"{ns.env}, {ns.episodes} episodes (seeds {seeds[0]}-{seeds[-1]})")
    for spec in specs:
        a = episodes(ns.env, spec, seeds)
        w, ok, grip, held = a[:, 0], a[:, 1], a[:, 2], a[:, 3]
        print(f"\n{spec}: success {ok.mean():.0%}")
        if not np.isnan(held).all():
            print(f"  held when the carry began: {int(held.sum())} of {len(held)}; still held at the end: "
                  f"{int((ok * held).sum())} of those")  # fmt: skip
        for lo, hi in BINS:
            m = (np.abs(w) >= lo) & (np.abs(w) < hi)
            if m.any():
                print(f"  |wedge| {lo:.3f}-{min(hi, 0.15):.3f} rad: success {ok[m].mean():4.0%} of {m.sum():3d}, "
                      f"fingers close {np.nanmean(grip[m]) * 100:+.1f} cm above the centre")  # fmt: skip
        for name, m in (("wedge > +0.025 (gap open at the top)", w > 0.025), ("wedge < -0.025 (open at the bottom)", w < -0.025)):
            if m.any():
                print(f"  {name}: success {ok[m].mean():4.0%} of {m.sum():3d}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
