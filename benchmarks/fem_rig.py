"""pybullet's FEM pad in the pad rig: one pad (softgrasp_env.fingers.fem, the ``fem`` finger kind's
mesh and material) on a fixed core, pressed by a frictionless cylinder along the closing axis with
1 / 3 / 6 N; its compression against the plane-strain finite-element reference (pad_reference.py,
the rows ours and MuJoCo's pads are measured on: benchmarks/peers.py).

    PYTHONPATH=. python benchmarks/fem_rig.py [--resolution coarse|fine] [--substeps 8]

The rig is the one of spatial_convergence.PadRig and mujoco_peer.run_rig: the core a box at the
origin, the pad on its +x face (and its tip), gravity off, the cylinder's axis along z and longer
than the face (plane strain across the face's height), on a slide joint along x with joint damping
about critical (mujoco_peer.RIG_DAMPING), pushed toward the pad by a force ramped to each load over
0.2 s and held 0.5 s. The pad is the grasp's: the same tetrahedral mesh (pad_mesh), anchored to the
core at its nodes on the core's surface, with the tissue's shear modulus at Poisson's ratio 0
(neo_hookean_parameters), its damping, collision margin and signed-distance voxels, and no friction
(the reference's contact is frictionless). The world runs at 1/240 s in ``substeps`` pybullet steps,
as the fem finger kind does (FemConfig.substeps).

Compression: where the cylinder first touches the undeformed pad less where it rests under the
load. The pad's collision margin (1 mm) holds the cylinder off its nodes, as a MuJoCo flex's radius
and margin do, so the touching point includes it (as mujoco_peer.rig_touch_x does). A measurement:
no assertions (tests/benchmarks/test_fem_rig.py holds its bounds).
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import dataclass, field

import numpy as np
import pybullet as p

from benchmarks.mujoco_peer import REFERENCE_MM, RIG_DAMPING
from softgrasp_env.fingers.fem import (
    FEM_CELLS_THROUGH,
    FEM_COLLISION_MARGIN,
    FEM_DAMPING,
    FEM_SDF_VOXEL,
    neo_hookean_parameters,
    pad_mesh,
    vtk_file,
)
from softgrasp_env.scene import SceneConfig
from softgrasp_env.sim.bullet import _quiet_c_stdout

LOADS = (1.0, 3.0, 6.0)


@dataclass
class FemRigResult:
    """What the rig measured; lengths in m, forces in N."""

    resolution: str
    substeps: int
    nodes: int
    loads: tuple[float, ...]
    compression: list[float] = field(default_factory=list)
    """Per load: the touching point less the cylinder's centre at the end of the hold."""
    read_load: list[float] = field(default_factory=list)
    """Per load: the pad's contact force on the cylinder pybullet reports, mean over the hold's
    last fifth (its face contacts only: it reports no node contacts, fingers/fem.py)."""
    speed: list[float] = field(default_factory=list)
    """Per load: the cylinder's speed at the end of the hold [m/s] (settled: near 0)."""
    steps_per_second: float = math.nan
    """pybullet steps per wall second, stepSimulation alone."""
    dt: float = 1.0 / 240.0

    @property
    def realtime(self) -> float:
        """Simulated seconds per wall second."""
        return self.steps_per_second * self.dt / self.substeps


def touch_x(cfg: SceneConfig) -> float:
    """The cylinder's centre when it first touches the undeformed pad [m]: the core's face, the pad,
    its collision margin and the cylinder's radius."""
    return cfg.finger_half_extents[0] + cfg.tissue.extrude + FEM_COLLISION_MARGIN + cfg.cylinder_radius


