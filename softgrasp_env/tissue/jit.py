"""How the tissue's kernels are compiled: one set of numba options for every kernel of the step.

- ``cache=True``: compiled once per install, loaded from disk afterwards (softgrasp_env.compile).
- ``error_model="numpy"``: a division by zero gives inf / NaN as numpy's does, without the branch
  and exception path Python's error model puts around every division.
- ``fastmath={"contract"}``: multiply-adds may fuse into FMA instructions, nothing else of
  fast-math (no reassociation, no reciprocal approximations, NaN and inf kept): results are
  deterministic for a given instruction set.
- ``_nrt=False``: no reference counting. numba counts references to every array a function
  receives, with an atomic increment on entry and decrement on exit (NRT_incref / NRT_decref,
  ``lock incq``), and calls to kernels that take twenty arrays - one group solve per group and
  pass, one anchor projection per particle - spent 35-40 % of the tissue step in them (measured
  with perf on the converged pads). The kernels allocate nothing and return no arrays (the solver
  owns every buffer), so there is nothing for the counts to keep alive. It is numba's own flag for
  code that does not need its runtime (an underscore option of ``numba.njit``); a kernel that
  must allocate (contacts.max_penetration) keeps the runtime, and a test checks the flag is set
  where it matters (the test suite). Results are unchanged to the bit.
"""

from __future__ import annotations

KERNEL = {"cache": True, "error_model": "numpy", "fastmath": {"contract"}, "_nrt": False}
"""numba.njit options of the tissue step's kernels (module docstring)."""

__all__ = ["KERNEL"]
