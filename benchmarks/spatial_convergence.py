"""Does the tissue converge in space? Its pad pressed by the cylinder at 4,000 ... 1,024,000 particles
per m^2 of face (others with ``--densities``), at the default dt and iterations, against the
independent finite-element reference of the same pad (benchmarks/pad_reference.py).

    PYTHONPATH=. python benchmarks/spatial_convergence.py [--quick] [--env] [--material continuum] [--layers 1,2,4]
        [--out benchmarks/out]

The rig (``PadRig``) is as close to the reference as the tissue allows: one finger core (the
scene's 16 x 40 x 60 mm box) held still, tissue on its inner face only (the face the cylinder
presses; the default finger also has its tip covered), built by the builder the fingers use, and
the scene's cylinder (radius 30 mm) standing upright, longer than the face, moved kinematically
along the face's normal by the rig, not by pybullet. The tissue solver runs alone at the default
SimConfig (dt 1/240 s, 3 iterations) in the world steps the env would take for a 50 g finger
(compliant.world_substeps), gravity off. Compression is measured as grasp_checks does it: the pad's
depth (extrude + normal radius, 11 mm) less the gap between core face and cylinder, i.e. the
cylinder's travel from first touching the undeformed pad.

- **Normal**: frictionless (friction_static 0, as the reference's cylinder), the cylinder driven in
  at ``RAMP_SPEED`` with a hold at each target; the load the cylinder feels (the tissue's impulses
  on it over a step, / dt) is read each step, and a secant search finds the compression at which
  the held load is 1, 3 and 6 N (within ``FORCE_TOL``).
- **Tangential**: default friction (mu 0.9); pressed to 3 N, then the cylinder moved down along
  its own axis to 0.25 mm and to 0.75 mm, held at each: one pad's compliance is the 0.5 mm
  (``SHEAR``) over the change in the axial load (the contact sticks: the load stays within a third
  of mu N). The grasp's incipient-slip benchmark
  reports the same per pair of pads (half this).

Printed: per density, the particles, the mean group radius of gyration l, the pad's stiffness
against its core (compliant.core_stiffness), the compression under each load and the reference's
at each Poisson ratio, the error against each, the observed order between successive densities
(the particle spacing halves from one to the next); the tangential compliance likewise. CSV to
``--out``/spatial_convergence.csv, figure spatial_convergence.png. With ``--env``, a second row per
density: the env's scripted grasp (SoftGraspEasy-v3, 3 N per finger, grasp_checks.scripted_episode).
One process, one thread; about 6 minutes (``--quick``: 4,000 and 16,000 per m^2, one load).

``--layers`` (comma list, default 1): the rig's pad is built with each TissueConfig.layers in turn
(element layers through the thickness), one row per (density, layers); the observed orders are
taken along the densities of each layer count. Each row also gives the inner layers' clearance
from the cylinder: the least, over the holds of the normal search, of an inner particle's distance
from the cylinder less its ellipsoid's support radius along the cylinder's normal (negative: an
inner particle touches the cylinder as the surface does). The CSV has a ``layers`` column; its and
the figure's names get ``_layers`` when any count but 1 is run.
"""

from __future__ import annotations

import argparse
import csv
import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from softgrasp_env.config import GROUP_ENERGIES, SimConfig, TissueConfig
from softgrasp_env.scene import SceneConfig
from softgrasp_env.tissue.builder import CoreShape, build_combined_body, surface_particles
from softgrasp_env.tissue.collision import SHAPE_CODES
from softgrasp_env.tissue.compliant import core_stiffness, world_substeps
from softgrasp_env.tissue.model import with_core_shapes
from softgrasp_env.tissue.rigid import Colliders
from softgrasp_env.tissue.rotation import quat_to_matrix
from softgrasp_env.tissue.solver import TissueSolver
from softgrasp_env.tissue.state import state_at_rest

