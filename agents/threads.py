"""Threads per process for training and evaluation: one torch thread unless asked
otherwise in the learner's process, and one thread (torch, BLAS, numba) in every env process it
starts.

Why one: on a 2-core cloud VM (no GPU), SB3's SAC with torch's default of two threads, beside a second
training process (two seeds at a time, as the baselines were trained), sampled 7 env steps/s end
to end, and 104 with one torch thread each, the same run; ``benchmarks/torch_threads.py``
measures it again. The env's kernels are serial, so numba's threads only compete with the learner.
A machine with cores to spare may give the learner more with ``--torch-threads N``.
"""

from __future__ import annotations

import os

DEFAULT_TORCH_THREADS = 1
"""The learner's torch threads when none are asked for."""

CHILD_THREAD_VARIABLES = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS")
"""Read by torch, BLAS and numba when a process starts: set here so that env processes started
later (SB3's SubprocVecEnv, Ray's workers) take one thread each."""


def threads_error(n: object) -> str | None:
    """Why ``n`` is not a thread count (None when it is one)."""
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        return f"torch threads must be a whole number >= 1, got {n!r}"
    cpus = os.cpu_count() or 1
    if n > 4 * cpus:
        return f"torch threads {n} is more than 4 x this machine's {cpus} CPUs"
    return None


def child_environment(torch_threads: int = DEFAULT_TORCH_THREADS) -> dict[str, str]:
    """The environment variables for a process that runs envs (one thread each) - or, with
    ``torch_threads``, a learner (Ray's trial actors): OMP/MKL/OpenBLAS get ``torch_threads``,
    numba 1 (its kernels here are serial)."""
    env = {name: str(torch_threads) for name in CHILD_THREAD_VARIABLES}
    env["NUMBA_NUM_THREADS"] = "1"
    return env


def set_threads(torch_threads: int = DEFAULT_TORCH_THREADS) -> dict[str, int]:
    """Give this process ``torch_threads`` torch threads, and make the env processes it starts
    later take one thread each; returns the count in effect. A bad count is a ValueError naming it.

    numba is left alone in this process: the package's kernels are serial, so numba never starts
    its thread pool here, and starting it (``numba.set_num_threads``) would fix its size for the
    process (numba refuses a different NUMBA_NUM_THREADS afterwards, and with its OpenMP layer it
    would set torch's OpenMP count too)."""
    problem = threads_error(torch_threads)
    if problem:
        raise ValueError(problem)
    for name, value in child_environment(1).items():
        os.environ[name] = value  # for processes started from here on (env subprocesses)
    import torch

    torch.set_num_threads(torch_threads)
    return {"torch": torch.get_num_threads()}
