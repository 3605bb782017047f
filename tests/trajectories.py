"""Seeded trajectories of the registered ids (and of the settings reached only through kwargs),
recorded through the public API alone: ``gym.make``, ``reset``, ``step`` and the scripted policy.
``tests/data/trajectories_v3.npz`` holds the v3 ids as 0.5.0 shipped them, ``trajectories_more.npz``
the other ids and the settings reached only through kwargs, ``trajectories_v4.npz`` the soft ids'
v4 recorded on a CPU without AVX-512 and ``trajectories_v4_avx512.npz`` the same cases on one with
it (before the kernels lost numba's reference counting), ``trajectories_global_avx512.npz`` the v4
tissue under the global material solve, with AVX-512; ``tests/test_trajectories.py``
replays them and asserts bit-identical observations, rewards and flags, so a refactor or a speed-up
that changes behaviour cannot land quietly. (The v1/v2 ids' recording went with them: release 0.6.0
replays it.)

Record again (only when behaviour is meant to change, with the ids moving version, or the change
named and measured):

    python -m tests.trajectories --set v3 | more
    python -m tests.trajectories --set more --cases fem/scripted   # one case, the others kept
"""

from __future__ import annotations

import platform
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np

from softgrasp_env.registration import RETIRED_AS as REGISTERED_AS
from softgrasp_env.registration import TISSUE_V3, registered_as

DATA_V3 = Path(__file__).parent / "data" / "trajectories_v3.npz"
DATA_V4 = Path(__file__).parent / "data" / "trajectories_v4.npz"
DATA_MORE = Path(__file__).parent / "data" / "trajectories_more.npz"
DATA_V4_AVX512 = Path(__file__).parent / "data" / "trajectories_v4_avx512.npz"
DATA_GLOBAL_AVX512 = Path(__file__).parent / "data" / "trajectories_global_avx512.npz"
DATA_V4_ZNVER4 = Path(__file__).parent / "data" / "trajectories_v4_znver4.npz"
DATA_GLOBAL_ZNVER4 = Path(__file__).parent / "data" / "trajectories_global_znver4.npz"

INFO_FLAGS = ("is_success", "held", "carrying", "diverged", "action_clipped")
"""Boolean info entries recorded per step."""

# (case name, env id, gym.make kwargs, policy, steps). "random" draws actions in [-1.2, 1.2]
# (clipping exercised) and resets after an episode ends; "scripted" runs the scripted policy.
V3_IDS = ("SoftGrasp-v3", "SoftGraspRigid-v3", "SoftGraspSparse-v3", "SoftGraspGoal-v3", "SoftGraspEasy-v3",
          "SoftGraspEasyRigid-v3", "SoftGraspRigidTorsion-v3", "SoftGraspEasyRigidTorsion-v3")
GRIP_V3_TASK = {"squeeze_reference": "finger_force", "squeeze_weight": 0.5, "squeeze_charge_steps": "all",
                "squeeze_free": 0.0, "tactile_history": 1}  # fmt: skip
"""The keywords that take the grip ids' latest task back to the first one (the v3 grip ids', and
SoftGraspGrip-v4's on the v4 tissue): the whole squeeze charged in shares of the finger's force,
one taxel frame. The physics is the same."""
RETIRED_AS: dict[str, tuple[str, dict]] = {
    **REGISTERED_AS,
    "SoftGraspGoal-v3": ("SoftGraspGoal-v5", {**TISSUE_V3, "end_when_knocked_over": True}),
    "SoftGraspGrip-v3": ("SoftGraspGripRigid-v5", {**GRIP_V3_TASK, "fingers": "tissue"}),
    "SoftGraspGrip-v4": ("SoftGraspGrip-v6", GRIP_V3_TASK),
    "SoftGraspGripRigid-v3": ("SoftGraspGripRigid-v5", GRIP_V3_TASK),
    "SoftGraspGripRigidTorsion-v3": ("SoftGraspGripRigidTorsion-v5", GRIP_V3_TASK),
}
"""A recorded id that is retired, and the registered id with the keywords that are it: the package's
own table (softgrasp_env.registration.RETIRED_AS: the thesis tissue's ids are the v4 ids with
TISSUE_V3), and the ids retired before it had one (the goal's v3 is the thesis tissue's goal with
the lift task's ends; the grip ids' v3 and the soft grip's v4 are the latest grip ids with the
first task, :data:`GRIP_V3_TASK`, the soft v3 on the rigid twin's v3 tissue)."""


