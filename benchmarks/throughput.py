"""Physics steps per second: rigid-only vs soft grasp scene (all faces of the cores covered, or
only the faces where contact can happen), in one run, and soft-scene scaling with particle count
(1x, 2x, 4x the default). Also the start-up time of a fresh process (numba's
compiled code comes from its on-disk cache).

    python benchmarks/throughput.py [--seconds 3]

Prints a table; the machine is shared, so each figure is the best of three runs.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time

import numpy as np

from softgrasp_env.config import SceneConfig, TissueConfig
from softgrasp_env.scene import GraspScene


def steps_per_second(cfg: SceneConfig, steps: int, repeats: int = 3) -> tuple[float, int]:
    """Best-of-``repeats`` physics steps/s of the scene squeezing the cylinder (contacts active)."""
    best = 0.0
    particles = 0
    for _ in range(repeats):
        scene = GraspScene(cfg)
        try:
            scene.set_palm_target(np.array([0.0, 0.0, scene.grasp_height + scene.palm_offset]))
            scene.set_finger_target(cfg.finger_max_opening)
            for _ in range(240):  # settle into the squeeze, and compile anything not cached
                scene.step()
            tic = time.perf_counter()
            for _ in range(steps):
                scene.step()
            best = max(best, steps / (time.perf_counter() - tic))
            particles = 0 if scene.world.model is None else scene.world.model.particle_count
        finally:
            scene.close()
    return best, particles


def startup_seconds() -> float:
    """Wall time for a new process to import, build the soft scene and take its first step."""
    code = (
        "import time; t=time.perf_counter();"
        "from softgrasp_env.scene import GraspScene; s=GraspScene(); s.step();"
        "print(time.perf_counter()-t)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return float(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=1000, help="timed steps per run")
    args = parser.parse_args()
    base = SceneConfig()
    rigid, _ = steps_per_second(SceneConfig(fingers="rigid"), args.steps)
    soft, n = steps_per_second(base, args.steps)
    print(f"{'scene':<28}{'particles':>10}{'steps/s':>12}")
    print(f"{'rigid-only fingers':<28}{0:>10}{rigid:>12.0f}")
    contact, nc = steps_per_second(SceneConfig(tissue_faces="contact"), args.steps)
    print(f"{'soft fingers (default)':<28}{n:>10}{soft:>12.0f}")
    print(f"{'soft, contact faces only':<28}{nc:>10}{contact:>12.0f}")
    print(f"soft / rigid ratio: {soft / rigid:.3f} (default), {contact / rigid:.3f} (contact faces only)   (goal >= 0.25)")
    print()
    print(f"{'density scale':<28}{'particles':>10}{'steps/s':>12}{'us/particle-step':>18}")
    for scale in (1, 2, 4):
        tissue = TissueConfig(density=base.tissue.density * scale)
        sps, n = steps_per_second(SceneConfig(tissue=tissue), args.steps // scale)
        print(f"{str(scale) + 'x':<28}{n:>10}{sps:>12.0f}{1e6 / sps / n:>18.3f}")
    print()
    t = min(startup_seconds() for _ in range(2))
    print(f"fresh process to first step (numba from cache): {t:.2f} s   (target < 2 s)")


if __name__ == "__main__":
    main()
