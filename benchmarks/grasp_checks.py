"""The env's own scripted grasp, measured as a new user would try it: the aligned gentle start
(SoftGraspEasy-v3 / SoftGraspEasyRigid-v3 with yaw, wedge, offset and cylinder position fixed at
0), 3 N per finger, every figure from one physics step to the next. (Release 0.6.0 also measures
the v1 ids' jump arm beside it.)

    PYTHONPATH=. python benchmarks/grasp_checks.py                          # every row
    PYTHONPATH=. python benchmarks/grasp_checks.py --rows dt,arm            # some

Rows: ``dt`` the scripted grasp at dt 1/1000 ... 1/120 s (held, lift, in-hand motion from
lift-off to the end, pad compression at the end, peak palm acceleration); ``arm`` the palm's peak
acceleration under a full-up action from rest; ``mass`` the heaviest cylinder the env episode
holds (bisection); ``friction`` the lowest friction scale that lifts 0.1 kg (bisection).
"""

from __future__ import annotations

import argparse
import math

import gymnasium as gym
import numpy as np

import softgrasp_env  # noqa: F401  (registers the ids)
from agents.scripted import ScriptedGraspPolicy
from softgrasp_env.config import SimConfig
from softgrasp_env.registration import TISSUE_GLOBAL, TISSUE_V4
from softgrasp_env.registration import make_as as make
from softgrasp_env.scene.scene import LEFT, PALM, RIGHT
from softgrasp_env.tasks.carry import CARRY_SLIDE_LIMIT

ALIGNED = {"yaw": 0.0, "jaw_wedge": 0.0, "lateral_offset": 0.0, "cylinder_xy": (0.0, 0.0)}
KINDS = {"soft": dict(fingers="tissue"), "soft-consistent": dict(fingers="tissue", coupling="consistent"),
         "rigid": dict(fingers="rigid"), "rigid_torsion": dict(fingers="rigid_torsion"),
         "soft-mu_k=0.7": dict(fingers="tissue", friction_kinetic=0.7),
         "soft-consistent-mu_k=0.7": dict(fingers="tissue", coupling="consistent", friction_kinetic=0.7),
         "soft-contact": dict(fingers="tissue", friction_law="contact"),
         "soft-contact-mu_k=0.7": dict(fingers="tissue", friction_law="contact", friction_kinetic=0.7),
         "soft-contact-16k": dict(fingers="tissue", friction_law="contact", particle_density=16_000.0),
         "soft-16k": dict(fingers="tissue", particle_density=16_000.0),
         "soft-v4": dict(fingers="tissue", **TISSUE_V4),
         "soft-v4-mu_k=0.7": dict(fingers="tissue", friction_kinetic=0.7, **TISSUE_V4),
         "soft-v4-16k": dict(fingers="tissue", particle_density=16_000.0, **TISSUE_V4),
         "soft-v5": dict(fingers="tissue", **TISSUE_GLOBAL),
         "soft-v5-16k": dict(fingers="tissue", particle_density=16_000.0, **TISSUE_GLOBAL)}  # fmt: skip
"""The finger kinds compared (the tissue at its default mu_k = mu_s, pybullet's one coefficient),
and the tissue with a two-coefficient law (mu_k 0.7 < mu_s 0.9); ``soft-v4`` is the v4 tissue
(registration.TISSUE_V4: SoftGraspEasy-v4's physics), ``soft-v5`` the same solved globally
(registration.TISSUE_GLOBAL: SoftGraspEasy-v5's)."""
NO_SLIP = CARRY_SLIDE_LIMIT
"""The mass and friction rows count a cylinder held only if it also moved at most this in the hand
from lift-off to the end [m], the v3 success's slide limit: a grasp that slips while the arm
accelerates and catches the cylinder again has not held it (the rigid twin did so, 'holding'
0.543 kg, above the bound); the soft pads' elastic sag (1-3 mm up to 0.4 kg) is no slip."""


def _make(kind: dict, version: str, *, dt: float = 1.0 / 240.0, **kwargs) -> gym.Env:
    kw = dict(kind)
    sim = SimConfig(dt=dt, coupling=kw.pop("coupling", "thesis"), iterations=kw.pop("iterations", SimConfig.iterations),
                    material_solve=kw.pop("material_solve", SimConfig.material_solve))  # fmt: skip
    env_id = f"SoftGraspEasyRigid-{version}" if kw.get("fingers") == "rigid" else f"SoftGraspEasy-{version}"
    return make(env_id, sim=sim, **kw, **kwargs)  # version "v3": SoftGraspEasy-v4 with TISSUE_V3 under kw