def run_rig(resolution: str = "coarse", loads: tuple[float, ...] = LOADS, *, substeps: int = 8, ramp: float = 0.2,
            hold: float = 0.5, dt: float = 1.0 / 240.0) -> FemRigResult:  # fmt: skip
    """Press the pad with each load in turn (ramped over ``ramp`` from the last one, held ``hold``)
    [N, s]; ``substeps`` pybullet steps per step of ``dt``."""
    if resolution not in FEM_CELLS_THROUGH:
        raise ValueError(f"resolution must be one of {tuple(FEM_CELLS_THROUGH)}, got {resolution!r}")
    if not (isinstance(substeps, int) and substeps >= 1):
        raise ValueError(f"substeps must be an int >= 1, got {substeps!r}")
    cfg = SceneConfig(fingers="rigid")
    hx, hy, hz = cfg.finger_half_extents
    h = dt / substeps
    with _quiet_c_stdout():
        cid = p.connect(p.DIRECT)
    try:
        p.resetSimulation(p.RESET_USE_DEFORMABLE_WORLD, physicsClientId=cid)
        p.setGravity(0.0, 0.0, 0.0, physicsClientId=cid)
        p.setPhysicsEngineParameter(fixedTimeStep=h, numSubSteps=0, deterministicOverlappingPairs=1,
                                    sparseSdfVoxelSize=FEM_SDF_VOXEL, physicsClientId=cid)  # fmt: skip
        # the core, fixed; the cylinder on a slide joint along x from a fixed base at the origin
        core = p.createMultiBody(0.0, p.createCollisionShape(p.GEOM_BOX, halfExtents=[hx, hy, hz], physicsClientId=cid),
                                 physicsClientId=cid)  # fmt: skip
        cyl_shape = p.createCollisionShape(p.GEOM_CYLINDER, radius=cfg.cylinder_radius, height=2.0 * hz + 0.02,
                                           physicsClientId=cid)  # fmt: skip
        start = touch_x(cfg) + 5e-4
        rig = p.createMultiBody(
            0.0, -1, linkMasses=[cfg.cylinder_mass], linkCollisionShapeIndices=[cyl_shape],
            linkVisualShapeIndices=[-1], linkPositions=[[start, 0.0, 0.0]], linkOrientations=[[0, 0, 0, 1]],
            linkInertialFramePositions=[[0, 0, 0]], linkInertialFrameOrientations=[[0, 0, 0, 1]],
            linkParentIndices=[0], linkJointTypes=[p.JOINT_PRISMATIC], linkJointAxis=[[1.0, 0.0, 0.0]],
            physicsClientId=cid,
        )  # fmt: skip
        p.setJointMotorControl2(rig, 0, p.VELOCITY_CONTROL, force=0.0, physicsClientId=cid)  # a free slide
        p.changeDynamics(rig, 0, lateralFriction=0.0, jointDamping=RIG_DAMPING, linearDamping=0.0, angularDamping=0.0,
                         physicsClientId=cid)  # fmt: skip
        p.setCollisionFilterPair(rig, core, 0, -1, 0, physicsClientId=cid)
        # the pad: the fem kind's mesh and material, no friction
        mesh = pad_mesh((hx, hy, hz), cfg.tissue.extrude, FEM_CELLS_THROUGH[resolution], side=+1)
        mu, lam = neo_hookean_parameters(cfg.tissue.shear_modulus)
        with _quiet_c_stdout():
            pad = p.loadSoftBody(
                vtk_file(mesh), basePosition=[0.0, 0.0, 0.0], baseOrientation=[0, 0, 0, 1], scale=1.0,
                mass=cfg.tissue.mass_density * mesh.volume, useNeoHookean=1, NeoHookeanMu=mu, NeoHookeanLambda=lam,
                NeoHookeanDamping=FEM_DAMPING, useMassSpring=0, useBendingSprings=0,
                collisionMargin=FEM_COLLISION_MARGIN, useSelfCollision=0, frictionCoeff=0.0, physicsClientId=cid,
            )  # fmt: skip
        if pad < 0:
            raise RuntimeError(f"pybullet could not load the fem pad {vtk_file(mesh)}")
        p.setCollisionFilterPair(pad, core, -1, -1, 0, physicsClientId=cid)
        for i in np.flatnonzero(mesh.node_anchored):
            p.createSoftBodyAnchor(pad, int(i), core, -1, mesh.node_x[i].tolist(), physicsClientId=cid)
        out = FemRigResult(resolution, substeps, mesh.node_count, tuple(loads), dt=dt)
        touch = touch_x(cfg)
        last, seconds, steps = 0.0, 0.0, 0
        for load in loads:
            n_ramp, n_hold = round(ramp / dt), round(hold / dt)
            reads = []
            for k in range(n_ramp + n_hold):
                f = -(last + (load - last) * min(1.0, (k + 1) / n_ramp))  # toward the pad, along -x
                for _ in range(substeps):
                    p.applyExternalForce(rig, 0, [f, 0.0, 0.0], [0.0, 0.0, 0.0], p.LINK_FRAME, physicsClientId=cid)
                    tic = time.perf_counter()
                    p.stepSimulation(physicsClientId=cid)
                    seconds += time.perf_counter() - tic
                    steps += 1
                if k >= n_ramp + n_hold - max(1, n_hold // 5):
                    reads.append(sum(pt[9] for pt in p.getContactPoints(pad, rig, physicsClientId=cid)))
            x, v = p.getJointState(rig, 0, physicsClientId=cid)[:2]
            out.compression.append(touch - (start + x))
            out.read_load.append(float(np.mean(reads)))
            out.speed.append(abs(v))
            last = load
        out.steps_per_second = steps / seconds
        return out
    finally:
        p.disconnect(physicsClientId=cid)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--resolution", default="coarse", choices=tuple(FEM_CELLS_THROUGH))
    parser.add_argument("--substeps", type=int, default=8)
    args = parser.parse_args(argv)
    r = run_rig(args.resolution, substeps=args.substeps)
    print(f"fem pad, {args.resolution}: {r.nodes} nodes, {args.substeps} substeps; {r.realtime:.3f} simulated s per "
          f"wall s ({r.steps_per_second:.0f} pybullet steps/s)")  # fmt: skip
    for load, c, rl, sp in zip(r.loads, r.compression, r.read_load, r.speed, strict=True):
        ref = REFERENCE_MM[load]
        print(f"  {load:g} N: compression {c * 1e3:.3f} mm (reference {ref:.3f}, {c * 1e3 / ref - 1:+.1%}), "
              f"pybullet reads {rl:.2f} N, cylinder at {sp * 1e3:.2f} mm/s")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
