"""The tissue's own contact patch on the cylinder, and the torsional lever a rigid finger would need
to resist spin about the contact normal as that patch does (the
``rigid_torsion`` finger kind takes its default from here: softgrasp_env/fingers/rigid.py).

    PYTHONPATH=. python benchmarks/contact_patch.py
    PYTHONPATH=. python benchmarks/contact_patch.py --particle-density 16000    # a finer tissue

Coulomb friction over a patch with pressure p bounds the torsion about the patch normal through
its centre of pressure c by mu * integral p |r - c| dA. With the tissue's particle contacts as the
pressure samples (normal force N_i at contact point r_i, projected into the plane of the patch's
mean normal), that is mu * l * N with the lever

    l = sum_i N_i |r_i - c| / sum_i N_i,       N = sum_i N_i,

the pressure-weighted radius the tissue's own patch friction bounds torsion with
(softgrasp_env/tissue/friction.py, friction_patches, its ``e``). Printed per finger, averaged
over the hold (lifted, before the episode's end), at the default soft grasp (SoftGraspEasy-v3:
aligned, no wedge, centred, the scripted policy's squeeze) and at a two-point misaligned one
(jaw wedge -0.1 rad); beside it the patch's extent along the cylinder's axis and around it, the
largest |r - c| = a and what a uniformly pressed disc of that radius would give, (2/3) a.

It reads the tissue solver's per-contact scratch (``TissueSolver._scratch``: ``c_lambda``, the
accumulated normal multiplier, a positional impulse [kg m], so N_i = lambda_i / h^2, h the world
step, dt / world_substeps;
``c_point``, where the contact touches; ``c_patch``, its (tissue body, shape) patch) after every
env step of the hold. No timing, no assertions: a measurement.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.registration import make_as as make
from softgrasp_env.scene.scene import CYLINDER_SHAPE

GRASPS = {
    "aligned (default)": {"yaw": 0.0, "jaw_wedge": 0.0, "lateral_offset": 0.0, "cylinder_xy": (0.0, 0.0)},
    "two-point (wedge -0.1)": {"yaw": 0.0, "jaw_wedge": -0.1, "lateral_offset": 0.0, "cylinder_xy": (0.0, 0.0)},
}
"""The reset options of the grasps measured."""
HOLD_FROM = 40
"""First env step of the hold measured (the scripted grasp has lifted and settled by step 30)."""


def patch_figures(solver, shape: int, body: int, dt: float) -> dict[str, float] | None:
    """The patch of tissue body ``body`` on shape ``shape`` after the solver's last step: normal
    force N [N], lever l [m], contacts, extent along the world z axis (the upright cylinder's axis)
    and across it in the patch plane [m], the largest radius a about the centre of pressure [m].
    None if the body does not touch the shape."""
    nc = int(solver._counts[0])
    sc = solver._scratch
    lam = sc["c_lambda"][:nc]
    sel = (sc["c_shape"][:nc] == shape) & ~sc["c_inner"][:nc] & (lam > 0.0)
    sel &= solver.model.particle_body[sc["c_particle"][:nc]] == body
    if not sel.any():
        return None
    lam = lam[sel]
    pts = sc["c_point"][:nc][sel]
    normals = sc["c_normal"][:nc][sel]
    n = (lam[:, None] * normals).sum(axis=0)
    n /= np.linalg.norm(n)
    centre = (lam[:, None] * pts).sum(axis=0) / lam.sum()
    r = pts - centre
    r -= np.outer(r @ n, n)  # into the plane of the patch's mean normal
    radius = np.linalg.norm(r, axis=1)
    up = np.array([0.0, 0.0, 1.0])
    along = up - (up @ n) * n
    along /= np.linalg.norm(along)
    across = np.cross(n, along)
    return {
        "N": float(lam.sum() / dt**2),
        "lever": float((lam * radius).sum() / lam.sum()),
        "contacts": float(sel.sum()),
        "extent_along": float(np.ptp(r @ along)),
        "extent_across": float(np.ptp(r @ across)),
        "a": float(radius.max()),
    }


def measure(options: dict, *, steps: int = 100, seed: int = 0, **env_kwargs) -> list[dict[str, np.ndarray]]:
    """Per finger (left, right): every figure of ``patch_figures`` at the last physics step of env
    steps HOLD_FROM..steps (the hold) of the scripted grasp from ``options``; ``env_kwargs`` go to
    gym.make."""
    env = make("SoftGraspEasy-v3", **env_kwargs)
    try:
        base = env.unwrapped
        # below 1 N per finger the policy's grip threshold (0.5 N) would be the motors' whole force:
        # at most half of it, as the stability maps take it (stability_map.policy_for)
        force = base.args.control.finger_force
        policy = ScriptedGraspPolicy.for_env(env, grip_force=min(ScriptedGraspPolicy().grip_force, 0.5 * force))
        obs, _ = env.reset(seed=seed, options=options)
        scene = base.scene
        # the solver's own step: a world step, dt / world_substeps (the multipliers are per step)
        solver = scene.world.solver
        dt = solver.sim.dt
        rows: list[list[dict]] = [[], []]
        # an env step is several physics steps and the scratch holds the last one's contacts: the
        # hold is sampled once per env step
        for k in range(steps):
            obs, _, term, trunc, info = env.step(policy(obs))
            if term or trunc:
                break
            if k >= HOLD_FROM and info["held"]:
                for body in (0, 1):
                    fig = patch_figures(solver, CYLINDER_SHAPE, body, dt)
                    if fig is not None:
                        rows[body].append(fig)
        return [{key: np.array([f[key] for f in r]) for key in (r[0] if r else {})} for r in rows]
    finally:
        env.close()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=100, help="env steps per grasp (20 Hz)")
    parser.add_argument("--particle-density", type=float, default=None,
                        help="tissue particles per m^2 of face (default: the default preset's, 4,000)")  # fmt: skip
    ns = parser.parse_args(argv)
    kwargs = {} if ns.particle_density is None else {"particle_density": ns.particle_density}
    print(f"tissue patch on the cylinder, per finger, mean (min-max) over the hold {kwargs or '(defaults)'}")
    for name, options in GRASPS.items():
        print(f"\n{name}: {options}")
        for side, figs in zip(("left", "right"), measure(options, steps=ns.steps, **kwargs), strict=True):
            if not figs:
                print(f"  {side}: no contact during the hold")
                continue

            def show(key, scale=1e3, unit="mm", figs=figs):
                v = figs[key] * scale
                return f"{v.mean():.2f} ({v.min():.2f}-{v.max():.2f}) {unit}"

            a = figs["a"]
            print(f"  {side}: N {show('N', 1.0, 'N')}, contacts {figs['contacts'].mean():.1f}, "
                  f"samples {len(a)}")  # fmt: skip
            print(f"    lever l = sum N_i |r_i - c| / N: {show('lever')}")
            print(f"    extent along the axis {show('extent_along')}, around it {show('extent_across')}")
            print(f"    largest radius a {show('a')}; uniform disc (2/3) a = {(2 / 3) * a.mean() * 1e3:.2f} mm")
    return 0


if __name__ == "__main__":
    sys.exit(main())
