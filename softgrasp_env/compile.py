"""Compile the solver's kernels ahead of time (numba caches them on disk), so that the first
``gym.make`` after an install starts at once:

    python -m softgrasp_env.compile            # or: softgrasp-compile
    python -m softgrasp_env.compile --report   # every kernel compiled, its time and signature
    python -m softgrasp_env.compile --threads 2  # also the tissue step on threads (SimConfig.threads)
    python -m softgrasp_env.compile --objects    # also the tissue step with the round and convex objects

Run it once after ``pip install`` (the repository's setup script does). A cold cache takes about a
minute on 2 cores; a warm one a fraction of a second. ``NUMBA_CACHE_DIR`` moves numba's cache (by
default it sits beside the package's sources, in ``__pycache__``). ``--report`` lists what was
compiled in this run only: with a warm cache, nothing (clear the cache or point ``NUMBA_CACHE_DIR``
at an empty folder to measure a cold one). The tissue step on threads is a kernel of its own,
compiled only with ``--threads`` (or at the first step of an env made with ``threads`` above 1):
a one-thread process never loads it. So is the tissue step in a scene with a cone, an elliptic
cylinder or a convex hull (``object=``: the collision kinds beyond pybullet's primitives), compiled
only with ``--objects`` or at its first step, about 100 s on 2 cores: the default scenes keep the
step compiled without those kinds.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import defaultdict

from ._jit_cache import Compiled, install_reporter, reporting

KINDS = ("tissue", "rigid")
"""The finger kinds of the registered ids; every other kind uses a subset of their kernels (the
segmented and FEM fingers need only the rigid kind's kernels: the arm's path and the state scatter)."""


def warm(kinds: tuple[str, ...] = KINDS, threads: int = 1, *, objects: bool = False) -> list[Compiled]:
    """Build a scene of each finger kind and step it once, and measure the tissue's penetration:
    every kernel the envs and the accuracy checks run is compiled or loaded; with ``threads``
    above 1 the tissue's step is the one on threads; with ``objects`` the scenes grasp a convex
    hull, whose step serves every object kind. Returns what was compiled (cache misses)."""
    from .config import SimConfig
    from .scene import GraspScene, SceneConfig

    sim = SimConfig(threads=threads)
    sim.solver_threads()  # a count above numba's fails here, naming it
    install_reporter()
    with reporting() as done:
        for kind in kinds:
            scene = GraspScene(SceneConfig(fingers=kind, sim=sim, object="pebble-0" if objects else None))
            try:
                scene.step()
                scene.world.penetration()
                if scene.fingers.no_tactile is None:
                    scene.fingers.tactile(scene.fingers.taxel_grid(2, 2))
            finally:
                scene.close()
    return done


def report(done: list[Compiled]) -> str:
    """A table of the compiled kernels: calls from Python (depth 0) and the callees compiled inside
    them, with their signatures counted (more than one: a specialisation that could be shared)."""
    by_name: dict[str, list[Compiled]] = defaultdict(list)
    for c in done:
        by_name[c.name].append(c)
    rows = sorted(by_name.items(), key=lambda kv: -sum(c.seconds for c in kv[1]))
    lines = [f"{'seconds':>8}  {'signatures':>10}  {'depth':>5}  kernel"]
    for name, cs in rows:
        depths = ",".join(str(d) for d in sorted({c.depth for c in cs}))
        lines.append(f"{sum(c.seconds for c in cs):8.2f}  {len(cs):10d}  {depths:>5}  {name}")
    top = sum(c.seconds for c in done if c.depth == 0)
    lines.append(f"{top:8.2f}  in all (depth 0: each nested compile is inside its caller's time)")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m softgrasp_env.compile", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    parser.add_argument("--report", action="store_true", help="list every kernel compiled, with its time")
    parser.add_argument("--threads", type=int, default=1,
                        help="also compile the tissue step on this many threads (SimConfig.threads; default 1)")  # fmt: skip
    parser.add_argument("--objects", action="store_true",
                        help="also compile the tissue step for scenes with a cone, elliptic cylinder or convex hull")  # fmt: skip
    ns = parser.parse_args(argv)
    tic = time.perf_counter()
    try:
        done = warm(KINDS) if ns.threads == 1 else warm(KINDS) + warm(("tissue",), ns.threads)
        if ns.objects:
            done += warm(("tissue",), objects=True)
    except ValueError as e:  # a bad thread count, named
        parser.error(str(e))
    seconds = time.perf_counter() - tic
    if not any(c.depth == 0 for c in done):
        print(f"the solver's kernels are compiled (loaded from numba's cache in {seconds:.1f} s)")
    if ns.report:
        print(report(done) if done else "nothing was compiled in this run (the cache was warm)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