def _made(env_id: str, kwargs: dict) -> tuple[str, dict]:
    """The registered id and keywords of a case recorded on ``env_id`` with ``kwargs``."""
    return registered_as(env_id, kwargs, table=RETIRED_AS)


def _case(name: str, env_id: str, policy: str, steps: int, kwargs: dict | None = None) -> tuple[str, str, dict, str, int]:
    return (name, *_made(env_id, kwargs or {}), policy, steps)


V3_CASES: tuple[tuple[str, str, dict, str, int], ...] = (
    *(_case(f"{env_id}/random", env_id, "random", 130) for env_id in V3_IDS),
    *(_case(f"{env_id}/scripted", env_id, "scripted", 100) for env_id in V3_IDS),  # through the carry (3.5-5 s)
    _case("v3-consistent/scripted", "SoftGrasp-v3", "scripted", 100, {"sim": "consistent"}),
    _case("v3-dt1000/scripted", "SoftGraspEasy-v3", "scripted", 40, {"sim": "dt1000"}),
    _case("v3-dt120/scripted", "SoftGraspEasy-v3", "scripted", 60, {"sim": "dt120"}),
)  # fmt: skip
"""The v3 ids and the settings a speed-up might treat differently: the consistent coupling, one
world substep (1/1000 s) and four (1/120 s). (The recording also holds a case of the per-step
material, retired after 0.6.0; it is no longer replayed.)"""

MORE_CASES: tuple[tuple[str, str, dict, str, int], ...] = (
    *(_case(f"{env_id}/random", env_id, "random", 130) for env_id in (
        "SoftGraspGoal-v4", "SoftGraspGrip-v3", "SoftGraspGripRigid-v3", "SoftGraspGripRigidTorsion-v3")),
    _case("SoftGraspGoal-v4/scripted", "SoftGraspGoal-v4", "scripted", 100),
    _case("segmented/scripted", "SoftGraspEasy-v3", "scripted", 60, {"fingers": "segmented"}),
    _case("segmented/random", "SoftGrasp-v3", "random", 40, {"fingers": "segmented"}),
    _case("fem/scripted", "SoftGraspEasy-v3", "scripted", 12, {"fingers": "fem"}),
    _case("tissue-all-consistent/random", "SoftGrasp-v3", "random", 40, {"tissue_faces": "all", "sim": "consistent"}),
    _case("fast-preset/scripted", "SoftGrasp-v3", "scripted", 60, {"preset": "fast"}),
    ("ranges/random", "SoftGraspRigid-v3",
     {"friction_range": 0.3, "cylinder_mass_range": 0.5, "cylinder_radius_range": 0.005}, "random", 60),
    ("SoftGraspGripRigid-v5/random", "SoftGraspGripRigid-v5", {}, "random", 130),
)  # fmt: skip
"""What the v3 recording does not reach: the v4 goal id, the grip-force ids (the squeeze as the
action, taxels), and the settings reached only through kwargs - the segmented and FEM fingers, tissue
on every face with the consistent coupling, the fast preset, the randomised ranges. Recorded after
the v1/v2 ids (which covered these settings) were retired, on the same physics; the grip task's
margin charge on the carry's steps (the rigid twin's v5, recorded when it was registered: the
soft grip's v6 has the same charge on the physics the v4 cases replay)."""

V4_IDS = ("SoftGrasp-v4", "SoftGraspSparse-v4", "SoftGraspGoal-v5", "SoftGraspEasy-v4", "SoftGraspGrip-v4")
V4_CASES: tuple[tuple[str, str, dict, str, int], ...] = (
    *(_case(f"{env_id}/random", env_id, "random", 130) for env_id in V4_IDS),
    *(_case(f"{env_id}/scripted", env_id, "scripted", 100) for env_id in V4_IDS if "Grip" not in env_id),
    ("v4-fine/scripted", "SoftGraspEasy-v4", {"preset": "fine"}, "scripted", 40),
    ("v4-consistent/scripted", "SoftGrasp-v4", {"sim": "consistent"}, "scripted", 100),
)  # fmt: skip
"""The soft ids' v4 (the goal's v5) on the v4 tissue (the grip id with random squeezes: the scripted
grasp does not read taxels), its fine preset and the consistent coupling."""