OUT = Path(__file__).resolve().parent / "out"
DENSITIES = (4_000.0, 16_000.0, 64_000.0, 256_000.0, 1_024_000.0)
LOADS = (1.0, 3.0, 6.0)
RAMP_SPEED = 0.01
"""How fast the rig moves the cylinder between holds [m/s]."""
HOLD = 0.25
"""Each hold [s]; the load is the mean over its last fifth (the pad settles in about 0.05 s: its
damping, SimConfig.damping, 300/s)."""
FORCE_TOL = 0.005
"""Relative tolerance on the held load of each target [-]."""
SHEAR = 5e-4
"""The tangential move between the two holds [m]."""


class PadRig:
    """One finger's inner face of tissue, its core fixed, pressed by a kinematic cylinder."""

    def __init__(self, density: float, *, friction: float | None = None, sim: SimConfig | None = None,
                 tissue: TissueConfig | None = None, punch: float | None = None) -> None:  # fmt: skip
        """``punch``: instead of the cylinder, a flat rigid punch of this half-width across the face
        [m] (a box longer than the face, its flat side parallel to the core's face)."""
        if punch is not None and not punch > 0.0:
            raise ValueError(f"punch must be a positive half-width [m], got {punch!r}")
        scene = SceneConfig()
        base = tissue or TissueConfig()
        kw = {"particle_density": density}
        if friction is not None:
            kw["friction_static"] = friction
        self.tissue = replace(base, **kw)
        self.sim = replace(sim or SimConfig(), gravity=0.0)
        hx, hy, hz = scene.finger_half_extents
        self.face_x = hx
        self.face_height = 2.0 * hz
        """The face's height along the cylinder's axis [m]; the core's centre is the origin."""
        self.radius = scene.cylinder_radius
        self.pad = self.tissue.extrude + self.tissue.normal_radius
        model = build_combined_body(CoreShape("box", half_extents=(hx, hy, hz)), self.tissue, faces=("+x",))
        self.model = with_core_shapes(model, np.array([0]))
        self.substeps = world_substeps(self.model, np.array([scene.finger_mass]), self.sim.dt, self.sim.material_solve)
        self.h = self.sim.dt / self.substeps
        self.solver = TissueSolver(self.model, replace(self.sim, dt=self.h) if self.substeps > 1 else self.sim)
        ident = np.array([[0.0, 0.0, 0.0, 1.0]])
        self.col = Colliders(
            rigid_x=np.zeros((2, 3)), rigid_q=np.repeat(ident, 2, axis=0), rigid_v=np.zeros((2, 3)),
            rigid_w=np.zeros((2, 3)), rigid_inv_mass=np.zeros(2), rigid_inv_inertia=np.zeros((2, 3)),
            rigid_gravity=np.zeros(2, dtype=np.bool_), rigid_in_solve=np.zeros(2, dtype=np.bool_),
            shape_kind=np.array([SHAPE_CODES["box"], SHAPE_CODES["cylinder" if punch is None else "box"]], dtype=np.int32),
            shape_params=np.array([[hx, hy, hz], [self.radius, 2.0 * hz, 0.0] if punch is None
                                   else [self.radius, punch, 2.0 * hz]]),
            shape_rigid=np.array([0, 1], dtype=np.int32), shape_local_x=np.zeros((2, 3)),
            shape_local_q=np.repeat(ident, 2, axis=0),
        )  # fmt: skip
        self.compression = -1e-3  # start 1 mm clear of the pad
        self.axial = 0.0
        self._place()
        self.state = state_at_rest(self.model, self.col.rigid_x[:1], self.col.rigid_q[:1])
        self.force = np.zeros(3)
        self.steps = 0
        # the inner layers (TissueConfig.layers > 1): free particles that are not the surface
        self.inner = np.flatnonzero(~self.model.particle_attached & ~surface_particles(self.model))
        self.inner_clearance = math.inf
        """The least inner_gap() over the holds so far [m] (inf: no inner layer)."""

    @property
    def particle_count(self) -> int:
        return self.model.particle_count

    def _place(self) -> None:
        self.col.rigid_x[1] = (self.face_x + self.pad + self.radius - self.compression, 0.0, self.axial)

    def step(self, velocity: np.ndarray | None = None) -> np.ndarray:
        """One step of sim.dt with the cylinder moving at ``velocity`` [m/s] (x: into the pad);
        returns the load the cylinder feels over it, (normal, y, axial) [N]."""
        v = np.zeros(3) if velocity is None else np.asarray(velocity, dtype=np.float64)
        total = np.zeros(3)
        for _ in range(self.substeps):
            self.col.rigid_v[1] = (-v[0], v[1], v[2])
            out = self.solver.step(self.state, self.col)
            total += out.rigid_impulse[1]
            self.compression += v[0] * self.h
            self.axial += v[2] * self.h
            self._place()
        self.steps += 1
        # the tissue's push on the cylinder is along +x (out of the pad): the normal load
        self.force = total / self.sim.dt
        return self.force

    def move_to(self, compression: float, *, axial: float | None = None, speed: float = RAMP_SPEED) -> None:
        """Drive the cylinder to ``compression`` (and ``axial``) at ``speed``, then stop."""
        dt = self.sim.dt
        for target, k in ((compression, 0), (axial, 2)):
            if target is None:
                continue
            now = self.compression if k == 0 else self.axial
            n = max(1, math.ceil(abs(target - now) / (speed * dt)))
            v = np.zeros(3)
            v[k] = (target - now) / (n * dt)
            for _ in range(n):
                self.step(v)
            if k == 0:
                self.compression = target
            else:
                self.axial = target
            self._place()

    def hold(self, seconds: float = HOLD) -> np.ndarray:
        """Hold still; the mean load over the last fifth [N]."""
        n = max(5, round(seconds / self.sim.dt))
        loads = [self.step().copy() for _ in range(n)]
        self.inner_clearance = min(self.inner_clearance, self.inner_gap())
        return np.mean(loads[-max(1, n // 5):], axis=0)

    def inner_gap(self) -> float:
        """The inner layers' least clearance from the cylinder now [m]: an inner particle's distance
        from the cylinder's side less its ellipsoid's support radius along the side's normal
        (collision.support_radius); inf without inner layers."""
        if self.inner.size == 0:
            return math.inf
        x = self.state.particle_x[self.inner]
        q = self.state.particle_q[self.inner]
        r = self.model.particle_radii[self.inner]
        d = x[:, :2] - self.col.rigid_x[1, :2]  # the cylinder stands along z
        rho = np.linalg.norm(d, axis=1)
        n = np.zeros_like(x)
        n[:, :2] = d / rho[:, None]
        local = np.stack([quat_to_matrix(qi).T @ ni for qi, ni in zip(q, n, strict=True)])
        support = np.sqrt(((r * local) ** 2).sum(axis=1))
        return float((rho - self.radius - support).min())

    def contact_width(self) -> float:
        """The contact strip's pressure-weighted RMS half-width across the strip after the last
        step [m]: sqrt(sum lambda y^2 / sum lambda) over the tissue's contacts with the cylinder, y
        a contact's particle's offset across the face from the cylinder's axis. For the reference's
        pressure profile the same moment of p(y) (a Hertzian strip's is a / 2, a parabolic one's
        a / sqrt 5); unlike the farthest touching contact it is not quantised to the particle
        spacing."""
        lc = self.solver.last_contacts()
        n = lc.count
        keep = ~lc.inner[:n] & (lc.normal_lambda[:n] > 0.0) & (lc.shape[:n] == 1)
        if not keep.any():
            return math.nan
        y = self.state.particle_x[lc.particle[:n][keep], 1] - self.col.rigid_x[1, 1]
        w = lc.normal_lambda[:n][keep]
        return float(math.sqrt(np.sum(w * y * y) / np.sum(w)))

    def press_to(self, force: float, *, guess: float) -> tuple[float, float]:
        """Compression at which the held normal load is ``force`` [N] (secant on the holds, from
        ``guess``): (compression [m], held load [N])."""
        pts: list[tuple[float, float]] = []
        c = guess
        for _ in range(12):
            self.move_to(c)
            f = float(self.hold()[0])
            pts.append((c, f))
            if abs(f - force) <= FORCE_TOL * force:
                return c, f
            if len(pts) == 1 or pts[-1][1] == pts[-2][1]:
                # first hold: scale as the thin layer does, F ~ delta^1.5
                c_new = c * (force / max(f, 1e-3)) ** (2.0 / 3.0) if f > 0 else c + 5e-4
            else:
                (c0, f0), (c1, f1) = pts[-2], pts[-1]
                c_new = c1 + (force - f1) * (c1 - c0) / (f1 - f0)
            c = float(np.clip(c_new, 0.5 * c, 2.0 * c + 1e-4))
        return c, f

    def group_radius(self) -> tuple[float, float]:
        """(mean group radius of gyration l [m], mean share of the groups' second moment along the
        face normal [-]): kappa = G / (rho l^2) (builder.group_kappa)."""
        m = self.model
        ls, shares = [], []
        for i in range(m.particle_count):
            e = slice(int(m.group_offsets[i]), int(m.group_offsets[i + 1]))
            w = m.particle_mass[m.group_members[e]]
            q = m.group_rest_offset[e]
            mom = (w[:, None] * q * q).sum(axis=0) / w.sum()
            ls.append(math.sqrt(mom.sum()))
            shares.append(mom[0] / mom.sum())
        return float(np.mean(ls)), float(np.mean(shares))


def measure_tissue(density: float, loads=LOADS, *, tangential: bool = True, material: str = "shape_matching",
                   layers: int = 1, law: str = "patch", hourglass: float = 0.0, sim: SimConfig | None = None) -> dict:  # fmt: skip
    """Everything the rig measures at one density, with each group's energy ``material``
    (TissueConfig.group_energy), ``layers`` element layers through the thickness, the friction
    law ``law`` (TissueConfig.friction_law; only the tangential hold has friction), the
    continuum energy's ``hourglass`` control (TissueConfig.hourglass_stiffness) and the solver's
    settings ``sim`` (None: SimConfig's defaults; PadRig)."""
    tic = time.perf_counter()
    tissue = TissueConfig(group_energy=material, layers=layers, friction_law=law, hourglass_stiffness=hourglass)
    rig = PadRig(density, friction=0.0, tissue=tissue, sim=sim)
    radius, share = rig.group_radius()
    out = {"density": density, "layers": layers, "particles": rig.particle_count, "substeps": rig.substeps,
           "l": radius, "normal_share": share, "core_stiffness": float(core_stiffness(rig.model)[0])}  # fmt: skip
    guess = 2e-3
    for load in loads:
        c, f = rig.press_to(load, guess=guess)
        out[f"compression_{load:g}N"] = c
        out[f"held_{load:g}N"] = f
        out[f"width_{load:g}N"] = rig.contact_width()
        guess = c * (1.6 if load < 3 else 1.4)
    out["inner_clearance"] = rig.inner_clearance
    if tangential:
        rig = PadRig(density, tissue=tissue, sim=sim)  # default friction: the contact sticks
        c, f = rig.press_to(3.0, guess=out.get("compression_3N", 2e-3))
        # incremental: from SHEAR / 2 to 3 SHEAR / 2 down the axis (the first tenths of a mm carry an
        # offset of a few hundredths of a N while the contact's anchors take hold)
        rig.move_to(c, axial=-0.5 * SHEAR, speed=RAMP_SPEED / 2)
        first = rig.hold()
        rig.move_to(c, axial=-1.5 * SHEAR, speed=RAMP_SPEED / 2)
        load = rig.hold()
        out["shear_normal"] = float(load[0])
        out["shear_load"] = float(load[2])  # the pad pulls the cylinder back up
        out["compliance"] = SHEAR / float(load[2] - first[2])
        out["compression_3N_friction"] = c
    out["seconds"] = time.perf_counter() - tic
    return out


def tangential_at(density: float, load: float, *, material: str = "shape_matching", layers: int = 1,
                  law: str = "patch", hourglass: float = 0.0, sim: SimConfig | None = None) -> float:  # fmt: skip
    """One pad's tangential compliance [m/N] pressed to ``load`` [N], as measure_tissue's at 3 N,
    the axial moves scaled with the load (SHEAR load / 3 N) so that the contact sticks; ``sim``
    the solver's settings (PadRig)."""
    tissue = TissueConfig(group_energy=material, layers=layers, friction_law=law, hourglass_stiffness=hourglass)
    rig = PadRig(density, tissue=tissue, sim=sim)
    c, _ = rig.press_to(load, guess=2.7e-3 * (load / 3.0) ** 0.7)
    shear = SHEAR * load / 3.0
    rig.move_to(c, axial=-0.5 * shear, speed=RAMP_SPEED / 2)
    first = rig.hold()
    rig.move_to(c, axial=-1.5 * shear, speed=RAMP_SPEED / 2)
    return shear / float(rig.hold()[2] - first[2])


def measure_env(density: float) -> float:
    """The pad's compression at the end of the env's scripted grasp (3 N per finger) [m]."""
    from benchmarks.grasp_checks import scripted_episode

    return scripted_episode({"fingers": "tissue"}, "v3", particle_density=density)["compression"]


def orders(values: list[float], ref: float) -> list[float]:
    """Observed order between successive densities (spacing halves): log2 of the error's ratio."""
    e = [abs(v - ref) for v in values]
    return [math.log2(a / b) if a > 0 and b > 0 else math.nan for a, b in zip(e, e[1:], strict=False)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="4,000 and 16,000 per m^2, 3 N only")
    parser.add_argument("--densities", default=None, help="comma-separated particles per m^2")
    parser.add_argument("--env", action="store_true", help="also the env's scripted grasp per density")
    parser.add_argument("--material", choices=GROUP_ENERGIES, default="shape_matching",
                        help="each group's energy (TissueConfig.group_energy); the CSV and figure get a suffix for "
                             "any but the default")  # fmt: skip
    parser.add_argument("--layers", default="1",
                        help="comma-separated TissueConfig.layers (element layers through the thickness), e.g. 1,2,4")  # fmt: skip
    parser.add_argument("--out", type=Path, default=OUT)
    ns = parser.parse_args(argv)
    try:
        layer_counts = [int(v) for v in ns.layers.split(",")]
    except ValueError:
        parser.error(f"--layers must be comma-separated integers, got {ns.layers!r}")
    if ns.env and ns.material != "shape_matching":
        parser.error("--env runs the env's own material only (gym.make has no group_energy keyword yet)")
    from benchmarks.pad_reference import NUS, default_pad, reference

    densities = [float(d) for d in ns.densities.split(",")] if ns.densities else (
        list(DENSITIES[:2]) if ns.quick else list(DENSITIES))  # fmt: skip
    loads = (3.0,) if ns.quick else LOADS
    tic = time.perf_counter()
    pad = default_pad()
    ref = reference(pad, loads=loads, **({"tangential_element": 4e-3} if ns.quick else {}))
    ref_secs = time.perf_counter() - tic
    refs = {(r["nu"], r["load"]): r for r in ref}
    print(f"reference (plane-strain P2; tangential: 3-D, the face's free ends, {ref_secs:.1f} s): h {pad.thickness * 1e3:g} mm, face "
          f"{pad.width * 1e3:g} x {pad.height * 1e3:g} mm, R {pad.radius * 1e3:g} mm, G {pad.shear_modulus:g} Pa")  # fmt: skip
    for nu in NUS:
        print(f"  nu {nu:<4}: " + ", ".join(f"{load:g} N -> {refs[(nu, load)]['delta'] * 1e3:.3f} mm "
                                          f"(a {refs[(nu, load)]['a'] * 1e3:.2f} mm)" for load in loads)
              + f"; tangential {refs[(nu, 3.0)]['compliance'] * 1e3:.3f} mm/N at 3 N")  # fmt: skip
    if ns.env and layer_counts != [1]:
        parser.error("--env runs the env's own pads only (one layer)")
    rows = []
    for layers in layer_counts:
        for d in densities:
            r = measure_tissue(d, loads, material=ns.material, layers=layers)
            if ns.env:
                t = time.perf_counter()
                r["env_compression_3N"] = measure_env(d)
                r["env_seconds"] = time.perf_counter() - t
            rows.append(r)
            gap = r["inner_clearance"]
            print(f"{d:>9,.0f}/m^2, {layers} layer{'s' if layers > 1 else ''}: {r['particles']} particles, "
                  f"{r['substeps']} world steps/step, l {r['l'] * 1e3:.2f} mm, K {r['core_stiffness']:.0f} N/m; "
                  + ", ".join(f"{load:g} N {r[f'compression_{load:g}N'] * 1e3:.3f} mm" for load in loads)
                  + f"; tangential {r['compliance'] * 1e3:.3f} mm/N ({r['seconds']:.1f} s)"
                  + (f"; inner layers' clearance {gap * 1e3:.2f} mm" if math.isfinite(gap) else "")
                  + (f"; env {r['env_compression_3N'] * 1e3:.3f} mm ({r['env_seconds']:.1f} s)" if ns.env else ""),
                  flush=True)  # fmt: skip
    suffix = ("" if ns.material == "shape_matching" else f"_{ns.material}") + ("" if layer_counts == [1] else "_layers")
    report(rows, refs, loads, ns.out, ns.env, suffix)
    print(f"\ntotal {time.perf_counter() - tic:.1f} s")
    return 0


def report(rows: list[dict], refs: dict, loads, out: Path, env: bool, suffix: str = "") -> None:
    from benchmarks.pad_reference import NUS

    out.mkdir(parents=True, exist_ok=True)
    table = []
    counts = sorted({r.get("layers", 1) for r in rows})
    by_layers = {n: [r for r in rows if r.get("layers", 1) == n] for n in counts}
    def block(quantity: str, key: str, ref_key: str, load: float, title: str, note=None) -> None:
        """One quantity's table: per row the tissue's value, its error against each nu's reference
        and (``note``) a remark; then the observed orders along the densities of each layer count."""
        print(f"\n{title} (reference nu 0 / 0.3 / 0.45: "
              + " / ".join(f"{refs[(nu, load)][ref_key] * 1e3:.3f}" for nu in NUS) + ")")  # fmt: skip
        print(f"{'density':>9}{'layers':>7}{'particles':>10}{'l mm':>7}{'tissue':>8}"
              + "".join(f"{'err nu ' + str(nu):>13}" for nu in NUS))  # fmt: skip
        for n, group in by_layers.items():
            vals = [r[key] for r in group]
            for r, v in zip(group, vals, strict=True):
                errs = [v / refs[(nu, load)][ref_key] - 1 for nu in NUS]
                print(f"{r['density']:>9.0f}{n:>7}{r['particles']:>10}{r['l'] * 1e3:>7.2f}{v * 1e3:>8.3f}"
                      + "".join(f"{e:>+13.1%}" for e in errs) + (note(r) if note else ""))  # fmt: skip
                for nu, e in zip(NUS, errs, strict=True):
                    table.append((quantity, load, r["density"], n, r["particles"], r["l"], v, nu,
                                  refs[(nu, load)][ref_key], e))  # fmt: skip
            for nu in NUS:
                print(f"  {n} layer(s), observed order against nu {nu}: "
                      + ", ".join(f"{o:+.2f}" for o in orders(vals, refs[(nu, load)][ref_key])))  # fmt: skip

    for load in loads:
        block("compression", f"compression_{load:g}N", "delta", load, f"compression under {load:g} N [mm]")
    for load in loads:
        block("contact_width", f"width_{load:g}N", "width", load,
              f"contact strip's pressure-weighted RMS half-width under {load:g} N [mm]")  # fmt: skip
    block("tangential_compliance", "compliance", "compliance", 3.0, "tangential compliance at 3 N, one pad [mm/N]",
          note=lambda r: f"   (held at {r['shear_normal']:.2f} N, axial {r['shear_load']:.3f} N)")  # fmt: skip
    print("\nper (density, layers): world steps per step, rig seconds, stiffness against the core "
          "(compliant.core_stiffness) [N/m], share of the groups' second moment along the face normal, "
          "inner layers' least clearance from the cylinder [mm]")  # fmt: skip
    for r in rows:
        gap = r.get("inner_clearance", math.inf)
        print(f"{r['density']:>9.0f}{r.get('layers', 1):>7}{r['substeps']:>5}{r['seconds']:>8.1f} s"
              f"{r['core_stiffness']:>8.0f}{r['normal_share']:>7.3f}"
              + (f"{gap * 1e3:>8.2f}" if math.isfinite(gap) else f"{'-':>8}"))  # fmt: skip
    if env:
        print("env scripted grasp, compression at 3 N [mm]: "
              + ", ".join(f"{r['density']:.0f}: {r['env_compression_3N'] * 1e3:.3f}" for r in rows))  # fmt: skip
        for r in rows:
            for nu in NUS:
                table.append(("env_compression", 3.0, r["density"], r.get("layers", 1), r["particles"], r["l"],
                              r["env_compression_3N"], nu, refs[(nu, 3.0)]["delta"],
                              r["env_compression_3N"] / refs[(nu, 3.0)]["delta"] - 1))  # fmt: skip
    with open(out / f"spatial_convergence{suffix}.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["quantity", "load_N", "density_per_m2", "layers", "particles", "group_radius_m", "tissue", "nu",
                    "reference", "relative_error"])  # fmt: skip
        w.writerows([(q, f"{ld:g}", f"{d:.0f}", n, npart, f"{gl:.6g}", f"{v:.6g}", f"{nu:g}", f"{rf:.6g}", f"{e:.6g}")
                     for q, ld, d, n, npart, gl, v, nu, rf, e in table])  # fmt: skip
    print(f"\nwrote {out / f'spatial_convergence{suffix}.csv'}")
    plot(rows, refs, loads, out, env, suffix)


def plot(rows: list[dict], refs: dict, loads, out: Path, env: bool, suffix: str = "") -> None:
    try:
        import matplotlib
    except ImportError:
        print("matplotlib is not installed: no figure")
        return
    from benchmarks.pad_reference import NUS

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    counts = sorted({r.get("layers", 1) for r in rows})
    by_layers = {n: [r for r in rows if r.get("layers", 1) == n] for n in counts}

    def label(n: int) -> str:
        return "tissue (rig)" if counts == [1] else f"tissue, {n} layer{'s' if n > 1 else ''}"

    fig, axes = plt.subplots(1, len(loads) + 1, figsize=(3.2 * (len(loads) + 1), 3.2), squeeze=False)
    styles = {0.0: ":", 0.3: "--", 0.45: "-."}
    for ax, load in zip(axes[0], loads, strict=False):
        for n, group in by_layers.items():
            ax.plot([r["density"] for r in group], [r[f"compression_{load:g}N"] * 1e3 for r in group], "o-",
                    label=label(n))  # fmt: skip
        if env and load == 3.0:
            ax.plot([r["density"] for r in rows], [r["env_compression_3N"] * 1e3 for r in rows], "s-", ms=4,
                    label="tissue (env grasp)")  # fmt: skip
        for nu in NUS:
            ax.axhline(refs[(nu, load)]["delta"] * 1e3, color="k", ls=styles[nu], lw=1, label=f"FE, nu {nu:g}")
        ax.set_title(f"compression under {load:g} N [mm]", fontsize=9)
    ax = axes[0, -1]
    for n, group in by_layers.items():
        ax.plot([r["density"] for r in group], [r["compliance"] * 1e3 for r in group], "o-", label=label(n))
    for nu in NUS:
        ax.axhline(refs[(nu, 3.0)]["compliance"] * 1e3, color="k", ls=styles[nu], lw=1, label=f"FE, nu {nu:g}")
    ax.set_title("tangential compliance at 3 N [mm/N]", fontsize=9)
    for ax in axes[0]:
        ax.set_xscale("log")
        ax.set_xlabel("particles per m^2 of face", fontsize=8)
        ax.set_ylim(bottom=0)
        ax.tick_params(labelsize=7)
    axes[0, 0].legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(out / f"spatial_convergence{suffix}.png", dpi=90)
    plt.close(fig)
    print(f"wrote {out / f'spatial_convergence{suffix}.png'}")


if __name__ == "__main__":
    raise SystemExit(main())