class Recorder:
    """Wraps a scene's step: after every physics step, the palm's velocity and the cylinder's pose
    in the palm's frame."""

    def __init__(self, env: gym.Env) -> None:
        self.env = env.unwrapped
        self.palm_v: list[np.ndarray] = []
        self.rel: list[np.ndarray] = []
        self.lift: list[float] = []
        self.gap: list[float] = []
        self.cyl_vz: list[float] = []
        self.press: list[float] = []
        scene = self.env.scene
        inner = scene.step

        def step(control=None):
            inner(control)
            self._record(scene)

        scene.step = step

    def _record(self, scene) -> None:
        col = scene.world.colliders
        self.palm_v.append(col.rigid_v[PALM].copy())
        c = scene.client
        pp, pq = c.getBasePositionAndOrientation(scene.gripper.body)
        cp, _ = c.getBasePositionAndOrientation(scene.cylinder)
        ip, iq = c.invertTransform(pp, pq)
        self.rel.append(np.asarray(c.multiplyTransforms(ip, iq, cp, [0, 0, 0, 1])[0]))
        self.lift.append(float(cp[2] - scene.cylinder_rest_z))
        # gap between each core's inner face and the cylinder's surface, along the palm's x axis
        rot = np.asarray(c.getMatrixFromQuaternion(pq)).reshape(3, 3)
        ax = rot[:, 0]
        fx = scene.config.finger_half_extents[0]
        r = scene.config.cylinder_radius
        left = float((np.asarray(cp) - col.rigid_x[LEFT]) @ ax) - fx - r
        right = float((col.rigid_x[RIGHT] - np.asarray(cp)) @ ax) - fx - r
        self.gap.append(0.5 * (left + right))
        self.cyl_vz.append(float(c.getBaseVelocity(scene.cylinder)[0][2]))
        solver = scene.world.solver
        if solver is not None:  # the tissue contacts' normal forces on the cylinder, magnitudes summed
            self.press.append(float(solver.contact_normal_force(scene.fingers.site.cylinder_shape).sum()))

    def cylinder_peak_acceleration(self, dt: float, *, window: int = 5, lift_off: float = 0.0005) -> float:
        """The cylinder's largest upward acceleration once off the ground [m/s^2], over ``window``
        physics steps (a contact's step-to-step jitter is not a load): what its grip must carry,
        m (g + a). On soft pads the cylinder bounces on them and peaks above the palm's."""
        vz, lift = np.asarray(self.cyl_vz), np.asarray(self.lift)
        up = np.flatnonzero(lift > lift_off)
        if len(vz) <= window or not len(up):
            return math.nan
        a = (vz[window:] - vz[:-window]) / (window * dt)
        return float(a[max(0, up[0] - window):].max())

    def peak_acceleration(self, dt: float) -> float:
        v = np.asarray(self.palm_v)
        return float(np.linalg.norm(np.diff(v, axis=0), axis=1).max() / dt) if len(v) > 1 else 0.0

    def in_hand_motion(self, lift_off: float = 0.002) -> float:
        """Largest distance of the cylinder centre in the palm's frame from where it was at
        lift-off (the first step 2 mm up) to the end [m]."""
        lift = np.asarray(self.lift)
        up = np.flatnonzero(lift > lift_off)
        if not len(up):
            return math.nan
        rel = np.asarray(self.rel)[up[0]:]
        return float(np.linalg.norm(rel - rel[0], axis=1).max())


