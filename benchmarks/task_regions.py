"""Where in the reach task's ranges each finger kind holds: success per region of every quantity
the v3 start draws (the successor of wedge_sign.py, which splits by the wedge only).

Runs one policy per kind (soft, rigid twin, torsional peer; default the scripted grasp) on the
card seeds (1000-1099) of SoftGrasp-v3, SoftGraspRigid-v3 and SoftGraspRigidTorsion-v3. The kinds
draw the same starts from the same seed (the draw does not depend on the fingers), so a region
holds the same episodes for every kind and the columns compare like with like. For each drawn
quantity - the jaw wedge (signed: positive opens the gap at the top), the palm's yaw, the grip's
start distance from the cylinder, the cylinder's radius, mass and friction scale when the id
draws them, and the sway's frequency, peak acceleration and direction (0 = across the jaw) - the
episodes are split into thirds by its value, and each third prints, per kind, how many were held
when the carry began and how many succeeded (held through the carry).

    PYTHONPATH=. python benchmarks/task_regions.py                  # the scripted grasp, 100 seeds
    PYTHONPATH=. python benchmarks/task_regions.py --policy tissue=SoftGrasp-v3_sac_0 \\
        --policy rigid=SoftGraspRigid-v3_sac_0 --policy rigid_torsion=SoftGraspRigidTorsion-v3_sac_0

``--policy KIND=SPEC`` takes anything ``agents.evaluate`` loads (a train.py run, a shipped
baseline's name, an RLlib trial, ``random``); it must have been trained on its kind's id.
``--option NAME=VALUE`` fixes a reset option in every episode (the env checks it), e.g. a heavier
cylinder or less friction than the task draws, to probe beyond its ranges:

    PYTHONPATH=. python benchmarks/task_regions.py --option cylinder_mass=0.3 --option friction_scale=0.6
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np

from benchmarks.carry_bands import IDS, add_kind_arguments, kinds_and_policies, make_policy
from softgrasp_env.registration import make_as as make

SEED = 1000
"""The model cards' first seed (agents.cards.SEED): a region's rates read against the cards'."""

QUANTITIES = {
    "jaw_wedge": "jaw wedge [rad]",
    "abs_yaw": "|palm yaw| [rad]",
    "approach": "grip start to cylinder [cm]",
    "cylinder_radius": "cylinder radius [mm]",
    "cylinder_mass": "cylinder mass [g]",
    "friction_scale": "friction scale [-]",
    "carry_frequency": "sway frequency [Hz]",
    "carry_acceleration": "sway peak acceleration [m/s^2]",
    "carry_direction": "sway direction from across the jaw [deg]",
}
"""The drawn quantities, as printed (a quantity every episode shares is left out)."""


def start_of(env) -> dict[str, float]:
    """The quantities this episode's start drew, read back from the scene and the carry task."""
    u = env.unwrapped
    cfg, base = u.scene.config, u.plan.scene
    dx = np.subtract(cfg.gripper_xy, cfg.cylinder_xy)
    carry = u.task
    omega = 2.0 * math.pi * carry.frequency
    direction = math.degrees(carry.angle) % 180.0
    return {
        "jaw_wedge": cfg.jaw_wedge,
        "abs_yaw": abs(cfg.yaw),
        "approach": 100.0 * math.hypot(*dx),
        "cylinder_radius": 1e3 * cfg.cylinder_radius,
        "cylinder_mass": 1e3 * cfg.cylinder_mass,
        "friction_scale": cfg.ground_friction / base.ground_friction,
        "carry_frequency": carry.frequency,
        "carry_acceleration": carry.amplitude * omega * omega,
        # a sway along +d and along -d is the same sway: fold to 0-90 deg from across the jaw
        "carry_direction": min(direction, 180.0 - direction),
    }


def episodes(
    kind: str, spec: str | None, seeds: range, options: dict[str, float] | None = None
) -> list[dict[str, float]]:
    """Per seed: the start's quantities, ``held_at_carry`` and ``success`` (1.0 / 0.0); ``options``
    are passed to every reset."""
    env = make(IDS[kind])
    try:
        policy = make_policy(spec, env)
        rows = []
        for seed in seeds:
            obs, _ = env.reset(seed=seed, options=options)
            row = start_of(env)
            held_at_carry, done, info = None, False, {}
            while not done:
                obs, _, term, trunc, info = env.step(policy(obs))
                done = term or trunc
                if held_at_carry is None and info["carrying"]:
                    held_at_carry = bool(info["held"])
            row["held_at_carry"] = float(bool(held_at_carry))  # None: the episode ended before the carry
            row["success"] = float(info["is_success"])
            rows.append(row)
        return rows
    finally:
        env.close()


