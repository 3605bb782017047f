"""The tissue solver on threads (SimConfig.threads, SOFTGRASP_THREADS): each finger's pad swept on a
thread of its own gives the same result to the bit as one thread, and bad settings fail clearly."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numba
import numpy as np
import pytest

import softgrasp_env  # noqa: F401  (registers the ids)
from softgrasp_env.config import THREADS_ENV, SimConfig
from softgrasp_env.tissue.compliant import bodies_independent

needs_two = pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="numba has one thread here")


# Every run with more than one thread goes to a fresh process: a thread pool fixes numba's
# NUMBA_NUM_THREADS for the process that starts it (numba refuses a different value afterwards),
# and other tests here set that variable for the env processes they start (agents.threads).
_CHILD = """
import sys
import warnings
import gymnasium as gym
import numpy as np
import softgrasp_env
from softgrasp_env.config import SimConfig

def run(threads, coupling, steps, solve="groups", **kwargs):
    solve, _, linear = solve.partition("+")  # "global+multigrid": the global solve by V-cycles
    sim = SimConfig(threads=threads, coupling=coupling, material_solve=solve, global_linear_solve=linear or "direct")
    env = gym.make("SoftGraspEasy-v4", sim=sim, **kwargs)
    obs, _ = env.reset(seed=5)
    rng = np.random.default_rng(5)
    rows = [obs]
    for _ in range(steps):
        obs, reward, terminated, truncated, _ = env.step(rng.uniform(-1.0, 1.0, size=4).astype(np.float32))
        rows.append(np.append(obs, reward))
        if terminated or truncated:
            obs, _ = env.reset()
    world = env.unwrapped.scene.world
    assert world.solver._threaded == (threads > 1), "the threaded passes did not run"
    out = (np.concatenate(rows), world.state.particle_x.copy(), world.state.particle_v.copy())
    env.close()
    return out

what = sys.argv[1]
if what == "pool":
    import os
    import numba
    from numba.np.ufunc import parallel
    run(1, "thesis", 5)
    assert not parallel._is_initialized, "one thread started numba's thread pool"
    # what training does for its env processes after the first env: a new NUMBA_NUM_THREADS, then
    # a compile (numba re-reads its configuration there and fails if the pool has started)
    os.environ["NUMBA_NUM_THREADS"] = "1"
    numba.njit(lambda a: a + 1)(1)
