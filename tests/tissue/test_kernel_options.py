"""The tissue step's kernels are compiled without numba's reference counting (tissue/jit.py): every
array a kernel receives was counted with an atomic increment and decrement per call, 35-40 % of the
step. The flag is an underscore option of numba's; if numba renamed or dropped it, the counts would
come back in silence, so this checks that each kernel the step calls per group, particle or contact
carries it. (That the results do not change is the recorded trajectories' test.)"""

from __future__ import annotations

from softgrasp_env.tissue import anchors, compliant, contacts, friction, integrate, shape_matching, solver
from softgrasp_env.tissue.jit import KERNEL

HOT = (
    solver._step, solver._sweep, compliant.compliant_sweep, compliant.sweep_body, compliant.project_group,
    compliant.continuum_groups, anchors.limit_deviation_of, anchors.project_anchors, anchors.snap_attached_of,
    contacts.collect_contacts, contacts.collect_pairs, contacts.project_shape_contacts, contacts.project_pairs,
    friction.friction_patches, friction._apply_patch_law, integrate.predict_particles, integrate.update_velocities,
    shape_matching.group_frames, shape_matching.balance_torques,
)  # fmt: skip


def test_the_step_kernels_run_without_reference_counting():
    assert KERNEL["_nrt"] is False
    for kernel in HOT:
        opts = kernel.targetoptions
        assert opts.get("_nrt") is False, f"{kernel.py_func.__qualname__} counts references: {opts}"
        assert opts.get("fastmath") == {"contract"} and opts.get("error_model") == "numpy"