def thirds(values: np.ndarray) -> list[np.ndarray]:
    """Masks splitting the episodes into thirds by ``values`` (by rank, so each third holds a
    third of the episodes whatever the quantity's distribution)."""
    order = np.argsort(values, kind="stable")
    parts = np.array_split(order, 3)
    masks = []
    for idx in parts:
        m = np.zeros(len(values), dtype=bool)
        m[idx] = True
        masks.append(m)
    return masks


def regions(results: dict[str, list[dict[str, float]]]) -> list[tuple[str, str, dict[str, tuple[int, int, int]]]]:
    """(quantity, range, {kind: (episodes, held when the carry began, succeeded)}) per third of
    every drawn quantity; the kinds must have run the same seeds (so they share the starts)."""
    kinds = list(results)
    first = results[kinds[0]]
    for kind in kinds[1:]:
        for q in QUANTITIES:
            a = np.array([r[q] for r in first])
            b = np.array([r[q] for r in results[kind]])
            if not np.allclose(a, b, rtol=1e-9, atol=1e-12):
                raise RuntimeError(f"{kind} drew other starts than {kinds[0]} ({q}): the regions would not compare")
    out = []
    for q, label in QUANTITIES.items():
        values = np.array([r[q] for r in first])
        if np.ptp(values) <= 1e-9 * max(1.0, abs(values).max()):
            continue  # not drawn on this id
        for m in thirds(values):
            span = f"{values[m].min():.3g} to {values[m].max():.3g}"
            cell = {}
            for kind in kinds:
                held = np.array([r["held_at_carry"] for r in results[kind]])[m]
                ok = np.array([r["success"] for r in results[kind]])[m]
                cell[kind] = (int(m.sum()), int(held.sum()), int(ok.sum()))
            out.append((label, span, cell))
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--episodes", type=int, default=100, help="seeds 1000, 1001, ... (default: the cards' 100)")
    add_kind_arguments(parser)
    parser.add_argument("--option", action="append", default=[], metavar="NAME=VALUE",
                        help="a reset option fixed in every episode (a number), e.g. cylinder_mass=0.3")  # fmt: skip
    ns = parser.parse_args(argv)
    options: dict[str, float] = {}
    for item in ns.option:
        name, sep, value = item.partition("=")
        if not (sep and name):
            parser.error(f"--option takes NAME=VALUE, got {item!r}")
        try:
            options[name] = float(value)
        except ValueError:
            parser.error(f"--option {item!r}: the value must be a number")
    kinds, specs = kinds_and_policies(parser, ns)
    if ns.episodes < 3:
        parser.error(f"--episodes must be at least 3 (one per third), got {ns.episodes}")
    seeds = range(SEED, SEED + ns.episodes)
    named = ", ".join(f"{k}: {specs.get(k, 'scripted')}" for k in kinds)
    fixed = "".join(f", {k}={v:g}" for k, v in options.items())
    print(f"reach task{fixed}, seeds {seeds.start}-{seeds.stop - 1}; 1 process; {named}")
    results = {}
    for kind in kinds:
        tic = time.perf_counter()
        results[kind] = episodes(kind, specs.get(kind), seeds, options)
        n_ok = int(sum(r["success"] for r in results[kind]))
        n_held = int(sum(r["held_at_carry"] for r in results[kind]))
        print(f"{kind:<14} success {n_ok}/{ns.episodes}, held when the carry began {n_held}/{ns.episodes} "
              f"({time.perf_counter() - tic:.0f} s)", flush=True)  # fmt: skip
    print("\nper third of each drawn quantity: held when the carry began / succeeded (of the third's episodes)")
    print(f"{'quantity':<42}{'range':>18}" + "".join(f"{k:>16}" for k in kinds))
    for label, span, cell in regions(results):
        row = "".join(f"{f'{h}/{s} of {n}':>16}" for n, h, s in cell.values())
        print(f"{label:<42}{span:>18}{row}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
