"""The tissue's contact patch on a sphere against the geometry of indentation: a sphere of radius R
pressed a depth delta into a flat pad meets it over a disc of radius sqrt(2 R delta - delta^2)
(the sphere's chord at that depth; Hertz's a = sqrt(R delta) is for two elastic half-spaces, not a
thin pad on a rigid core, where the pad's surface follows the sphere over the patch). The patch
grows with the squeeze as the chord says only if the tissue's patch is a surface that wraps the
sphere, not a few particles.

    PYTHONPATH=. python benchmarks/sphere_patch.py                        # default and converged tissue
    PYTHONPATH=. python benchmarks/sphere_patch.py --presets default --forces 1,3

The scripted grasp lifts the 3 cm sphere (SoftGraspEasy-v4, object="sphere", aligned) with each
finger's motor at the squeeze given, and holds it; over the hold (env steps 40-60), per finger:

- delta: the pad's indentation, its thickness less the gap from the core's inner face to the
  sphere's surface along the core's closing axis [mm];
- the chord sqrt(2 R delta - delta^2) [mm];
- a_max: the largest distance of a contact point from the centre of pressure, in the patch's
  plane [mm] (resolution-limited: the outermost touching particle);
- a_2: sqrt(2 <r^2>_N), the pressure-weighted second moment's radius - a uniform disc of radius a
  has <r^2> = a^2 / 2, a parabolic (Hertz-like) pressure a^2 / 3 [mm];
- N, the normal force, and the contacts.
No timing, no assertions: a measurement.
"""

from __future__ import annotations

import argparse
import math
import sys

import gymnasium as gym
import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from benchmarks.contact_patch import patch_figures
from softgrasp_env.policies import ScriptedGraspPolicy
from softgrasp_env.scene.scene import CYLINDER_SHAPE, LEFT, RIGHT

ALIGNED = {"yaw": 0.0, "jaw_wedge": 0.0, "lateral_offset": 0.0, "cylinder_xy": (0.0, 0.0)}
HOLD = (40, 60)


def second_moment_radius(solver, shape: int, body: int) -> float:
    """sqrt(2 <r^2>) of the pressure over body ``body``'s patch on ``shape`` (r in the patch plane)."""
    nc = int(solver._counts[0])
    sc = solver._scratch
    lam = sc["c_lambda"][:nc]
    sel = (sc["c_shape"][:nc] == shape) & ~sc["c_inner"][:nc] & (lam > 0.0)
    sel &= solver.model.particle_body[sc["c_particle"][:nc]] == body
    lam, pts, normals = lam[sel], sc["c_point"][:nc][sel], sc["c_normal"][:nc][sel]
    n = (lam[:, None] * normals).sum(axis=0)
    n /= np.linalg.norm(n)
    r = pts - (lam[:, None] * pts).sum(axis=0) / lam.sum()
    r -= np.outer(r @ n, n)
    return float(math.sqrt(2.0 * (lam * (r * r).sum(axis=1)).sum() / lam.sum()))


def indentation(scene, slot: int) -> float:
    """The pad's indentation by the sphere at finger ``slot`` [m]: its thickness less the gap from
    the core's inner face to the sphere's surface along the core's x axis."""
    col = scene.world.colliders
    x, q = col.rigid_x[slot], col.rigid_q[slot]
    qx, qy, qz, qw = q
    ex = np.array([1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy + qz * qw), 2 * (qx * qz - qy * qw)])
    c = col.rigid_x[2]  # the object's slot
    radius = scene.config.object.size[0]
    face_gap = abs(float((c - x) @ ex)) - scene.config.finger_half_extents[0]
    return scene.config.pad_thickness - (face_gap - radius)


def measure(force: float, preset: str) -> list[dict[str, float]]:
    env = gym.make("SoftGraspEasy-v4", object="sphere", finger_force=force, preset=preset)
    try:
        base = env.unwrapped
        policy = ScriptedGraspPolicy.for_env(env, grip_force=min(0.5, 0.5 * force))
        obs, _ = env.reset(seed=0, options=ALIGNED)
        scene = base.scene
        solver = scene.world.solver
        dt = solver.sim.dt  # the solver's own step, a world step (its multipliers are per step)
        rows: list[list[dict]] = [[], []]
        for k in range(HOLD[1]):
            obs, _, term, trunc, info = env.step(policy(obs))
            if term or trunc:
                break
            if k >= HOLD[0] and info["held"]:
                for body, slot in ((0, LEFT), (1, RIGHT)):
                    fig = patch_figures(solver, CYLINDER_SHAPE, body, dt)
                    if fig is not None:
                        fig["a2"] = second_moment_radius(solver, CYLINDER_SHAPE, body)
                        fig["delta"] = indentation(scene, slot)
                        rows[body].append(fig)
        return [{key: float(np.mean([f[key] for f in r])) for key in r[0]} if r else {} for r in rows]
    finally:
        env.close()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--forces", default="0.5,1,3,6", help="each finger's squeeze [N]")
    parser.add_argument("--presets", default="default,converged")
    ns = parser.parse_args(argv)
    radius = 0.03
    print("| tissue | squeeze [N] | N [N] | contacts | delta [mm] | chord sqrt(2 R delta - delta^2) [mm] | a_max [mm] "
          "| a_2 [mm] |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|")
    for preset in ns.presets.split(","):
        for force in (float(f) for f in ns.forces.split(",")):
            for side, fig in zip(("left", "right"), measure(force, preset), strict=True):
                if not fig:
                    print(f"| {preset} | {force:g} | {side}: no contact in the hold | | | | | |")
                    continue
                d = fig["delta"]
                chord = math.sqrt(max(0.0, 2 * radius * d - d * d))
                print(f"| {preset} ({side}) | {force:g} | {fig['N']:.2f} | {fig['contacts']:.0f} | {d * 1e3:.2f} | "
                      f"{chord * 1e3:.1f} | {fig['a'] * 1e3:.1f} | {fig['a2'] * 1e3:.1f} |", flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
