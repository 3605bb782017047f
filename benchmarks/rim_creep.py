"""A grip high on the cylinder, the pads partly above its rim: how far the cylinder creeps down the
fingers while it is lifted and the palm moves about, per finger kind (where ours
loses).

The learned soft policies close 26-48 mm above the cylinder's centre and, beyond the
task's ranges (a 0.2 kg cylinder at half friction), drop what the learned torsional peer holds,
although the scripted soft grasp holds it. This isolates the physics from the policies: the
scripted grasp of the reach task, aimed ``height`` above the centre (the fingers are 6 cm tall,
the cylinder's top 5 cm above its centre: at 4 cm the pads' upper 2 cm are above the rim), lifting
to ``lift`` and, once both fingers press, adding uniform noise of ``noise`` (of full action) to
the palm's horizontal velocity command at every control step, seeded per episode. Printed per
kind and setting: success (the env's: held through the carry), the median and largest creep (how
far the cylinder slid down the fingers from where they first gripped it), and Coulomb's margin
2 mu F / (m (g + a)) with the arm's acceleration a; for the tissue, the rim push: the largest
downward force its contacts on the cylinder's top face and rim edge put on the cylinder.

The cause (measured with ``--particle-density``): each tissue particle meets a rigid shape as a
sphere of its support radius along the contact normal (Mueller & Chentanez 2011 sec. 5), and the
normal is the cylinder's at the closest point. A surface particle reaches about half the
particle spacing within the pad's plane (its ellipsoid's radii: 8.5-8.8 mm in the plane, 3 mm
across, at the default 4000 per m^2), so a particle whose centre
sits up to that far above the rim, squeezed inward, lands on the rim edge or the top face: the
contact pushes it up and the cylinder down, turning the squeeze into load. The push and the creep
scale with the spacing and vanish as the tissue is refined: a discretisation error at sharp
edges, not the material or the friction law.

    PYTHONPATH=. python benchmarks/rim_creep.py                       # 0.2 kg, friction x 0.5
    PYTHONPATH=. python benchmarks/rim_creep.py --mass 0.1 --friction 1 --seeds 5
    PYTHONPATH=. python benchmarks/rim_creep.py --kinds tissue --heights 0 0.04 --particle-density 4000 16000 64000
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from benchmarks.carry_bands import IDS
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.registration import make_as as make
from softgrasp_env.scene import CYLINDER_SHAPE

KINDS = {**IDS, "tissue_cones": "SoftGrasp-v3"}
"""The kinds and their ids; ``tissue_cones`` is the soft fingers with the per-contact friction cones."""
GRAVITY = 9.81


UP = 0.3
"""A contact whose normal (out of the cylinder) has a z component above this is on the cylinder's
top face or its rim edge: it pushes the cylinder down."""


def watch_rim_push(scene) -> list[float]:
    """Hook the tissue solver of ``scene``: after every world step, append the downward force [N]
    the tissue's contacts on the cylinder's top face and rim edge put on the cylinder (their
    normal multipliers lambda n over dt^2, Mueller et al. 2020 eq. 6). Rigid kinds have no tissue
    contacts: their pushes are 0 (or none)."""
    pushes: list[float] = []
    solver = getattr(scene.world, "solver", None)
    if solver is None:
        return pushes
    inner_step = solver.step

    def step(state, colliders):
        out = inner_step(state, colliders)
        lc = solver.last_contacts()
        n = lc.count
        on_top = (lc.shape[:n] == CYLINDER_SHAPE) & ~lc.inner[:n] & (lc.normal[:n, 2] > UP)
        pushes.append(float(np.sum(lc.normal_lambda[:n][on_top] * lc.normal[:n, 2][on_top])) / solver.sim.dt**2)
        return out

    solver.step = step
    return pushes


def episode(env, height: float, lift: float, noise: float, seed: int, options: dict) -> tuple[bool, float, float, float]:
    """(success, creep [m], Coulomb's margin, the largest downward push of the tissue's contacts on
    the cylinder's top and rim [N]; 0 for rigid kinds) of one episode of the aimed, shaken scripted
    grasp."""
    names = env.unwrapped.obs_names
    iz, il, ir = names.index("cyl_rel_z"), names.index("force_left"), names.index("force_right")
    policy = ScriptedGraspPolicy.for_env(env, lift_to=lift)
    rng = np.random.default_rng(seed)
    obs, _ = env.reset(seed=seed, options=options)
    pushes = watch_rim_push(env.unwrapped.scene)
    cfg = env.unwrapped.scene.config
    margin = 2.0 * cfg.tissue.friction_static * cfg.finger_force / (
        cfg.cylinder_mass * (GRAVITY + cfg.arm_acceleration))  # fmt: skip
    first, creep, done, info = None, 0.0, False, {}
    while not done:
        aimed = obs.copy()
        aimed[iz] += height  # the policy steers the grip point to the cylinder's centre: aim above it
        action = policy(aimed)
        if obs[il] > policy.grip_force and obs[ir] > policy.grip_force:
            action[:2] = np.clip(action[:2] + rng.uniform(-noise, noise, 2), -1.0, 1.0)
            grip = -float(obs[iz])  # the grip point's height above the cylinder's centre
            first = grip if first is None else first
            creep = max(creep, grip - first)
        obs, _, terminated, truncated, info = env.step(action)
        done = terminated or truncated
    return bool(info["is_success"]), creep, margin, max(pushes, default=0.0)


def run(kind: str, height: float, lift: float, noise: float, seeds: range, options: dict,
        particle_density: float | None = None) -> dict[str, float]:  # fmt: skip
    """Episodes of ``kind`` on ``seeds``; ``particle_density`` [particles / m^2] refines the
    tissue kinds' discretisation (None: the id's)."""
    kwargs = {"tissue_contact_cone": True} if kind == "tissue_cones" else {}
    if particle_density is not None:
        if not kind.startswith("tissue"):
            raise ValueError(f"particle_density is a tissue setting; {kind!r} has no tissue")
        kwargs["particle_density"] = particle_density
    env = make(KINDS[kind], **kwargs)
    try:
        rows = [episode(env, height, lift, noise, s, options) for s in seeds]
    finally:
        env.close()
    creeps, pushes = [r[1] for r in rows], [r[3] for r in rows]
    return {"success": sum(r[0] for r in rows), "episodes": len(rows), "median_creep": float(np.median(creeps)),
            "max_creep": max(creeps), "margin": rows[0][2], "median_push": float(np.median(pushes)),
            "max_push": max(pushes)}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--kinds", default="tissue,tissue_cones,rigid_torsion,rigid")
    parser.add_argument("--heights", type=float, nargs="+", default=[0.0, 0.02, 0.04], help="aim above the centre [m]")
    parser.add_argument("--noise", type=float, nargs="+", default=[0.0, 0.8], help="palm noise, of full action")
    parser.add_argument("--lift", type=float, default=0.11, help="lift height the grasp holds [m]")
    parser.add_argument("--mass", type=float, default=0.2, help="cylinder mass [kg] (the task's: 0.1)")
    parser.add_argument("--friction", type=float, default=0.5, help="friction scale (the task's: 1)")
    parser.add_argument("--seeds", type=int, default=10, help="episodes per setting (seeds 1000, 1001, ...)")
    parser.add_argument("--particle-density", type=float, nargs="+", default=[None], metavar="D",
                        help="the tissue kinds' particles per m^2 of core surface, one row each (default: the id's, "
                             "4000: 15.8 mm apart); the rigid kinds ignore it")  # fmt: skip
    ns = parser.parse_args(argv)
    kinds = ns.kinds.split(",")
    for kind in kinds:
        if kind not in KINDS:
            parser.error(f"--kinds: {kind!r} is not one of {sorted(KINDS)}")
    for name, values in (("--heights", ns.heights), ("--noise", ns.noise)):
        if not all(np.isfinite(values)):
            parser.error(f"{name} must be finite, got {values}")
    if not all(0.0 <= n <= 2.0 for n in ns.noise):
        parser.error(f"--noise must be in [0, 2] (of full action), got {ns.noise}")
    if ns.seeds < 1:
        parser.error(f"--seeds must be >= 1, got {ns.seeds}")
    if any(d is not None and not (np.isfinite(d) and d > 0) for d in ns.particle_density):
        parser.error(f"--particle-density must be positive and finite, got {ns.particle_density}")
    options = {"cylinder_mass": ns.mass, "friction_scale": ns.friction}
    seeds = range(1000, 1000 + ns.seeds)
    print(f"cylinder {ns.mass * 1e3:.0f} g, friction x {ns.friction:g}, lift to {ns.lift * 1e2:.1f} cm, "
          f"seeds {seeds.start}-{seeds.stop - 1}; 1 process")  # fmt: skip
    print("rim push: the largest downward force of the tissue's contacts on the cylinder's top face and rim edge "
          "in an episode, median and largest over the episodes [N]")  # fmt: skip
    print(f"{'kind':<15}{'density':>9}{'aim mm':>8}{'noise':>7}{'success':>9}{'creep median mm':>17}{'max mm':>8}"
          f"{'margin':>8}{'rim push N':>12}{'max':>7}")  # fmt: skip
    for kind in kinds:
        tissue = kind.startswith("tissue")
        for density in ns.particle_density if tissue else [None]:
            for height in ns.heights:
                for noise in ns.noise:
                    r = run(kind, height, ns.lift, noise, seeds, options, density)
                    label = "-" if not tissue else "id's" if density is None else f"{density:g}"
                    push = f"{r['median_push']:>12.2f}{r['max_push']:>7.2f}" if tissue else f"{'-':>12}{'-':>7}"
                    print(f"{kind:<15}{label:>9}{height * 1e3:>8.0f}{noise:>7.1f}{r['success']:>5}/{r['episodes']:<3}"
                          f"{r['median_creep'] * 1e3:>17.1f}{r['max_creep'] * 1e3:>8.1f}{r['margin']:>8.2f}{push}",
                          flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