GLOBAL_CASES: tuple[tuple[str, str, dict, str, int], ...] = (
    ("global-SoftGrasp-v4/scripted", "SoftGrasp-v5", {}, "scripted", 100),
    ("global-SoftGraspEasy-v4/random", "SoftGraspEasy-v5", {}, "random", 130),
    ("global-fine/scripted", "SoftGraspEasy-v5", {"preset": "fine"}, "scripted", 40),
)  # fmt: skip
"""The soft ids' v5: the v4 tissue under the global material solve, recorded as the v4 ids with
``material_solve="global"`` (what the v5 ids are) before they were registered: the scripted grasp
through the carry, random actions across a reset, and the fine preset. Recorded with AVX-512 on the
code before the solve was split by pad (for its threads), so that the replay shows the split kept
every bit."""

SETS = {"v3": (V3_CASES, DATA_V3), "more": (MORE_CASES, DATA_MORE), "v4": (V4_CASES, DATA_V4),
        "v4-avx512": (V4_CASES, DATA_V4_AVX512), "global-avx512": (GLOBAL_CASES, DATA_GLOBAL_AVX512),
        "v4-znver4": (V4_CASES, DATA_V4_ZNVER4), "global-znver4": (GLOBAL_CASES, DATA_GLOBAL_ZNVER4)}
"""The v4 cases are recorded without AVX-512 (``v4``), with it on an Intel Xeon (``v4-avx512``) and
on an AMD EPYC of LLVM's ``znver4`` (``v4-znver4``), so that each kind of machine replays them bit
for bit (and the others' prefix within tolerance): the continuum group solve, which only the v4
tissue runs, is then checked whole on each. The global solve's cases likewise on the two AVX-512
CPUs. numba compiles for the host CPU by name, and two CPUs with the same vector units round
differently where LLVM vectorises a reassociated sum for each its own way (the global solve's
substitutions): the Intel recordings replay on ``znver4`` within the prefix tolerance only."""


def _kwargs(kwargs: dict) -> dict:
    out = dict(kwargs)
    if out.get("sim") == "consistent":  # a SimConfig is not an npz-friendly literal: named here
        from softgrasp_env.config import SimConfig

        out["sim"] = SimConfig(coupling="consistent")
    elif isinstance(out.get("sim"), str) and out["sim"].startswith("dt"):
        from softgrasp_env.config import SimConfig

        out["sim"] = SimConfig(dt=1.0 / int(out["sim"][2:]))
    return out


def _obs_vector(obs) -> np.ndarray:
    if isinstance(obs, dict):
        return np.concatenate([obs["observation"], obs["achieved_goal"], obs["desired_goal"]])
    return np.asarray(obs)


def record(env_id: str, kwargs: dict, policy: str, steps: int, *, seed: int = 7) -> dict[str, np.ndarray]:
    """One case: arrays of the observations (reset's first), rewards, terminated / truncated, the
    info flags, lift heights and reward terms, step by step."""
    from agents.scripted import ScriptedGraspPolicy

    env = gym.make(env_id, **_kwargs(kwargs))
    rng = np.random.default_rng(seed + 1)
    scripted = ScriptedGraspPolicy.for_env(env)
    obs, info = env.reset(seed=seed)
    rows: dict[str, list] = {k: [] for k in ("obs", "reward", "terminated", "truncated", "lift", "terms", "reset",
                                             *INFO_FLAGS)}  # fmt: skip
    rows["obs"].append(_obs_vector(obs))
    rows["reset"].append(True)
    for _ in range(steps):
        if policy == "random":
            action = rng.uniform(-1.2, 1.2, size=4).astype(np.float32)
        else:
            action = scripted(obs)
        obs, reward, terminated, truncated, info = env.step(action)
        rows["obs"].append(_obs_vector(obs))
        rows["reward"].append(float(reward))
        rows["terminated"].append(bool(terminated))
        rows["truncated"].append(bool(truncated))
        rows["lift"].append(float(info["lift_height"]))
        terms = info.get("reward_terms", {})
        rows["terms"].append([float(terms[k]) for k in sorted(terms)])
        for k in INFO_FLAGS:
            rows[k].append(bool(info[k]))
        rows["reset"].append(False)
        if terminated or truncated:
            obs, info = env.reset()
            rows["obs"].append(_obs_vector(obs))
            rows["reset"].append(True)
    env.close()
    return {k: np.asarray(v) for k, v in rows.items()}