elif what == "same":
    density, steps, solve = float(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
    one = run(1, sys.argv[2], steps, solve, particle_density=density)
    two = run(2, sys.argv[2], steps, solve, particle_density=density)
    assert all(a.tobytes() == b.tobytes() for a, b in zip(one, two)), "1 and 2 threads differ"
elif what == "warn":
    from softgrasp_env.accuracy import _Pad
    from softgrasp_env.config import TissueConfig
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pad = _Pad(0.0, TissueConfig(), SimConfig(threads=2))
        pad.step()
        pad.step()  # once per solver, not every step
    said = [str(w.message) for w in caught if issubclass(w.category, RuntimeWarning)]
    assert len(said) == 1 and "2 threads asked for, running on one" in said[0], said
    assert not pad.solver._threaded
else:
    kwargs = {"threads": 2} if what == "keyword" else {}
    env = gym.make("SoftGraspEasy-v4", **kwargs)
    env.reset(seed=0)
    env.step(env.action_space.sample())
    assert env.unwrapped.scene.world.solver._threaded, "the threaded passes did not run"
    env.close()
print("ok")
"""


def _child(*args, env=None):
    """Run _CHILD with ``args`` in a fresh interpreter; fails the test with its output if it fails."""
    root = Path(__file__).resolve().parents[2]
    environ = {k: v for k, v in os.environ.items() if k not in ("NUMBA_NUM_THREADS", THREADS_ENV)}
    environ["PYTHONPATH"] = os.pathsep.join(filter(None, [str(root), environ.get("PYTHONPATH")]))
    environ.update(env or {})
    done = subprocess.run([sys.executable, "-c", _CHILD, *args], env=environ, capture_output=True, text=True,
                          timeout=1200)  # fmt: skip
    assert done.returncode == 0 and done.stdout.strip().endswith("ok"), done.stdout[-2000:] + done.stderr[-4000:]


@needs_two
@pytest.mark.parametrize(("coupling", "solve"), [("thesis", "groups"), ("consistent", "groups"), ("thesis", "global")])
@pytest.mark.parametrize(("density", "steps"), [(4_000, 130), (16_000, 25)])
def test_two_threads_give_one_threads_result_to_the_bit(coupling, solve, density, steps):
    """SoftGraspEasy-v4 with random actions at the default density for 130 steps (past the
    100-step episode, so across a reset) and at 16,000 per m^2 (the fine preset's) for 25: the
    observations, rewards and every particle's position and velocity, on 1 and 2 threads. Under
    the consistent coupling each core slides inside its own pad's sweep; under the global material
    solve each pad's block of the factor is solved on its own thread."""
    _child("same", coupling, str(density), str(steps), solve)


@needs_two
def test_two_threads_give_one_threads_result_to_the_bit_under_the_multigrid_solve():
    """The global solve by V-cycles (global_linear_solve="multigrid") at 64,000 per m^2, where each
    pad's system has two levels: each pad's cycles on its own thread, its own stretch of the
    levels' scratch, the same result to the bit as one thread (8 random steps)."""
    _child("same", "thesis", "64000", "8", "global+multigrid")


def test_one_thread_never_loads_parallel_code():
    """A one-thread step must not start numba's thread pool: once started, the pool refuses any
    change of NUMBA_NUM_THREADS, which the training code makes for its env processes (a build
    whose serial step called the parallel passes failed 228 tests that way)."""
    _child("pool")


def test_the_thread_count_is_checked(monkeypatch):
    with pytest.raises(ValueError, match="threads"):
        SimConfig(threads=0)
    with pytest.raises(ValueError, match="threads"):
        SimConfig(threads=2.5)
    monkeypatch.setenv(THREADS_ENV, "two")
    with pytest.raises(ValueError, match=f"{THREADS_ENV} must be an integer"):
        SimConfig().solver_threads()
    monkeypatch.setenv(THREADS_ENV, "0")
    with pytest.raises(ValueError, match=f"{THREADS_ENV} must be an integer"):
        SimConfig().solver_threads()
    monkeypatch.setenv(THREADS_ENV, str(numba.config.NUMBA_NUM_THREADS + 1))
    with pytest.raises(ValueError, match="NUMBA_NUM_THREADS"):
        SimConfig().solver_threads()
    monkeypatch.setenv(THREADS_ENV, "1")
    assert SimConfig().solver_threads() == 1
    assert SimConfig(threads=1).solver_threads() == 1  # the keyword wins over the variable
    monkeypatch.delenv(THREADS_ENV)
    assert SimConfig().solver_threads() == 1  # one thread by default


@needs_two
@pytest.mark.parametrize("how", ["variable", "keyword"])
def test_the_variable_and_the_keyword_set_the_threads_of_an_env(how):
    _child(how, env={THREADS_ENV: "2"} if how == "variable" else None)
    with pytest.raises(ValueError, match="threads"):
        gym.make("SoftGraspEasy-v4", threads=0)


def test_pads_that_share_a_core_or_have_none_stay_on_one_thread():
    class Model:
        body_core_shape = np.array([0, 1])
        body_particle_offsets = np.array([0, 4, 9])
        particle_count = 9

    assert bodies_independent(Model, np.array([0, 1]))
    assert not bodies_independent(Model, np.array([3, 3]))  # both cores on one rigid slot
    Model.particle_count = 10
    assert not bodies_independent(Model, np.array([0, 1]))  # a particle outside every body
    Model.particle_count = 9
    Model.body_core_shape = np.array([-1, 1])
    assert not bodies_independent(Model, np.array([0, 1]))  # a pad without a core


@needs_two
def test_threads_that_cannot_be_given_are_named_in_a_warning():
    """A free block has no core: its passes cannot be split by pad, so threads=2 runs on one thread
    and says so once (in a fresh process, as every test here that asks for two threads)."""
    _child("warn")
