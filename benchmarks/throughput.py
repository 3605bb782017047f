"""Physics steps per second: rigid-only fingers against the soft fingers at every preset and at the
defaults before the presets (all faces covered, 10,000 particles per m^2), in one run, and the
soft scene's scaling with particle count (1x, 2x, 4x the default). Also the start-up time of a fresh process (numba's
compiled code comes from its on-disk cache).

    python benchmarks/throughput.py [--seconds 3]

Prints a table; the machine is shared, so each figure is the best of three runs.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from dataclasses import replace

import numpy as np

from softgrasp_env import presets
from softgrasp_env.config import TissueConfig
from softgrasp_env.fingers import TissueFingerConfig
from softgrasp_env.scene import GraspScene, GripperControl, SceneConfig


def steps_per_second(cfg: SceneConfig, steps: int, repeats: int = 3) -> tuple[float, int]:
    """Best-of-``repeats`` physics steps/s of the scene squeezing the cylinder (contacts active)."""
    best = 0.0
    particles = 0
    for _ in range(repeats):
        scene = GraspScene(cfg)
        try:
            squeeze = GripperControl(np.array([0.0, 0.0, scene.grasp_height + scene.palm_offset]), cfg.finger_stroke)
            scene.step(squeeze)
            for _ in range(239):  # settle into the squeeze, and compile anything not cached
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
    rows = [("rigid-only fingers", SceneConfig(fingers="rigid"))]
    rows += [(f"soft, preset {name!r}", presets.scene_config(name)) for name in presets.PRESETS]
    # the former defaults, before a preset was chosen: every face covered at 10,000 particles per m^2
    rows.append(("soft, all faces, 10k/m^2", replace(base, fingers=TissueFingerConfig(faces="all"),
                                                         tissue=replace(base.tissue, particle_density=10_000.0))))
    print(f"{'scene':<28}{'particles':>10}{'steps/s':>12}{'/ rigid':>10}")
    rigid = None
    for label, cfg in rows:
        sps, n = steps_per_second(cfg, args.steps)
        rigid = sps if rigid is None else rigid
        print(f"{label:<28}{n:>10}{sps:>12.0f}{sps / rigid:>10.3f}")
    print("(goal: the default preset >= 0.4 of the rigid-only fingers)")
    print()
    print(f"{'density scale':<28}{'particles':>10}{'steps/s':>12}{'us/particle-step':>18}")
    for scale in (1, 2, 4):
        tissue = TissueConfig(particle_density=base.tissue.particle_density * scale)
        sps, n = steps_per_second(SceneConfig(tissue=tissue), args.steps // scale)
        print(f"{str(scale) + 'x':<28}{n:>10}{sps:>12.0f}{1e6 / sps / n:>18.3f}")
    print()
    t = min(startup_seconds() for _ in range(2))
    print(f"fresh process to first step (numba from cache): {t:.2f} s   (target < 2 s)")


if __name__ == "__main__":
    main()
