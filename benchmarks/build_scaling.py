"""Building the grasp scene at 1x, 10x and 100x the default particle density: particles, build
time, peak memory of the build and the estimate the builder checks before it starts (a former bug:
memory used to grow with the square of the particle count; 1e7 per m^2 asked for 574 GiB).

    PYTHONPATH=. python benchmarks/build_scaling.py [--factors 1 10 100]

Peak memory is tracemalloc's (numpy's arrays included; pybullet's C++ allocations are not).
"""

from __future__ import annotations

import argparse
import sys
import time
import tracemalloc
from dataclasses import replace

from softgrasp_env.scene import GraspScene, SceneConfig
from softgrasp_env.tissue.builder import memory_estimate


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--factors", type=float, nargs="+", default=[1.0, 10.0, 100.0])
    ns = parser.parse_args(argv)
    base = SceneConfig()
    GraspScene(base).close()  # warm: numba's cached kernels loaded, pybullet up
    print(f"{'density /m^2':>13} {'particles':>10} {'build s':>8} {'peak MB':>8} {'estimate MB':>12} {'bytes/particle':>15}")
    for factor in ns.factors:
        cfg = replace(base, tissue=replace(base.tissue, particle_density=base.tissue.particle_density * factor))
        tracemalloc.start()
        tic = time.perf_counter()
        scene = GraspScene(cfg)
        seconds = time.perf_counter() - tic
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        n = scene.world.state.particle_x.shape[0]
        scene.close()
        est = memory_estimate(n, cfg.tissue.group_size)
        print(f"{cfg.tissue.particle_density:13,.0f} {n:10,d} {seconds:8.2f} {peak / 1e6:8.1f} {est / 1e6:12.1f} {peak / n:15,.0f}",
              flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