def scripted_episode(kind: dict, version: str, *, dt: float = 1.0 / 240.0, options: dict | None = None,
                     **kwargs) -> dict:  # fmt: skip
    env = _make(kind, version, dt=dt, **kwargs)
    policy = ScriptedGraspPolicy.for_env(env)
    try:
        obs, _ = env.reset(seed=0, options={**ALIGNED, **(options or {})})
        rec = Recorder(env)
        u = env.unwrapped
        done, deviation = False, 0.0
        while not done:
            obs, _, term, trunc, info = env.step(policy(obs))
            done = term or trunc
            deviation = max(deviation, u.scene.world.tissue_deviation())
        pad = u.plan.scene.pad_thickness
        return {"held": bool(info["is_success"]), "lift": float(info["lift_height"]), "in_hand": rec.in_hand_motion(),
                "compression": pad - rec.gap[-1], "pad": pad, "peak_accel": rec.peak_acceleration(dt),
                "cyl_accel": rec.cylinder_peak_acceleration(dt),
                "press": float(np.mean(rec.press[-len(rec.press) // 5:])) if rec.press else math.nan,
                "diverged": bool(info["diverged"]), "deviation": deviation}  # fmt: skip
    finally:
        env.close()


def arm_from_rest(version: str, dt: float) -> float:
    """Peak palm acceleration [m/s^2] under a full-up action from rest (fingers open, nothing held)."""
    env = _make(KINDS["rigid"], version, dt=dt)
    try:
        env.reset(seed=0, options=ALIGNED)
        rec = Recorder(env)
        for _ in range(10):
            env.step(np.array([0.0, 0.0, 1.0, -1.0], dtype=np.float32))
        return rec.peak_acceleration(dt)
    finally:
        env.close()


def bisect(held, lo: float, hi: float, *, rel_tol: float = 0.02, limits: tuple[float, float] | None = None) -> float:
    """The boundary between held (lo) and not held (hi), geometric bisection. With ``limits`` a
    bracket that does not straddle the boundary is widened by 1.25 x per try, never past the
    limits (a tight bracket saves episodes where a coarser level says where the boundary lies);
    NaN if even the limits do not straddle it."""
    lo_limit, hi_limit = limits if limits is not None else (lo, hi)
    if not lo_limit <= lo < hi <= hi_limit:
        raise ValueError(f"bracket ({lo}, {hi}) must be increasing and inside the limits {limits}")
    while not held(lo):
        if lo <= lo_limit:
            return math.nan
        lo, hi = max(lo / 1.25, lo_limit), lo
    while held(hi):
        if hi >= hi_limit:
            return math.nan
        lo, hi = hi, min(hi * 1.25, hi_limit)
    while hi / lo > 1.0 + rel_tol:
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if held(mid) else (lo, mid)
    return math.sqrt(lo * hi)


def hold_bound(kind: dict, version: str, *, force: float = 3.0, mu: float = 0.9,
               bracket: tuple[float, float] = (0.05, 1.5), report=None, **kwargs) -> dict | None:  # fmt: skip
    """The heaviest cylinder the scripted env episode holds (bisection over 0.05-1.5 kg, from
    ``bracket`` [kg] if given, widened inside that range if it does not straddle; held with at
    most NO_SLIP in the hand) and Coulomb's bound 2 mu F / (g + a) with the palm's and the
    cylinder's peak acceleration a at that mass; for the tissue also mu sum N / (g + a), with the
    contacts' normal forces summed (``press``: Coulomb per contact bounds the friction by mu times
    their sum, which on a pad wrapped round the cylinder exceeds the squeeze). None if no mass in
    the range is held. ``kwargs`` go to gym.make."""
    g = 9.81

    def holds(m):
        r = scripted_episode(kind, version, options={"cylinder_mass": m}, **kwargs)
        ok = r["held"] and r["in_hand"] < NO_SLIP
        if report is not None:
            report(f"  mass {m:.4f} kg: {'held' if ok else 'not held'} (in hand {r['in_hand'] * 1e3:.2f} mm)")
        return ok

    m = bisect(holds, *bracket, limits=(0.05, 1.5))
    if math.isnan(m):
        return None
    r = scripted_episode(kind, version, options={"cylinder_mass": m / 1.01}, **kwargs)
    return {"mass": m, "coulomb": 2 * mu * force / (g + r["peak_accel"]),
            "coulomb_cylinder": 2 * mu * force / (g + r["cyl_accel"]), "press": r["press"],
            "coulomb_press": mu * r["press"] / (g + r["peak_accel"]), "peak_accel": r["peak_accel"],
            "cyl_accel": r["cyl_accel"]}  # fmt: skip


def lowest_friction(kind: dict, version: str, *, force: float = 3.0, mu: float = 0.9, mass: float = 0.1,
                    bracket: tuple[float, float] = (0.05, 1.0), report=None, **kwargs) -> dict | None:  # fmt: skip
    """The lowest friction scale at which the scripted env episode lifts ``mass`` (bisection over
    0.05-1 x the default, from ``bracket`` if given, widened inside that range if it does not
    straddle; held with at most NO_SLIP in the hand) and Coulomb's m (g + a) / (2 mu F)
    with the palm's and the cylinder's peak acceleration at that scale. None if none in the range
    lifts. ``kwargs`` go to gym.make."""
    g = 9.81

    def slips(s):
        r = scripted_episode(kind, version, options={"friction_scale": s}, **kwargs)
        ok = r["held"] and r["in_hand"] < NO_SLIP
        if report is not None:
            report(f"  friction scale {s:.4f}: {'lifts' if ok else 'slips'} (in hand {r['in_hand'] * 1e3:.2f} mm)")
        return not ok

    f = bisect(slips, *bracket, limits=(0.05, 1.0))
    if math.isnan(f):
        return None
    r = scripted_episode(kind, version, options={"friction_scale": f * 1.01}, **kwargs)
    return {"scale": f, "coulomb": mass * (g + r["peak_accel"]) / (2 * force) / mu,
            "coulomb_cylinder": mass * (g + r["cyl_accel"]) / (2 * force) / mu, "peak_accel": r["peak_accel"],
            "cyl_accel": r["cyl_accel"]}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rows", default="dt,arm,mass,friction")
    parser.add_argument("--kinds", default=",".join(KINDS), help="for the mass and friction rows, comma-separated")
    ns = parser.parse_args(argv)
    rows, versions = ns.rows.split(","), ["v3"]
    kinds = {name: KINDS[name] for name in ns.kinds.split(",")}
    mu, force, mass = 0.9, 3.0, 0.1
    if "dt" in rows:
        print("scripted grasp, aligned gentle start, 3 N per finger, 0.1 kg")
        print(f"{'ids':<4}{'kind':<18}{'dt':>8}{'held':>6}{'lift mm':>9}{'in-hand mm':>11}{'pad mm':>8}"
              f"{'compr. mm':>10}{'peak a m/s2':>12}")  # fmt: skip
        for version in versions:
            for name in ("soft", "rigid"):
                for hz in (1000, 480, 240, 120):
                    r = scripted_episode(KINDS[name], version, dt=1.0 / hz)
                    print(f"{version:<4}{name:<18}{'1/' + str(hz):>8}{str(r['held']):>6}{r['lift'] * 1e3:>9.1f}"
                          f"{r['in_hand'] * 1e3:>11.2f}{r['pad'] * 1e3:>8.1f}{r['compression'] * 1e3:>10.2f}"
                          f"{r['peak_accel']:>12.1f}", flush=True)  # fmt: skip
    if "arm" in rows:
        for version in versions:
            for hz in (1000, 240, 120):
                print(f"{version}: palm peak acceleration, full-up from rest, dt 1/{hz}: "
                      f"{arm_from_rest(version, 1.0 / hz):.2f} m/s^2", flush=True)  # fmt: skip
    for version in versions:
        if "mass" in rows:
            for name, kind in kinds.items():
                r = hold_bound(kind, version, force=force, mu=mu)
                if r is None:
                    print(f"{version}: heaviest cylinder held, env episode, {name}: none between 0.05 and 1.5 kg "
                          f"(held with at most {NO_SLIP * 1e3:g} mm in the hand)", flush=True)  # fmt: skip
                    continue
                m, palm, cyl = r["mass"], r["coulomb"], r["coulomb_cylinder"]
                print(f"{version}: heaviest cylinder held, env episode, {name}: {m:.3f} kg; Coulomb 2 mu F / (g + a): "
                      f"{palm:.3f} kg with the palm's a = {r['peak_accel']:.2f} m/s^2 ({m / palm - 1:+.1%}), "
                      f"{cyl:.3f} kg with the cylinder's a = {r['cyl_accel']:.2f} ({m / cyl - 1:+.1%})", flush=True)  # fmt: skip
                if not math.isnan(r["press"]):
                    press = r["coulomb_press"]
                    print(f"{version}: ... the tissue contacts press the cylinder with {r['press']:.3f} N in all "
                          f"(2F = {2 * force:.3f} N): mu sum N / (g + a) = {press:.3f} kg ({m / press - 1:+.1%})",
                          flush=True)  # fmt: skip
        if "friction" in rows:
            for name, kind in kinds.items():
                r = lowest_friction(kind, version, force=force, mu=mu, mass=mass)
                if r is None:
                    print(f"{version}: lowest friction that lifts 0.1 kg, {name}: none between 0.05 and 1 x the default "
                          f"(held with at most {NO_SLIP * 1e3:g} mm in the hand)", flush=True)  # fmt: skip
                    continue
                f, palm, cyl = r["scale"], r["coulomb"], r["coulomb_cylinder"]
                print(f"{version}: lowest friction that lifts 0.1 kg, {name}: {f:.3f} x the default; Coulomb m (g + a) "
                      f"/ 2F: {palm:.3f} x with the palm's a ({f / palm - 1:+.1%}), {cyl:.3f} x with the "
                      f"cylinder's a = {r['cyl_accel']:.2f} m/s^2 ({f / cyl - 1:+.1%})", flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
