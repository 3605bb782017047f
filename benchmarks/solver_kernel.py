"""Speed and sameness checks of the tissue kernel (softgrasp_env/tissue/solver.py::_step).

    python benchmarks/solver_kernel.py block        # us/step of a free 125-particle block
    python benchmarks/solver_kernel.py dispatch     # the call's fixed cost (8 particles, 0 iterations)
    python benchmarks/solver_kernel.py conserve     # momentum drift, zero gravity, damping 0
    python benchmarks/solver_kernel.py scene        # us/step of the grasp scene's tissue (352 p.)
    python benchmarks/solver_kernel.py demo         # whole scripted grasp: steps/s, tissue share
    python benchmarks/solver_kernel.py breakdown [--converged]   # SoftGrasp-v4's pads: a call's fixed
                                                    # cost, its cost per iteration, the group sweep alone
    python benchmarks/solver_kernel.py record DIR   # save reference outputs (run on the old code)
    python benchmarks/solver_kernel.py compare DIR  # max |difference| against the saved reference

Timings are best-of-N over repeated runs (the machine is shared and noisy).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from softgrasp_env.config import SimConfig, TissueConfig
from softgrasp_env.scene import SceneConfig
from softgrasp_env.tissue.builder import build_free_block
from softgrasp_env.tissue.rigid import Colliders, empty_colliders
from softgrasp_env.tissue.solver import TissueSolver
from softgrasp_env.tissue.state import TissueState, state_at_rest

# Grasp-scene steps whose solver inputs are captured for replay: approach, squeeze, lift, hold.
SNAP_STEPS = (100, 200, 300, 450, 700, 950)


def free_block(spacing: float = 0.008, half: float = 0.02, seed: int = 0, sim: SimConfig | None = None):
    model = build_free_block((half, half, half), TissueConfig(), spacing=spacing)
    sim = sim or SimConfig(gravity=0.0, damping=0.0)
    state = state_at_rest(model, np.zeros((1, 3)), np.array([[0.0, 0.0, 0.0, 1.0]]))
    rng = np.random.default_rng(seed)
    state.particle_v[:] = rng.normal(scale=0.01, size=state.particle_v.shape)
    return model, sim, state


def time_steps(solver: TissueSolver, state: TissueState, col: Colliders, steps: int, repeats: int) -> float:
    """Best-of-``repeats`` mean seconds per step over ``steps`` steps from a copy of ``state``."""
    solver.step(state.copy(), col)  # compile / load the cache
    best = np.inf
    for _ in range(repeats):
        s = state.copy()
        tic = time.perf_counter()
        for _ in range(steps):
            solver.step(s, col)
        best = min(best, (time.perf_counter() - tic) / steps)
    return best


def best_per_call(fn, args: tuple, calls: int, repeats: int) -> float:
    """Best-of-``repeats`` mean seconds per call of ``fn(*args)`` over ``calls`` calls."""
    best = np.inf
    for _ in range(repeats):
        tic = time.perf_counter()
        for _ in range(calls):
            fn(*args)
        best = min(best, (time.perf_counter() - tic) / calls)
    return best


def bench_block(repeats: int = 7) -> None:
    model, sim, state = free_block()
    solver = TissueSolver(model, sim)
    t = time_steps(solver, state, empty_colliders(), 300, repeats)
    print(f"block {model.particle_count} particles: {t * 1e6:.1f} us/step (best of {repeats})")


def bench_dispatch(repeats: int = 7) -> None:
    """The call's fixed cost: the smallest block (8 particles, one group of all 8 each) stepped at 1
    and 2 iterations, extrapolated to none (each iteration's work on 8 groups is ~9 us of it), and
    of that the Python front end (TissueSolver.step less the compiled _step called directly)."""
    from dataclasses import replace

    from softgrasp_env.tissue.solver import _step

    model, sim, state = free_block(spacing=0.008, half=0.008)
    col = empty_colliders()
    t = {}
    for it in (1, 2):
        t[it] = time_steps(TissueSolver(model, replace(sim, iterations=it)), state, col, 3000, repeats)
    solver = TissueSolver(model, replace(sim, iterations=1))
    solver.step(state.copy(), col)
    s = state.copy()
    args = (s.particle_x, s.particle_v, s.particle_q, s.particle_omega, s.group_q, s.particle_anchor_shape,
            s.particle_anchor_x, s.particle_anchor_slide, col.rigid_x, col.rigid_q, col.rigid_v, col.rigid_w,
            col.rigid_inv_mass, col.rigid_inv_inertia, col.rigid_axis, col.rigid_force, col.rigid_gravity,
            col.rigid_in_solve, col.shape_kind, col.shape_params, col.shape_rigid, col.shape_local_x,
            col.shape_local_q, *solver._tail_args)  # fmt: skip
    raw = best_per_call(_step, args, 3000, repeats)
    fixed = 2.0 * t[1] - t[2]
    print(f"dispatch, {model.particle_count} particles (best of {repeats}): {t[1] * 1e6:.2f} us/step at 1 iteration, "
          f"{t[2] * 1e6:.2f} at 2; fixed cost per call {fixed * 1e6:.2f} us, of which the Python front end "
          f"{(t[1] - raw) * 1e6:.2f} (the compiled call alone {raw * 1e6:.2f} us at 1 iteration)")  # fmt: skip


def angular_momentum(model, state) -> np.ndarray:
    from softgrasp_env.tissue.rotation import quat_to_matrix

    m = model.particle_mass
    orbital = np.sum(m[:, None] * np.cross(state.particle_x, state.particle_v), axis=0)
    inertia = model.particle_inertia_local()
    spin = np.zeros(3)
    for i in range(model.particle_count):
        r = quat_to_matrix(state.particle_q[i])
        spin += r @ (inertia[i] * (r.T @ state.particle_omega[i]))
    return orbital + spin


def conserve(steps: int = 1000) -> tuple[float, float]:
    model, sim, state = free_block()
    solver = TissueSolver(model, sim)
    m = model.particle_mass
    p0 = np.sum(m[:, None] * state.particle_v, axis=0)
    l0 = angular_momentum(model, state)
    col = empty_colliders()
    for _ in range(steps):
        solver.step(state, col)
    p1 = np.sum(m[:, None] * state.particle_v, axis=0)
    l1 = angular_momentum(model, state)
    dp = np.linalg.norm(p1 - p0) / np.linalg.norm(p0)
    dl = np.linalg.norm(l1 - l0) / np.linalg.norm(l0)
    print(f"conserve {steps} steps: linear drift {dp:.3e} (< 1e-9), angular drift {dl:.3e} (< 1e-3)"
          f" -> {'OK' if dp < 1e-9 and dl < 1e-3 else 'FAIL'}")  # fmt: skip
    return dp, dl


def _copy_colliders(col: Colliders) -> Colliders:
    from dataclasses import fields

    return Colliders(**{f.name: getattr(col, f.name).copy() for f in fields(col)})


def capture_scene() -> tuple[TissueSolver, list[tuple[TissueState, Colliders]], dict]:
    """Run the scripted grasp once; return the solver and the inputs of the steps in SNAP_STEPS,
    plus the scripted grasp's result and its time inside the tissue solver."""
    from softgrasp_env.accuracy import GraspPlan, run_grasp
    from softgrasp_env.scene import GraspScene

    scene = GraspScene(SceneConfig())
    solver = scene.world.solver
    snaps: list[tuple[TissueState, Colliders]] = []
    inner = solver.step
    tissue_time = [0.0]
    calls = [0]

    def step(state, col):
        if calls[0] in SNAP_STEPS:
            snaps.append((state.copy(), _copy_colliders(col)))
        calls[0] += 1
        tic = time.perf_counter()
        out = inner(state, col)
        tissue_time[0] += time.perf_counter() - tic
        return out

    solver.step = step
    try:
        res = run_grasp(scene, GraspPlan())
        final = scene.world.state.copy()
    finally:
        scene.close()
    solver.step = inner
    info = dict(result=res, tissue_seconds=tissue_time[0], final=final, held=res.held(GraspPlan()))
    return solver, snaps, info


def bench_scene(repeats: int = 7) -> None:
    solver, snaps, _ = capture_scene()
    total = 0.0
    for k, (state, col) in zip(SNAP_STEPS, snaps, strict=True):
        time_steps(solver, state, col, 1, 1)  # warm
        best = np.inf
        for _ in range(repeats):
            s = state.copy()
            tic = time.perf_counter()
            for _ in range(20):
                solver.step(s.copy(), col)
            best = min(best, (time.perf_counter() - tic) / 20)
        out = solver.step(state.copy(), col)
        total += best
        print(f"scene step {k:4d}: {best * 1e6:7.1f} us  ({out.contact_count} contacts, {out.pair_count} pairs)")
    print(f"scene mean over snapshots: {total / len(snaps) * 1e6:.1f} us/step")


def bench_demo(repeats: int = 3) -> None:
    best = None
    for _ in range(repeats):
        _, _, info = capture_scene()
        res = info["result"]
        if best is None or res.seconds < best[0].seconds:
            best = (res, info)
    res, info = best
    print(f"demo: {res.steps_per_second:.0f} steps/s, tissue {info['tissue_seconds'] / res.steps * 1e6:.1f} us/step,"
          f" rest {(res.seconds - info['tissue_seconds']) / res.steps * 1e6:.1f} us/step;"
          f" lift {res.lift_height * 100:.3f} cm (min {res.min_lift_during_hold * 100:.3f}),"
          f" pen {res.max_penetration * 1000:.3f} mm, intr {res.max_core_intrusion * 1000:.3f} mm,"
          f" {'HELD' if info['held'] else 'NOT HELD'}")  # fmt: skip


def capture_env(env_kwargs: dict, steps: int = 60) -> tuple[TissueSolver, TissueState, Colliders]:
    """SoftGrasp-v4 (with ``env_kwargs``), the scripted grasp from seed 0 for ``steps`` env steps (the
    pads pressed on the cylinder by then): the env's tissue solver and the next world step's inputs."""
    import gymnasium as gym

    import softgrasp_env  # noqa: F401  (registers the ids)
    from softgrasp_env.policies import ScriptedGraspPolicy

    env = gym.make("SoftGrasp-v4", **env_kwargs)
    obs, _ = env.reset(seed=0)
    policy = ScriptedGraspPolicy.for_env(env)
    for _ in range(steps):
        obs, *_ = env.step(policy(obs))
    world = env.unwrapped.scene.world
    return world.solver, world.state.copy(), _copy_colliders(world.colliders)


def _packed_views(solver: TissueSolver) -> dict[str, np.ndarray]:
    """The solver's packed model and scratch arrays by name (views, as _step sees them)."""
    from softgrasp_env.tissue import solver as solver_module

    f, i, b, layout = solver._packed
    n_f, n_i = len(solver_module._F_PACK), len(solver_module._I_PACK)
    out = {}
    for k, (name, _, cols) in enumerate(solver_module._PACK):
        buf = f if k < n_f else (i if k < n_f + n_i else b)
        o, rows, c = layout[k]
        out[name] = buf[o : o + rows * c].reshape(rows, c) if cols else buf[o : o + rows]
    return out


def bench_breakdown(converged: bool, repeats: int = 7) -> None:
    """Where a tissue step's time goes on SoftGrasp-v4's pads pressed on the cylinder: the step at
    1, 2, 3 and 6 iterations (its fixed cost and its cost per iteration, from the 3 -> 6 slope),
    and the group sweep alone (compliant.compliant_sweep on the solver's own buffers after a step)."""
    from dataclasses import replace

    from softgrasp_env.tissue.compliant import compliant_sweep

    for label, kwargs in (("default", {}), *((("converged", {"preset": "converged"}),) if converged else ())):
        solver, state, col = capture_env(kwargs)
        per = {}
        for it in (1, 2, 3, 6):
            sv = TissueSolver(solver.model, replace(solver.sim, iterations=it))
            per[it] = time_steps(sv, state, col, 30, repeats)
        slope = (per[6] - per[3]) / 3
        s = state.copy()
        solver.step(s, col)
        v, sim = _packed_views(solver), solver.sim
        args = (v["g_turn"], sim.rotation_iterations, v["body_off"], v["group_kappa"], sim.dt, v["g_off"], v["g_mem"],
                v["g_pack"], v["g_frame"], v["attached"], v["fixed"], v["rest_q"], v["rest_moment"], s.particle_x,
                v["xp"], v["qp"], s.group_q, v["moment"], v["g_u"], v["g_raw"], v["mass"], v["body_core_shape"],
                col.shape_rigid, solver._rig_x, solver._rig_q, col.rigid_inv_mass, col.rigid_inv_inertia, col.rigid_axis,
                col.rigid_in_solve, solver._imp_lin, solver._imp_ang, solver._coupling_imp, solver.model.continuum,
                v["g_cont"])  # fmt: skip
        compliant_sweep(*args)
        sweep = best_per_call(compliant_sweep, args, 50, repeats)
        n, groups = solver.model.particle_count, len(v["g_off"]) - 1
        members = len(v["g_mem"]) / groups
        print(f"{label}: {n} particles, {groups} groups of {members:.1f} members; a step at 1 / 2 / 3 / 6 iterations "
              + " / ".join(f"{per[k] * 1e6:.1f}" for k in (1, 2, 3, 6)) + " us")
        print(f"  per iteration {slope * 1e6:.1f} us ({slope * 1e6 / n:.3f} us per particle), fixed "
              f"{(per[3] - 3 * slope) * 1e6:.1f} us; at {sim.iterations} iterations "
              f"{per[sim.iterations] * 1e6 / n / sim.iterations:.3f} us per particle and iteration")
        print(f"  the group sweep alone {sweep * 1e6:.1f} us ({sweep * 1e6 / groups:.3f} us per group), "
              f"{sweep / slope:.0%} of an iteration")


STATE_FIELDS = ("particle_x", "particle_v", "particle_q", "particle_omega", "group_q")
OUTPUT_FIELDS = ("rigid_pred_x", "rigid_pred_q", "rigid_impulse", "rigid_angular_impulse", "coupling_impulse")


def _block_outputs(out: dict[str, np.ndarray]) -> None:
    model, sim, state = free_block()
    solver = TissueSolver(model, sim)
    for _ in range(200):
        solver.step(state, empty_colliders())
    for name in STATE_FIELDS:
        out[f"block.{name}"] = getattr(state, name)


def _step_outputs(solver, state, col, key: str, out: dict[str, np.ndarray]) -> None:
    o = solver.step(state, col)
    for name in STATE_FIELDS:
        out[f"{key}.{name}"] = getattr(state, name).copy()
    for name in OUTPUT_FIELDS:
        out[f"{key}.{name}"] = getattr(o, name).copy()


def record(path: Path) -> None:
    """Reference: the block after 200 steps; the inputs of the grasp's SNAP_STEPS and the outputs
    of one step from each; the final tissue state and the result of the whole scripted grasp."""
    from dataclasses import fields

    out: dict[str, np.ndarray] = {}
    _block_outputs(out)
    solver, snaps, info = capture_scene()
    for k, (state, col) in zip(SNAP_STEPS, snaps, strict=True):
        for f in fields(state):
            out[f"in{k}.state.{f.name}"] = getattr(state, f.name)
        for f in fields(col):
            out[f"in{k}.col.{f.name}"] = getattr(col, f.name)
        _step_outputs(solver, state.copy(), _copy_colliders(col), f"snap{k}", out)
    for name in ("particle_x", "particle_q"):
        out[f"demo.{name}"] = getattr(info["final"], name)
    r = info["result"]
    out["demo.result"] = np.array([r.lift_height, r.min_lift_during_hold, r.max_penetration, r.max_core_intrusion])
    path.mkdir(parents=True, exist_ok=True)
    np.savez(path / "reference.npz", **out)
    print(f"saved {path / 'reference.npz'}")


def compare(path: Path) -> None:
    """Replay the reference inputs with the current code; max |difference| per output. The
    single-step and block rows measure round-off; the whole grasp (demo.*) is chaotic, so any
    round-off change there grows to a visible but physically equivalent difference."""
    from dataclasses import fields

    ref = np.load(path / "reference.npz")
    new: dict[str, np.ndarray] = {}
    _block_outputs(new)
    solver, _, info = capture_scene()
    for k in SNAP_STEPS:
        state = TissueState(**{f.name: ref[f"in{k}.state.{f.name}"].copy() for f in fields(TissueState)})
        col = Colliders(**{f.name: ref[f"in{k}.col.{f.name}"].copy() for f in fields(Colliders)})
        _step_outputs(solver, state, col, f"snap{k}", new)
    for name in ("particle_x", "particle_q"):
        new[f"demo.{name}"] = getattr(info["final"], name)
    r = info["result"]
    new["demo.result"] = np.array([r.lift_height, r.min_lift_during_hold, r.max_penetration, r.max_core_intrusion])
    worst = 0.0
    for key in new:
        d = float(np.max(np.abs(ref[key] - new[key]))) if ref[key].size else 0.0
        if key.startswith("snap") and key.endswith(("particle_q", "group_q")):
            # q and -q are one rotation
            d = float(np.max(np.minimum(np.abs(ref[key] - new[key]), np.abs(ref[key] + new[key]))))
        if not key.startswith("demo"):
            worst = max(worst, d)
        print(f"{key:32s} max|diff| {d:.3e}{'' if d == 0.0 else '  <-- differs'}")
    print(f"demo result old: lift {ref['demo.result'][0] * 100:.3f} cm (min {ref['demo.result'][1] * 100:.3f}),"
          f" pen {ref['demo.result'][2] * 1000:.3f} mm, intr {ref['demo.result'][3] * 1000:.3f} mm")  # fmt: skip
    print(f"demo result new: lift {r.lift_height * 100:.3f} cm (min {r.min_lift_during_hold * 100:.3f}),"
          f" pen {r.max_penetration * 1000:.3f} mm, intr {r.max_core_intrusion * 1000:.3f} mm,"
          f" {'HELD' if info['held'] else 'NOT HELD'}")  # fmt: skip
    print(f"worst single-step/block difference: {worst:.3e}")


def main(argv: list[str]) -> None:
    what = argv[0] if argv else "block"
    if what == "block":
        bench_block()
    elif what == "dispatch":
        bench_dispatch()
    elif what == "conserve":
        conserve()
    elif what == "scene":
        bench_scene()
    elif what == "demo":
        bench_demo()
    elif what == "breakdown":
        bench_breakdown("--converged" in argv)
    elif what == "record":
        record(Path(argv[1]))
    elif what == "compare":
        compare(Path(argv[1]))
    else:
        raise SystemExit(__doc__)


if __name__ == "__main__":
    main(sys.argv[1:])