def fingerprint() -> str:
    """The instruction set, the CPU numba compiles for and the libraries a recording was made on:
    bit-identity is promised on the same ones (a CPU with other vector units may take another code
    path in a library's sin or exp and round differently, and numba compiles for the host CPU by
    LLVM's name for it, whose vector code rounds reassociated sums its own way). Recordings made
    before the CPU was part of it (``tests/data/*_avx512.npz``, ``trajectories_v3`` / ``more`` /
    ``v4``) end without it, and are replayed bit for bit only where the CPU's name is not known to
    differ (``matches``)."""
    import llvmlite.binding as llvm
    import numba
    import pybullet

    flags = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("flags"):
                have = set(line.split(":", 1)[1].split())
                flags = ",".join(f for f in ("fma", "avx2", "avx512f") if f in have)
                break
    except OSError:
        pass
    return (f"{platform.machine()} [{flags}] python {sys.version.split()[0]} numpy {np.__version__} "
            f"numba {numba.__version__} pybullet {pybullet.getAPIVersion()} cpu {llvm.get_host_cpu_name()}")  # fmt: skip


CPU_RECORDED = {DATA_V4_AVX512.name: "intel", DATA_GLOBAL_AVX512.name: "intel"}
"""The vendor of the CPU a recording made without the CPU's name in its fingerprint ran on, where
known (the AVX-512 recordings: an Intel Xeon); such a recording is not replayed bit for bit on
another vendor's CPU."""


def matches(recorded: str, here: str, file_name: str = "") -> bool:
    """True if a recording with fingerprint ``recorded`` (in file ``file_name``) replays bit for
    bit here (``here``: fingerprint()): the same fingerprint, or one recorded before the CPU's name
    was part of it that equals this one without it, on a CPU of the same vendor where known."""
    if recorded == here:
        return True
    head = here.rpartition(" cpu ")[0]
    if " cpu " in recorded or recorded != head:
        return False
    vendor = CPU_RECORDED.get(file_name)
    return vendor is None or _vendor() == vendor


def _vendor() -> str:
    """'intel', 'amd' or '' (unknown), from /proc/cpuinfo."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("vendor_id"):
                v = line.split(":", 1)[1].strip()
                return {"GenuineIntel": "intel", "AuthenticAMD": "amd"}.get(v, "")
    except OSError:
        pass
    return ""


def main(argv: list[str] | None = None) -> None:
    import argparse

    import softgrasp_env  # noqa: F401  (registers the ids)

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--set", choices=sorted(SETS), required=True,
                        help="which recording to make again (each is a file of its own)")
    parser.add_argument("--cases", default="",
                        help="comma-separated case names: record only these again and keep the file's others "
                             "(only on a machine whose fingerprint matches the file's)")  # fmt: skip
    ns = parser.parse_args(argv)
    cases, path = SETS[ns.set]
    out: dict[str, np.ndarray] = {"fingerprint": np.array(fingerprint())}
    if ns.cases:
        wanted = ns.cases.split(",")
        unknown = sorted(set(wanted) - {c[0] for c in cases})
        if unknown:
            parser.error(f"--cases: {unknown} are not cases of the {ns.set} set")
        old = dict(np.load(path))
        if not matches(str(old["fingerprint"]), fingerprint(), path.name):
            parser.error(f"--cases: {path.name} was recorded on {old['fingerprint']}, the one running is {fingerprint()}; "
                         "record the whole set instead")  # fmt: skip
        out.update({k: v for k, v in old.items() if k != "fingerprint" and k.rsplit("/", 1)[0] not in wanted})
        cases = tuple(c for c in cases if c[0] in wanted)
    for name, env_id, kwargs, policy, steps in cases:
        for key, arr in record(env_id, kwargs, policy, steps).items():
            out[f"{name}/{key}"] = arr
        print(f"{name}: {steps} steps")
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **out)
    print(f"wrote {path} ({path.stat().st_size / 1024:.0f} kB) on {out['fingerprint']}")


if __name__ == "__main__":
    main()
