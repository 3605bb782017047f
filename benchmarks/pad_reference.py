"""An independent reference for the tissue pad: a plane-strain finite-element model of the same pad,
pressed by the same rigid cylinder, that shares no code with the oriented-particle solver.

    PYTHONPATH=. python benchmarks/pad_reference.py [--quick] [--plot docs/results/pad_reference.png]

Needs scikit-fem (``pip install softgrasp-env[reference]`` or ``pip install scikit-fem``).

The model
---------
A finger's inner face is a box face 40 mm wide (y) and 60 mm high (z) (SceneConfig.finger_half_extents
(0.008, 0.02, 0.03)); the tissue on it is a layer whose attached particles sit on the core's face
and whose outer partners sit ``TissueConfig.extrude`` = 8 mm further out along the face normal
(tissue/builder.py, build_combined_body: each attached/outer pair "stands for a prism of tissue
(area x extrude)", its mass rho * area * extrude). The elastic layer is therefore 8 mm thick. The
outer particles' ellipsoids reach ``normal_radius`` = 3 mm beyond it (the pad's 11 mm,
TissueFingers.pad_thickness), but an ellipsoid is rigid: it moves the contact surface out without
adding compliance, so indentation measured from first touch is the layer's. The cylinder (radius
30 mm, SceneConfig.cylinder_radius) stands upright and touches the face along its whole height, so
the cross-section at any height is the same: plane strain in the horizontal (x, y) plane, x across
the layer (x = 0 bonded to the rigid core, x = h the free surface), y across the face (free edges
at y = +-20 mm). A load F on the pad is F / H per unit length, H = 60 mm the face's height.

- Material: linear elastic, isotropic, shear modulus G (TissueConfig's default 4,000 Pa) and a
  Poisson ratio nu. Which nu the oriented-particle tissue behaves like is part of the question, so
  every result is given for several (0.0, 0.3, 0.45).
- Elements: 6-node quadratic triangles (P2) on a tensor mesh of the layer, finest at the contact
  surface: element size e = h / n there, growing linearly to 2 e at the core (n the resolution
  level below), e across the face's width.
- Contact: a rigid frictionless cylinder of radius R, its axis at x = h + R - delta (delta the
  indentation from first touch). Each surface node i (vertex and edge-midpoint, at y_i) must stay
  outside it, u_x,i <= R - delta - sqrt(R^2 - y_i^2) (small-strain, node-to-surface, the exact
  circle). With the layer condensed onto the surface nodes' normal displacements (compliance
  matrix C = S K^-1 S^T, one factorisation), the contact is the linear complementarity problem
  f >= 0, C f - d >= 0, f . (C f - d) = 0 (f the nodal contact forces, d the interference), solved
  exactly as the equivalent non-negative least-squares problem (Lawson-Hanson active set,
  scipy.optimize.nnls): at the solution no node penetrates by more than 1e-9 of the indentation
  and no node pulls (checked, ``contact``). The load for a given force is found by Brent's method
  on delta to 1e-10 relative.
- Pressure profile: nodal forces over each node's share of the surface (the integral of its shape
  function: exact for uniform pressure). Contact half-width: where the gap outside the contact,
  which opens as (|y| - a)^1.5, extrapolates to zero from the first two free nodes.
- Tangential compliance: the cylinder pulled along its own axis (z) with the contact stuck is
  anti-plane shear of the layer: G Laplace(w) = 0, w = 0 on the core, w = U on the contact strip
  (the frictionless contact's strip at that load), free elsewhere; compliance U / (H q), q the
  strip's force per unit length (one pad; a grasp's two pads carrying the load together give half).
  Anti-plane shear does not depend on nu except through the strip's width. That is the pad of
  infinite length; the finger's face is H = 60 mm long with free ends, where the shear traction
  must fall to zero, and the ends make it more compliant. ``tangential_compliance_3d`` solves the
  3-D pad (h x W x H, bonded to the core, the strip |y| <= a moved along z with the contact stuck:
  u = (0, 0, U) there, every other face free; a quarter by its two symmetry planes; 27-node
  hexahedra, linear elasticity at the row's nu): 1.194 mm/N at nu 0 and 3 N against the anti-plane
  1.128 (+5.9 %; +4.3 % at nu 0.3, +3.3 % at 0.45). That is the reference the tissue's tangential
  compliance is measured against (``reference``'s "compliance"; the anti-plane value is kept as
  "compliance_2d"). Checked: a pad 8 H long gives, per H, 1.1267 mm/N with the end effect
  shrinking as 1 / length toward the anti-plane value (``verify``); element size 4 / 2 / 1.33 mm
  gives 1.1842 / 1.1939 / 1.1976 mm/N (2 mm, the default, within 0.5 % of the finest).

Verification (``verify``): the laterally confined layer under uniform pressure against
u = p h (1 - 2 nu) / (2 G (1 - nu)); a thin layer under a cylinder against its thin-layer limit, in
which every point compresses as the confined layer does (the layer as an elastic foundation of
modulus M / h, M = 2 G (1 - nu) / (1 - 2 nu); Johnson, Contact Mechanics, 1985, sec. 5.9): a
line load P = (4 / 3) (M / h) sqrt(2 R) delta^(3/2) on a half-width a = sqrt(2 R delta); and the
model's own mesh convergence (observed order from three successive levels).
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import dataclass
from functools import cached_property

import numpy as np

NUS = (0.0, 0.3, 0.45)
"""Poisson ratios the reference is computed for."""
LOADS = (1.0, 3.0, 6.0)
"""Total normal loads on one pad [N]."""
LEVEL = 16
"""Default resolution: elements across the layer's thickness at the contact surface (e = h / 16 =
0.5 mm; benchmarks/spatial_convergence.py). Measured against level 32 (``verify``): the indentation
under 3 N within 0.03 %, the contact half-width within 0.4 %, the tangential compliance within 0.2 %."""


@dataclass(frozen=True)
class Pad:
    """The pad's geometry and material [SI]."""

    thickness: float
    """h, the elastic layer: TissueConfig.extrude [m]."""
    width: float
    """W, the finger face across (y) [m]."""
    height: float
    """H, the finger face along the cylinder's axis (z) [m]."""
    radius: float
    """R, the cylinder's radius [m]."""
    shear_modulus: float
    """G [Pa]."""


def default_pad() -> Pad:
    """The pad of the default scene: TissueConfig's extrude and shear modulus, the finger's inner
    face, the cylinder's radius."""
    from softgrasp_env.config import TissueConfig
    from softgrasp_env.scene import SceneConfig

    scene, tissue = SceneConfig(), TissueConfig()
    _, hy, hz = scene.finger_half_extents
    return Pad(tissue.extrude, 2.0 * hy, 2.0 * hz, scene.cylinder_radius, tissue.shear_modulus)


def confined_compression(p: float, h: float, shear_modulus: float, nu: float) -> float:
    """Compression of a laterally confined layer under uniform pressure p: p h (1 - 2 nu) / (2 G (1 - nu)) [m]."""
    return p * h * (1.0 - 2.0 * nu) / (2.0 * shear_modulus * (1.0 - nu))


def foundation_modulus(shear_modulus: float, nu: float) -> float:
    """M = 2 G (1 - nu) / (1 - 2 nu), the confined (oedometric) modulus [Pa]."""
    return 2.0 * shear_modulus * (1.0 - nu) / (1.0 - 2.0 * nu)


def thin_layer_load(delta: float, pad: Pad, nu: float, *, parabolic: bool = False) -> float:
    """The thin-layer limit's line load for indentation ``delta`` [N/m]: (M / h) times the integral
    of the interference delta - (R - sqrt(R^2 - y^2)) over the contact; with ``parabolic`` the
    cylinder's usual parabola, (4/3) (M / h) sqrt(2 R) delta^1.5 (0.25 % more at delta = 0.5 mm, R
    30 mm: the circle's y^4 / 8 R^3)."""
    m = foundation_modulus(pad.shear_modulus, nu)
    r = pad.radius
    if parabolic:
        return 4.0 / 3.0 * m / pad.thickness * math.sqrt(2.0 * r) * delta**1.5
    a = math.sqrt(r * r - (r - delta) ** 2)
    # integral of delta - r + sqrt(r^2 - y^2) over |y| <= a
    area = 2.0 * ((delta - r) * a + 0.5 * (a * math.sqrt(r * r - a * a) + r * r * math.asin(a / r)))
    return m / pad.thickness * area


class LayerModel:
    """The pad as a plane-strain P2 model at resolution ``level`` (elements across the thickness at
    the surface). ``sides``: 'free' (the finger's face edges) or 'roller' (u_y = 0 there: the
    laterally confined layer of the analytic check). ``across``: the element size across the width
    [m], if not e."""

    def __init__(self, pad: Pad, nu: float, level: int = LEVEL, *, sides: str = "free",
                 across: float | None = None) -> None:
        from skfem import Basis, BilinearForm, ElementTriP2, ElementVector, FacetBasis, LinearForm, MeshTri, asm
        from skfem.models.elasticity import linear_elasticity

        if not 0.0 <= nu < 0.5:
            raise ValueError(f"nu must be in [0, 0.5), got {nu!r}")
        self.pad, self.nu, self.level = pad, nu, level
        h, half = pad.thickness, 0.5 * pad.width
        e = h / level
        # x: finest (e) at the surface x = h, growing linearly to 2e at the core
        n_x = max(1, round(h / (1.5 * e)))
        s = np.linspace(0.0, 1.0, n_x + 1)
        xs = h * (2.0 * s - 0.5 * s * s) / 1.5  # spacing ~ (2 - s): 2e at the core (s = 0), e at the surface
        ys = np.linspace(-half, half, max(2, round(pad.width / (across or e))) + 1)
        self.mesh = MeshTri.init_tensor(xs, ys)
        self.basis = Basis(self.mesh, ElementVector(ElementTriP2()))
        g = pad.shear_modulus
        lam = 2.0 * g * nu / (1.0 - 2.0 * nu)
        self.K = asm(linear_elasticity(lam, g), self.basis).tocsc()
        m = self.mesh
        base = self.basis.get_dofs(m.facets_satisfying(lambda x: np.isclose(x[0], 0.0))).all()
        fixed = [base]
        if sides == "roller":
            for y0 in (-half, half):
                fixed.append(self.basis.get_dofs(m.facets_satisfying(lambda x, y0=y0: np.isclose(x[1], y0))).all("u^2"))
        elif sides != "free":
            raise ValueError(f"sides must be 'free' or 'roller', got {sides!r}")
        self.fixed = np.unique(np.concatenate(fixed))
        self.free = np.setdiff1d(np.arange(self.basis.N), self.fixed)
        top = m.facets_satisfying(lambda x: np.isclose(x[0], h))
        dofs = self.basis.get_dofs(top).all("u^1")
        y = self.basis.doflocs[1, dofs]
        order = np.argsort(y)
        self.surface = dofs[order]
        """x-displacement DOFs of the surface nodes, by y."""
        self.y = y[order]
        """Their y [m]."""
        fb = FacetBasis(self.mesh, self.basis.elem, facets=top)
        share = asm(LinearForm(lambda v, w: v[0]), fb)
        self.share = share[self.surface]
        """Each surface node's share of the surface, the integral of its shape function [m]."""
        self._facet_basis, self._bilinear, self._asm = fb, BilinearForm, asm
        from scipy.sparse.linalg import splu

        self._lu = splu(self.K[self.free][:, self.free].tocsc())
        self.element_size = e
        self.dof_count = self.basis.N

    def solve(self, load: np.ndarray) -> np.ndarray:
        """Displacements under nodal ``load`` (fixed DOFs held at 0)."""
        u = np.zeros(self.basis.N)
        u[self.free] = self._lu.solve(load[self.free])
        return u

    def uniform_pressure(self, p: float) -> np.ndarray:
        """The surface nodes' x displacement under uniform pressure p [Pa] on the whole surface [m]."""
        load = np.zeros(self.basis.N)
        load[self.surface] = -p * self.share
        return self.solve(load)[self.surface]

    @cached_property
    def compliance(self) -> np.ndarray:
        """C[i, j]: surface node i's inward (-x) displacement per unit inward force at node j [m/(N/m)]."""
        rhs = np.zeros((self.basis.N, self.surface.size))
        rhs[self.surface, np.arange(self.surface.size)] = 1.0
        sol = self._lu.solve(rhs[self.free])
        u = np.zeros_like(rhs)
        u[self.free] = sol
        return u[self.surface]

    @cached_property
    def _chol(self) -> np.ndarray:
        c = 0.5 * (self.compliance + self.compliance.T)
        return np.linalg.cholesky(c)  # lower L, C = L L^T

    def contact(self, delta: float) -> dict:
        """The frictionless cylinder pressed ``delta`` [m] into the surface: line load P [N/m], nodal
        forces f [N/m], pressure p [Pa] per surface node, the contact mask, half-width a [m] (the
        face's half-width if the whole surface touches), and the solution's residuals (largest
        penetration, largest pull) [m, N/m]."""
        from scipy.linalg import solve_triangular
        from scipy.optimize import nnls

        r = self.pad.radius
        d = delta - (r - np.sqrt(np.maximum(r * r - self.y**2, 0.0)))
        d[np.abs(self.y) >= r] = -np.inf
        live = d > -10.0 * abs(delta) - 1e-9  # nodes far outside cannot touch
        d = np.where(np.isfinite(d), d, -1.0)
        # min 1/2 f C f - d f, f >= 0  <=>  min |L^T f - L^-1 d|^2, f >= 0 (C = L L^T)
        lo = self._chol
        b = solve_triangular(lo, d, lower=True)
        f = np.zeros_like(d)
        sol, _ = nnls(lo.T[:, live], b, maxiter=50 * int(live.sum()) + 100)
        f[live] = sol
        gap = self.compliance @ f - d  # inward displacement - interference: >= 0
        touch = f > 0.0
        a = self._half_width(touch, gap)
        return {"P": float(f.sum()), "f": f, "pressure": f / self.share, "touch": touch, "a": float(a),
                "penetration": float(max(0.0, -gap.min())), "pull": float(max(0.0, -f.min()))}  # fmt: skip

    def _half_width(self, touch: np.ndarray, gap: np.ndarray) -> float:
        """The contact's half-width [m]: near a frictionless contact's edge the gap opens as
        (|y| - a)^1.5, so gap^(2/3) of the first two free nodes outside the contact, extrapolated
        linearly to zero, within the interval between the last node in contact and the first
        free one (the mean of the two sides)."""
        if touch.all():
            return 0.5 * self.pad.width
        if not touch.any():
            return 0.0
        k = np.flatnonzero(touch)
        ends = []
        for i, step in ((k.max(), 1), (k.min(), -1)):
            o1, o2 = i + step, i + 2 * step
            yi, y1 = abs(self.y[i]), abs(self.y[o1])
            if 0 <= o2 < self.y.size:
                g1, g2 = max(gap[o1], 0.0) ** (2 / 3), max(gap[o2], 0.0) ** (2 / 3)
                y2 = abs(self.y[o2])
                edge = y1 - g1 * (y2 - y1) / (g2 - g1) if g2 > g1 else 0.5 * (yi + y1)
                ends.append(min(max(edge, yi), y1))
            else:
                ends.append(0.5 * (yi + y1))
        return float(np.mean(ends))

    def indentation(self, force: float, *, rtol: float = 1e-10) -> tuple[float, dict]:
        """(delta, contact) for a total load ``force`` [N] on the pad (force / height per unit length)."""
        from scipy.optimize import brentq

        target = force / self.pad.height
        hi = 1e-4
        while self.contact(hi)["P"] < target:
            hi *= 2.0
            if hi > self.pad.thickness:
                raise ValueError(f"{force} N presses the cylinder deeper than the layer")
        delta = brentq(lambda x: self.contact(x)["P"] - target, 0.0 if hi <= 1e-4 else hi / 2, hi, rtol=rtol, xtol=1e-15)
        return delta, self.contact(delta)

    def tangential_compliance(self, a: float) -> float:
        """One pad's compliance along the cylinder's axis with the strip |y| <= a stuck to it [m/N]:
        anti-plane shear, G Laplace(w) = 0. The strip is held at the surface nodes; between two
        nodes the compliance is interpolated linearly in a (so that it moves smoothly with the load
        and the mesh instead of jumping from node to node)."""
        y = np.sort(np.abs(self.y))
        inside = y[y <= a + 1e-15]
        lo = inside.max() if inside.size else y.min()
        outside = y[y > a + 1e-15]
        if not outside.size:
            return self._strip_compliance(np.abs(self.y) <= lo + 1e-12)
        hi = outside.min()
        c_lo = self._strip_compliance(np.abs(self.y) <= lo + 1e-12)
        c_hi = self._strip_compliance(np.abs(self.y) <= hi + 1e-12)
        t = (a - lo) / (hi - lo)
        return float((1.0 - t) * c_lo + t * c_hi)

    @cached_property
    def _anti(self) -> tuple:
        """The anti-plane system: (scalar P2 basis, G times its Laplacian, the core's DOFs, the
        surface's DOFs by y)."""
        from skfem import Basis, ElementTriP2
        from skfem.models.poisson import laplace

        sb = Basis(self.mesh, ElementTriP2())
        k = self._asm(laplace, sb).tocsc() * self.pad.shear_modulus
        base = sb.get_dofs(self.mesh.facets_satisfying(lambda x: np.isclose(x[0], 0.0))).all()
        top = sb.get_dofs(self.mesh.facets_satisfying(lambda x: np.isclose(x[0], self.pad.thickness))).all()
        return sb, k, base, top[np.argsort(sb.doflocs[1, top])]

    def _strip_compliance(self, touch: np.ndarray) -> float:
        """One pad's tangential compliance with the surface nodes ``touch`` held [m/N]."""
        sb, k, base, top = self._anti
        if touch.shape != top.shape:
            raise ValueError("touch must be a mask over the surface nodes")
        held = top[touch]
        fixed = np.union1d(base, held)
        free = np.setdiff1d(np.arange(sb.N), fixed)
        w = np.zeros(sb.N)
        w[held] = 1.0
        from scipy.sparse.linalg import spsolve

        w[free] = spsolve(k[free][:, free].tocsc(), -(k[free][:, held] @ w[held]))
        q = float((k @ w)[held].sum())  # force per unit length holding the strip at U = 1 m
        return 1.0 / (q * self.pad.height)

    def partial_slip(self, normal: np.ndarray, mu: float, *, steps: int = 400) -> dict:
        """Partial slip of the strip under a growing axial load: anti-plane shear (G Laplace(w) = 0, w = 0
        on the core) with Coulomb's law at every surface node, the cylinder moved by U along its axis.

        ``normal``: the nodal normal forces [N/m] per surface node (``contact(delta)["f"]``); in linear
        elasticity the anti-plane problem does not disturb the in-plane one, so this pressure holds
        through the whole ramp. A node with normal force f_n sticks (w = U) while its axial force r
        stays within mu f_n, else slides with r = mu f_n and w <= U (it lags the cylinder). For each U
        on a grid up to gross slip the stick set is found by an active-set iteration from the last
        U's (it shrinks monotonically toward the strip's centre, as in Cattaneo-Mindlin), which is
        exact for the discrete problem: every stuck node within its cone, every sliding node behind
        the cylinder (to 1e-12 relative); the ramp's last U, u_gross, is gross slip. Returns arrays over the ramp: "ratio" Q / mu P, "share" the
        sticking nodes' share of the normal load, "c_over_a" the |y| within which the nodes carry
        that share (read off their cumulative load, the tissue's measure: partial_slip.ramp) over the
        contact's outermost loaded |y|, "c_geom" the outermost sticking node's |y| over the same,
        "U" [m] and "Q" [N/m]; and "gross" the U at which every node slides."""
        from scipy.sparse.linalg import splu

        sb, k, base, top = self._anti
        if normal.shape != self.y.shape:
            raise ValueError(f"normal must give one force per surface node ({self.y.size}), got shape {normal.shape}")
        if not mu > 0.0:
            raise ValueError(f"mu must be positive, got {mu!r}")
        touch = normal > 0.0
        if not touch.any():
            raise ValueError("no surface node carries a normal force")
        limit = mu * normal  # each node's cone [N/m]
        big_p = float(normal.sum())
        ya = np.abs(self.y)
        a = float(ya[touch].max())
        k = k.tocsr()

        def solve(stick: np.ndarray, u: float) -> tuple[np.ndarray, np.ndarray]:
            held = top[stick]
            fixed = np.union1d(base, held)
            free = np.setdiff1d(np.arange(sb.N), fixed)
            w = np.zeros(sb.N)
            w[held] = u
            rhs = -(k[free][:, fixed] @ w[fixed])
            slide = top[touch & ~stick]
            load = np.zeros(sb.N)
            load[slide] = limit[touch & ~stick]
            rhs += load[free]
            w[free] = splu(k[free][:, free].tocsc()).solve(rhs)
            r = k @ w - load  # the cylinder's force on each held node
            return w[top], r[top]

        # the largest U first: with every node at its cone the strip lags by w_gross; beyond it all slide
        w_all, _ = solve(np.zeros(self.y.size, bool), 0.0)
        u_gross = float(w_all[touch].max())
        stick = touch.copy()
        rows = []
        for u in np.linspace(u_gross / steps, u_gross, steps)[:-1]:
            for _ in range(4 * self.y.size):
                w, r = solve(stick, u)
                settled, stick = _coulomb_update(stick, touch, r, limit, w, u)
                if settled:
                    break
            else:
                raise RuntimeError("the active set did not settle")
            q = float(r[stick].sum() + limit[touch & ~stick].sum())
            share = float(normal[stick].sum() / big_p)
            order = np.argsort(ya[touch])
            cum = np.concatenate(([0.0], np.cumsum(normal[touch][order]) / big_p))
            c_load = float(np.interp(share, cum, np.concatenate(([0.0], ya[touch][order])))) / a
            c_geom = float(ya[stick].max()) / a if stick.any() else 0.0
            rows.append((q / (mu * big_p), share, c_load, c_geom, u, q))
            if not stick.any():
                break
        else:  # at u_gross every node at its cone is the solution (the last to stick is exactly there)
            rows.append((1.0, 0.0, 0.0, 0.0, u_gross, mu * big_p))
        arr = np.array(rows)
        return {"ratio": arr[:, 0], "share": arr[:, 1], "c_over_a": arr[:, 2], "c_geom": arr[:, 3], "U": arr[:, 4],
                "Q": arr[:, 5], "gross": u_gross, "a": a}  # fmt: skip


def _coulomb_update(stick: np.ndarray, touch: np.ndarray, force: np.ndarray, limit: np.ndarray, lag: np.ndarray,
                    travel: float) -> tuple[bool, np.ndarray]:  # fmt: skip
    """One active-set update of Coulomb's law at each node of a strip pulled by ``travel``: a stuck
    node whose force exceeds its cone ``limit`` slides; a sliding node whose displacement ``lag``
    got ahead of the cylinder sticks. Returns (settled, the new stick set)."""
    over = stick & (force > limit * (1.0 + 1e-12))
    ahead = touch & ~stick & (lag > travel * (1.0 + 1e-12))
    if not over.any() and not ahead.any():
        return True, stick
    return False, (stick & ~over) | ahead


def pressure_width(y: np.ndarray, pressure: np.ndarray) -> float:
    """The pressure-weighted RMS half-width of a contact strip, sqrt(int p y^2 dy / int p dy) [m]
    (trapezoid rule over the surface nodes): a / 2 for a Hertzian (elliptic) profile of half-width
    a, a / sqrt 5 for a parabolic one. The tissue's contacts give the same moment of their normal
    loads (spatial_convergence.PadRig.contact_width)."""
    return float(math.sqrt(np.trapezoid(pressure * y * y, y) / np.trapezoid(pressure, y)))


TANGENTIAL_ELEMENT = 2e-3
"""Element size of the 3-D tangential model [m] (h / 4 with 27-node hexahedra: within 0.5 % of
1.33 mm, see the module docstring)."""
TANGENTIAL_LOADS = (3.0,)
"""The normal loads at which ``reference`` solves the 3-D tangential model (8 s each)."""


def _compressed_shear(pad: Pad, indentation: float, g: float, profile: str):
    """The bilinear form that turns linear elasticity's shear across the layer (modulus ``g``)
    into the continuum group energy's about the pad compressed by the cylinder to ``indentation``
    [m]: tangential_compliance_3d's ``indentation`` and ``profile``, whose docstring derives it."""
    from skfem import BilinearForm

    h, radius = pad.thickness, pad.radius
    if profile == "thin":

        @BilinearForm
        def softened(u, v, w):
            y = np.abs(w.x[1])
            d = np.maximum(0.0, indentation - (radius - np.sqrt(np.maximum(radius**2 - y**2, 0.0))))
            s = 1.0 - d / h
            # + (G_xz - G) gamma_xz(u) gamma_xz(v), gamma = 2 eps_xz: the shear modulus across the layer
            return (2.0 * s / (1.0 + s) - 1.0) * g * (u.grad[0, 2] + u.grad[2, 0]) * (v.grad[0, 2] + v.grad[2, 0])

    elif profile == "plane_strain":
        modulus = _shear_pair_modulus(pad, indentation)

        @BilinearForm
        def softened(u, v, w):
            m = modulus(w.x[0], np.abs(w.x[1]))  # (2, 2, ...): 2 G sum_i s_i / (1 + s_i) v_i v_i^T
            gu = (u.grad[0, 2] + u.grad[2, 0], u.grad[1, 2] + u.grad[2, 1])
            gv = (v.grad[0, 2] + v.grad[2, 0], v.grad[1, 2] + v.grad[2, 1])
            # + gamma(u)^T (G_eff - G I) gamma(v) / ... for the pair (gamma_xz, gamma_yz)
            return sum((m[i, j] - (g if i == j else 0.0)) * gu[i] * gv[j] for i in range(2) for j in range(2))

    else:
        raise ValueError(f"profile must be 'thin' or 'plane_strain', got {profile!r}")
    return softened


def tangential_compliance_3d(pad: Pad, a: float, nu: float, *, element: float = TANGENTIAL_ELEMENT,
                             length: float | None = None, quadratic: bool = True,
                             indentation: float | None = None, profile: str = "thin") -> float:  # fmt: skip
    """One pad's compliance along the cylinder's axis [m/N], the pad solved in 3-D with its finite
    length: the layer x in [0, h] bonded to the core at x = 0 (u = 0), the strip |y| <= a of its
    surface x = h moved by U along z with the contact stuck (u = (0, 0, U): the rigid cylinder
    moves along its axis only), every other face traction-free, the face's ends z = +-length / 2
    included. A quarter is solved: u_y = 0 on y = 0 (the load is even in y) and u_x = u_y = 0 on
    z = 0 (a translation along z is odd under z -> -z). Linear elasticity at ``nu`` (Lame's
    lambda, mu = G), a tensor grid of ``element`` with a node line at |y| = a, 27-node (or
    ``quadratic=False``: 8-node) hexahedra (scikit-fem). ``length`` (default the face's H) other
    than H gives the compliance per H of a longer pad: the verification of the anti-plane limit.

    ``indentation`` (nu 0 only): the shear about the pad as the cylinder has compressed it, for the
    continuum group energy E = G V ||F - R||^2 (tissue/compliant.py) at finite strain. A layer
    compressed to a stretch s across it (F = diag(s, 1, 1)) and sheared by g = dw/dx along the axis
    has ||F - R||^2 = (1 - s)^2 + g^2 s / (1 + s) (the polar rotation takes up part of the shear),
    so its shear modulus across the layer is G 2 s / (1 + s), 0.78 G at the strip's centre under
    3 N, while shear along the face keeps G. Here s(y) = 1 - d(y) / h through the thickness (a thin
    layer), d(y) the cylinder's interference indentation - (R - sqrt(R^2 - y^2)), and the xz shear
    modulus is G 2 s / (1 + s): linear elasticity linearised about the compressed pad. None: the
    undeformed pad (linear elasticity, small strain). ``profile`` "plane_strain" takes the
    in-plane deformation F2 = I + grad u from the plane-strain model pressed to ``indentation``
    instead (LayerModel, nu 0) at every point, its principal stretches s_i and directions v_i:
    the shear pair (dw/dx, dw/dy) then has the modulus 2 G sum_i s_i / (1 + s_i) v_i v_i^T (the
    same expansion in F2's principal frame)."""
    from scipy.sparse.linalg import spsolve
    from skfem import Basis, ElementHex1, ElementHex2, ElementVector, MeshHex, asm
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    def grid(span: float) -> np.ndarray:
        return np.linspace(0.0, span, max(1, math.ceil(span / element - 1e-9)) + 1)

    length = pad.height if length is None else length
    if not 0.0 < a < pad.width / 2:
        raise ValueError(f"the strip's half-width a must lie inside the face's half-width {pad.width / 2!r}, got {a!r}")
    h = pad.thickness
    mesh = MeshHex.init_tensor(grid(h), np.concatenate([grid(a), a + grid(pad.width / 2 - a)[1:]]), grid(length / 2))
    basis = Basis(mesh, ElementVector(ElementHex2() if quadratic else ElementHex1()), intorder=4 if quadratic else 2)
    lam, mu = lame_parameters(2.0 * pad.shear_modulus * (1.0 + nu), nu)
    k = asm(linear_elasticity(lam, mu), basis)
    if indentation is not None:
        if nu != 0.0:
            raise ValueError(f"the compressed pad's shear is that of the continuum group energy, nu 0; got nu {nu!r}")
        k = k + asm(_compressed_shear(pad, indentation, mu, profile), basis)
    k = k.tocsr()
    core = basis.get_dofs(lambda p: np.isclose(p[0], 0.0)).all()
    strip = basis.get_dofs(lambda p: np.isclose(p[0], h) & (p[1] <= a + 1e-12))
    mid_y = basis.get_dofs(lambda p: np.isclose(p[1], 0.0)).all("u^2")
    mid_z = basis.get_dofs(lambda p: np.isclose(p[2], 0.0))
    held = np.setdiff1d(strip.all("u^3"), core)
    fixed = np.unique(np.concatenate([core, strip.all("u^1"), strip.all("u^2"), mid_y, mid_z.all("u^1"),
                                      mid_z.all("u^2"), held]))  # fmt: skip
    u = np.zeros(k.shape[0])
    u[held] = 1.0
    free = np.setdiff1d(np.arange(k.shape[0]), fixed)
    u[free] = spsolve(k[free][:, free].tocsc(), -(k[free][:, fixed] @ u[fixed]))
    force = 4.0 * float((k @ u)[held].sum())  # the whole pad's axial force at U = 1 m
    return length / (pad.height * force)


def partial_slip_3d(pad: Pad, y_profile: np.ndarray, pressure: np.ndarray, mu: float, *, nu: float = 0.0,
                    element: float = TANGENTIAL_ELEMENT, across: float = 5e-4, steps: int = 120,
                    indentation: float | None = None, goodman: bool = True) -> dict:  # fmt: skip
    """Partial slip of the 3-D pad of finite length under a growing axial load, Coulomb's law at every
    node of the contact strip: the reference for the tissue rig, whose face has free ends.

    The pad is tangential_compliance_3d's (27-node hexahedra, ``element`` along x and z, ``across``
    across the strip, a node line at |y| = a). The contact's pressure before the pull is the
    plane-strain one, ``pressure`` [Pa] at ``y_profile`` [m] (LayerModel.contact), uniform along the
    face's height (exact in 3-D at nu 0: the plane-strain field leaves the free ends traction-free).
    Every strip node (|y| <= a, a the outermost |y| with pressure) is held in y (friction across the
    strip: a lateral slip is not modelled); along z it sticks (u_z = U, the cylinder's travel) while
    its axial force stays within mu times its normal force, else slides at that bound behind the
    cylinder (u_z <= U).

    ``goodman`` True: Goodman's approximation, the axial pull does not change the normal force, each
    node's is its share of the pressure (its consistent nodal load), and the strip nodes are held in
    x; then the problem is symmetric about the face's mid-height and the model is a quarter by two
    symmetry planes. False: the normal force is the solution's. A pad bonded to a core and pulled
    along its face at its outer surface carries the couple Q h (h its thickness) to the core; part
    of it is a couple of normal forces on the strip, which presses the strip's trailing end (the end
    the cylinder moves away from) harder and lifts the leading one (about 0.46 h Q of couple on the
    strip at nu 0). The model is then the half by the y symmetry plane, the strip's nodes held in x
    (by the rigid cylinder: u_x = 0 from the pressed state) only while they push on it, else free
    with no force (the contact opens), and Coulomb's bound moves with each node's normal force.
    Either way the strip's stiffness is condensed onto its nodes (one factorisation), and for each U
    on a grid to gross slip an active-set iteration from the last U's finds the stick (and contact)
    set, exact for the discrete problem. ``indentation`` [m] (nu 0 only): the shear across the layer
    is the continuum group energy's about the pad the cylinder compressed that far
    (tangential_compliance_3d's, the thin-layer profile); None: linear elasticity.

    Returns arrays over the ramp: "ratio" Q / mu P (P the present normal load when ``goodman`` is
    False: the cylinder holds its place across the pad, as in the tissue rig, and the pull changes
    P a little: +0.08 % by gross slip at 3 N and mu 0.9 on 4 mm elements), "share" the sticking
    nodes' share of the normal load (of the present normal forces when ``goodman`` is False, as the
    tissue rig reads them),
    "c_over_a" the tissue's measure of the stick zone (partial_slip.ramp: the |y| within which the
    nodes carry that share, off their cumulative load, over a), "c_over_a_mid" the same over the
    middle half of the face's height (|z| <= H / 4), "U" [m], "Q" [N] (the whole pad), "a" [m]; with
    ``goodman`` False also "trailing" the share over the trailing half of the face (z < 0; the
    cylinder moves to +z), "leading" over the other, and "open" the count of strip nodes whose
    contact has opened (of the half model)."""
    from scipy.sparse.linalg import splu
    from skfem import Basis, ElementHex2, ElementVector, FacetBasis, LinearForm, MeshHex, asm
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    if not mu > 0.0:
        raise ValueError(f"mu must be positive, got {mu!r}")
    touching = pressure > 0.0
    if not touching.any():
        raise ValueError("the pressure profile is zero everywhere")
    a = float(np.abs(y_profile[touching]).max())
    if not 0.0 < a < pad.width / 2:
        raise ValueError(f"the strip's half-width must lie inside the face's half-width {pad.width / 2!r}, got {a!r}")

    def grid(span: float, size: float) -> np.ndarray:
        return np.linspace(0.0, span, max(1, math.ceil(span / size - 1e-9)) + 1)

    h, half_h = pad.thickness, pad.height / 2
    ys = np.concatenate([grid(a, across), a + grid(pad.width / 2 - a, element)[1:]])
    zs = grid(half_h, element) if goodman else np.concatenate([-grid(half_h, element)[:0:-1], grid(half_h, element)])
    mesh = MeshHex.init_tensor(grid(h, element), ys, zs)
    basis = Basis(mesh, ElementVector(ElementHex2()), intorder=4)
    lam, g = lame_parameters(2.0 * pad.shear_modulus * (1.0 + nu), nu)
    k = asm(linear_elasticity(lam, g), basis)
    if indentation is not None:
        if nu != 0.0:
            raise ValueError(f"the compressed pad's shear is that of the continuum group energy, nu 0; got nu {nu!r}")
        k = k + asm(_compressed_shear(pad, indentation, g, "thin"), basis)
    k = k.tocsr()
    on_strip = lambda p: np.isclose(p[0], h) & (p[1] <= a + 1e-12)  # noqa: E731
    strip = basis.get_dofs(on_strip)
    axial, across_x = strip.all("u^3"), strip.all("u^1")  # the same nodes, in the same order
    core = basis.get_dofs(lambda p: np.isclose(p[0], 0.0)).all()
    mid_y = basis.get_dofs(lambda p: np.isclose(p[1], 0.0)).all("u^2")
    held = [core, strip.all("u^2"), mid_y]
    if goodman:
        mid_z = basis.get_dofs(lambda p: np.isclose(p[2], 0.0))
        held += [strip.all("u^1"), mid_z.all("u^1"), mid_z.all("u^2")]
    fixed = np.unique(np.concatenate(held))
    keep = ~np.isin(axial, fixed)
    axial, across_x = axial[keep], across_x[keep]
    # the normal force on each strip node before the pull: the pressure's consistent load (read on
    # the z component, whose shape functions are the same)
    top = mesh.facets_satisfying(lambda x: np.isclose(x[0], h) & (x[1] <= a + 1e-12))
    fb = FacetBasis(mesh, basis.elem, facets=top, intorder=6)
    order = np.argsort(y_profile)
    yp, pp = y_profile[order], pressure[order]
    weights = asm(LinearForm(lambda v, w: v[2] * np.interp(np.abs(w.x[1]), yp, pp)), fb)
    normal = np.asarray(weights[axial]).ravel()
    loc = basis.doflocs[:, axial]
    y_node, z_node = loc[1], loc[2]
    big_p = float(normal.sum())
    on = normal > 0.0
    mid = np.abs(z_node) <= 0.25 * pad.height

    def zone(sel: np.ndarray, stuck: np.ndarray, load: np.ndarray) -> float:
        lam_, y_ = load[sel], y_node[sel]
        share = float(lam_[stuck[sel]].sum() / lam_.sum())
        o = np.argsort(y_)
        cum = np.concatenate(([0.0], np.cumsum(lam_[o]) / lam_.sum()))
        return float(np.interp(share, cum, np.concatenate(([0.0], y_[o])))) / a

    free = np.setdiff1d(np.arange(k.shape[0]), fixed)
    if goodman:
        # the strip's axial compliance: C[i, j] the axial displacement of node i per unit axial force at j
        lu = splu(k[free][:, free].tocsc())
        pos = np.searchsorted(free, axial)
        rhs = np.zeros((free.size, axial.size))
        rhs[pos, np.arange(axial.size)] = 1.0
        c = lu.solve(rhs)[pos]
        c = 0.5 * (c + c.T)
        limit = mu * normal
        u_gross = float((c @ limit).max())  # every node at its cone: the strip's farthest lag
        stick = on.copy()
        rows = []
        for u in np.linspace(u_gross / steps, u_gross, steps)[:-1]:
            for _ in range(4 * axial.size):
                force = np.where(on & ~stick, limit, 0.0)
                s = np.flatnonzero(stick)
                if s.size:
                    force[s] = np.linalg.solve(c[np.ix_(s, s)], u - c[s] @ force)
                settled, stick = _coulomb_update(stick, on, force, limit, c @ force, u)
                if settled:
                    break
            else:
                raise RuntimeError("the active set did not settle")
            q = float(force.sum())
            rows.append((q / (mu * big_p), float(normal[stick].sum() / big_p), zone(on, stick, normal),
                         zone(on & mid, stick, normal), u, 4.0 * q))  # fmt: skip
            if not stick.any():
                break
        else:  # at u_gross every node at its cone is the solution (the last to stick is exactly there)
            rows.append((1.0, 0.0, 0.0, 0.0, u_gross, 4.0 * mu * big_p))
        arr = np.array(rows)
        return {"ratio": arr[:, 0], "share": arr[:, 1], "c_over_a": arr[:, 2], "c_over_a_mid": arr[:, 3],
                "U": arr[:, 4], "Q": arr[:, 5], "a": a}  # fmt: skip
    out = _partial_slip_unilateral(k, free, across_x, axial, normal, z_node < 0.0, mid, mu, steps, zone)
    out["a"] = a
    return out


def _share(load: np.ndarray, stick: np.ndarray, sel: np.ndarray) -> float:
    """The sticking nodes' share of the normal load over the nodes ``sel``."""
    return float(load[stick & sel].sum() / max(load[sel].sum(), 1e-300))


def _partial_slip_unilateral(k, free: np.ndarray, across_x: np.ndarray, axial: np.ndarray, normal: np.ndarray,
                             trailing: np.ndarray, mid: np.ndarray, mu: float, steps: int, zone) -> dict:  # fmt: skip
    """partial_slip_3d without Goodman's approximation (``goodman`` False), on the half model.

    The pad's stiffness is condensed onto the strip nodes' x and z displacements (every other free
    dof eliminated: K_ss - K_si K_ii^-1 K_is), increments from the pressed state. Per node, with F
    the force the cylinder exerts on the pad beyond the pressed state's (F = K_c u) and N = N0 -
    F_x its normal force (the cylinder pushes along -x): in contact u_x = 0, open F_x = N0 (N = 0);
    stuck u_z = U, sliding F_z = mu N. A contact opens where N < 0 and closes where an open node
    would move into the cylinder (u_x > 0); a stuck node slides where F_z > mu N; a sliding one
    sticks where it got ahead of the cylinder (u_z > U)."""
    from scipy.sparse.linalg import splu

    n = axial.size
    strip = np.concatenate([across_x, axial])
    inner = np.setdiff1d(free, strip)
    k_is = k[inner][:, strip].toarray()
    kc = k[strip][:, strip].toarray() - k_is.T @ splu(k[inner][:, inner].tocsc()).solve(k_is)
    kc = 0.5 * (kc + kc.T)
    kx, kz = kc[:n], kc[n:]  # the rows of F_x and F_z over (u_x, u_z)
    on = normal > 0.0
    tol = 1e-9 * float(normal.max())
    # Goodman's gross-slip travel sets the step; the trailing end's last nodes, pressed harder as
    # the pull grows, stick on beyond it
    u_gross = float(np.linalg.solve(kc[n:, n:], mu * normal).max())
    stick, closed = on.copy(), np.ones(n, dtype=bool)
    rows = []
    for u in u_gross / steps * np.arange(1, 10 * steps + 1):
        for _ in range(8 * n):
            # known: closed nodes' u_x = 0, stuck nodes' u_z = U; unknown: the rest, from the open
            # nodes' F_x = N0 (N = 0) and the sliding nodes' F_z = mu (N0 - F_x)
            slide = ~stick
            unknown = np.concatenate([~closed, slide])
            rows_ = np.concatenate([kx[~closed], kz[slide] + mu * kx[slide]])
            rhs = np.concatenate([normal[~closed], mu * normal[slide]])
            sol = np.zeros(2 * n)
            sol[n:][stick] = u
            if unknown.any():
                sol[unknown] = np.linalg.solve(rows_[:, unknown], rhs - rows_[:, ~unknown] @ sol[~unknown])
            fx, fz = kx @ sol, kz @ sol
            now = normal - fx
            opens = closed & (now < -tol)
            closes = ~closed & (sol[:n] > 0.0)
            over = stick & (fz > mu * np.maximum(now, 0.0) + tol)
            ahead = slide & closed & on & (sol[n:] > u * (1.0 + 1e-12))
            if not (opens.any() or closes.any() or over.any() or ahead.any()):
                break
            closed = (closed & ~opens) | closes
            stick = ((stick & ~over) | ahead) & closed
        else:
            raise RuntimeError("the active set did not settle")
        q = float(fz.sum())
        load = np.maximum(now, 0.0)
        rows.append((q / (mu * float(load.sum())), _share(load, stick, on), zone(on, stick, load),
                     zone(on & mid, stick, load), u, 2.0 * q, _share(load, stick, on & trailing),
                     _share(load, stick, on & ~trailing), float((~closed).sum())))  # fmt: skip
        if not stick.any():
            break
    else:
        raise RuntimeError("the strip had not slid entirely at ten times Goodman's gross-slip travel")
    arr = np.array(rows)
    keys = ("ratio", "share", "c_over_a", "c_over_a_mid", "U", "Q", "trailing", "leading", "open")
    return {key: arr[:, i] for i, key in enumerate(keys)}


def at_ratios(ramp: dict, ratios, key: str = "c_over_a") -> np.ndarray:
    """A partial-slip ramp's ``key`` (LayerModel.partial_slip, partial_slip_3d) at each Q / mu P in
    ``ratios``, linearly between the ramp's steps; NaN beyond its last step."""
    r = np.asarray(ramp["ratio"])
    return np.array([np.interp(x, r, ramp[key]) if x <= r[-1] else math.nan for x in ratios])


def _shear_pair_modulus(pad: Pad, indentation: float):
    """(x, y) -> (2, 2, ...) the continuum energy's shear modulus of the pair (dw/dx, dw/dy) about
    the plane-strain pad (nu 0) pressed ``indentation`` [m] by the cylinder: 2 G sum_i s_i / (1 +
    s_i) v_i v_i^T from the SVD of F2 = I + grad u (tangential_compliance_3d's "plane_strain")."""
    from scipy.interpolate import LinearNDInterpolator, NearestNDInterpolator

    model = LayerModel(pad, 0.0)
    c = model.contact(indentation)
    load = np.zeros(model.basis.N)
    load[model.surface] = -c["f"]
    grad = model.basis.interpolate(model.solve(load)).grad  # (2, 2, elements, points)
    pts = model.basis.mapping.F(model.basis.X)  # (2, elements, points)
    xy = np.stack([pts[0].ravel(), pts[1].ravel()], axis=1)
    f2 = np.eye(2)[:, :, None] + grad.reshape(2, 2, -1)
    u, sv, vt = np.linalg.svd(np.moveaxis(f2, 2, 0))  # F2 = U S V^T per point
    v = np.swapaxes(vt, 1, 2)  # columns: the right singular vectors (reference frame)
    m = 2.0 * pad.shear_modulus * np.einsum("nik,nk,njk->nij", v, sv / (1.0 + sv), v).reshape(-1, 4)
    linear, nearest = LinearNDInterpolator(xy, m), NearestNDInterpolator(xy, m)

    def modulus(x, y):
        q = np.stack([x.ravel(), y.ravel()], axis=1)
        out = linear(q)
        bad = np.isnan(out).any(axis=1)
        out[bad] = nearest(q[bad])
        return np.moveaxis(out.reshape(*x.shape, 2, 2), (-2, -1), (0, 1))

    return modulus


def reference(pad: Pad | None = None, *, nus=NUS, loads=LOADS, level: int = LEVEL,
              tangential_loads=TANGENTIAL_LOADS, tangential_element: float = TANGENTIAL_ELEMENT) -> list[dict]:  # fmt: skip
    """One row per (nu, load): indentation [m], half-width [m], peak pressure [Pa], one pad's
    tangential compliance along the cylinder's axis [m/N] ("compliance": the 3-D pad,
    tangential_compliance_3d, at the loads in ``tangential_loads``, NaN at the others;
    "compliance_2d": the anti-plane pad of infinite length), the pressure profile (y, p) and its
    pressure-weighted RMS half-width ("width", pressure_width).
    ``tangential_element``: the 3-D model's element size [m] (4 mm: 1.3 % stiffer than the finest)."""
    pad = pad or default_pad()
    rows = []
    for nu in nus:
        model = LayerModel(pad, nu, level)
        for load in loads:
            delta, c = model.indentation(load)
            full = (tangential_compliance_3d(pad, c["a"], nu, element=tangential_element) if load in tangential_loads
                    else math.nan)  # fmt: skip
            rows.append({"nu": nu, "load": load, "delta": delta, "a": c["a"], "p_max": float(c["pressure"].max()),
                         "compliance": full, "compliance_2d": model.tangential_compliance(c["a"]),
                         "width": pressure_width(model.y, c["pressure"]),
                         "y": model.y.copy(), "pressure": c["pressure"].copy(),
                         "penetration": c["penetration"]})  # fmt: skip
    return rows


def verify(pad: Pad | None = None, *, levels=(2, 4, 8, 16, 32), quick: bool = False) -> dict:
    """The reference against analytic limits and itself; returns every number it prints."""
    pad = pad or default_pad()
    out: dict = {}
    print("1. laterally confined layer (roller sides) under uniform pressure 1 kPa, level 4:")
    out["confined"] = {}
    for nu in NUS:
        u = -LayerModel(pad, nu, 4, sides="roller").uniform_pressure(1000.0)
        exact = confined_compression(1000.0, pad.thickness, pad.shear_modulus, nu)
        err = float(np.abs(u - exact).max() / exact)
        out["confined"][nu] = err
        print(f"   nu {nu:<5} FE {u.mean() * 1e3:.6f} mm, exact {exact * 1e3:.6f} mm, largest relative error {err:.1e}")
    print("   the finger's face (free sides) under the same pressure: mean compression / confined")
    for nu in NUS:
        u = -LayerModel(pad, nu, 8).uniform_pressure(1000.0)
        print(f"   nu {nu:<5} {u.mean() / confined_compression(1000.0, pad.thickness, pad.shear_modulus, nu):.4f}")
    print("2. thin layer under the cylinder (face 8 a wide, delta 0.5 mm) against the thin-layer limit\n"
          "   P = (M / h) * integral of the interference (the circle), a = sqrt(R^2 - (R - delta)^2);\n"
          "   ratios FE / limit as h / a falls:")  # fmt: skip
    out["thin"] = {}
    delta = 5e-4
    a = math.sqrt(pad.radius**2 - (pad.radius - delta) ** 2)
    for nu in (0.0, 0.3):
        ratios = []
        for h in ((2e-3, 1e-3, 5e-4) if quick else (2e-3, 1e-3, 5e-4, 2.5e-4)):
            thin = Pad(h, 8 * a, pad.height, pad.radius, pad.shear_modulus)
            model = LayerModel(thin, nu, 4, across=min(h / 4, a / 60))
            c = model.contact(delta)
            ratios.append((h / a, c["P"] / thin_layer_load(delta, thin, nu), c["a"] / a))
        out["thin"][nu] = ratios
        print(f"   nu {nu}: " + ", ".join(f"h/a {r:.3f}: P {p:.4f}, a {s:.3f}" for r, p, s in ratios))
    print("3. mesh convergence, indentation under 3 N and tangential compliance (e = h / level at the surface):")
    out["mesh"] = {}
    for nu in (0.3,) if quick else NUS:
        vals = []
        for lvl in levels:
            tic = time.perf_counter()
            model = LayerModel(pad, nu, lvl)
            d, c = model.indentation(3.0)
            comp = model.tangential_compliance(c["a"])
            vals.append((lvl, model.dof_count, d, c["a"], comp, time.perf_counter() - tic))
        orders = []
        for k in range(len(vals) - 2):
            e1 = abs(vals[k][2] - vals[k + 1][2])
            e2 = abs(vals[k + 1][2] - vals[k + 2][2])
            orders.append(math.log2(e1 / e2) if e2 > 0 and e1 > 0 else math.nan)
        out["mesh"][nu] = {"rows": vals, "orders": orders}
        print(f"   nu {nu}:")
        for (lvl, dofs, d, a_, comp, secs), ref in zip(vals, [None] + vals[:-1], strict=True):
            step = "" if ref is None else f"  change {(d - ref[2]) / d:+.2e}"
            print(f"     level {lvl:>2} ({dofs:>6} dofs, {secs:5.1f} s): delta {d * 1e3:.5f} mm{step}, "
                  f"a {a_ * 1e3:.3f} mm, compliance {comp * 1e3:.5f} mm/N")  # fmt: skip
        print("     observed order of delta: " + ", ".join(f"{o:.2f}" for o in orders))
    print("4. the 3-D tangential model (nu 0, the strip of 3 N): element size, and a longer pad toward the\n"
          "   anti-plane pad of infinite length (compliance per H, 4 mm elements)")  # fmt: skip
    a = LayerModel(pad, 0.0, LEVEL).indentation(3.0)[1]["a"]
    out["tangential_3d"] = {"elements": [], "lengths": [], "anti_plane": LayerModel(pad, 0.0, LEVEL).tangential_compliance(a)}
    for element in (4e-3,) if quick else (4e-3, 2e-3):
        out["tangential_3d"]["elements"].append((element, tangential_compliance_3d(pad, a, 0.0, element=element)))
    for k in (1, 2, 4, 8):
        out["tangential_3d"]["lengths"].append((k, tangential_compliance_3d(pad, a, 0.0, element=4e-3, length=k * pad.height)))
    print("   elements: " + ", ".join(f"{e * 1e3:g} mm {c * 1e3:.4f} mm/N" for e, c in out["tangential_3d"]["elements"]))
    print("   lengths:  " + ", ".join(f"{k} H {c * 1e3:.4f}" for k, c in out["tangential_3d"]["lengths"])
          + f" mm/N; anti-plane {out['tangential_3d']['anti_plane'] * 1e3:.4f} mm/N")  # fmt: skip
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer levels and Poisson ratios")
    parser.add_argument("--plot", default=None, help="draw the load-indentation curves and pressure profiles to this PNG")
    ns = parser.parse_args(argv)
    pad = default_pad()
    print(f"pad: layer h {pad.thickness * 1e3:g} mm, face {pad.width * 1e3:g} x {pad.height * 1e3:g} mm, "
          f"cylinder R {pad.radius * 1e3:g} mm, G {pad.shear_modulus:g} Pa")  # fmt: skip
    tic = time.perf_counter()
    verify(pad, levels=(2, 4, 8, 16) if ns.quick else (2, 4, 8, 16, 32), quick=ns.quick)
    print(f"\nreference at level {LEVEL}:")
    print(f"{'nu':>5}{'load N':>8}{'delta mm':>10}{'a mm':>8}{'p_max Pa':>10}{'tang. 3-D mm/N':>16}{'anti-plane':>12}")
    for r in reference(pad):
        print(f"{r['nu']:>5}{r['load']:>8g}{r['delta'] * 1e3:>10.4f}{r['a'] * 1e3:>8.2f}{r['p_max']:>10.0f}"
              f"{r['compliance'] * 1e3:>16.4f}{r['compliance_2d'] * 1e3:>12.4f}")  # fmt: skip
    print(f"\n{time.perf_counter() - tic:.1f} s")
    if ns.plot:
        plot(pad, ns.plot)
    return 0


def plot(pad: Pad, path: str) -> None:
    """Load against indentation for each nu, and the pressure across the contact strip at 1, 3, 6 N."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(8.0, 3.2))
    forces = np.linspace(0.25, 6.0, 24)
    for nu, style in zip(NUS, (":", "--", "-."), strict=True):
        model = LayerModel(pad, nu, LEVEL)
        axes[0].plot([model.indentation(f)[0] * 1e3 for f in forces], forces, style, label=f"nu {nu:g}")
        for load, colour in zip(LOADS, ("C0", "C1", "C2"), strict=True):
            _, c = model.indentation(load)
            axes[1].plot(model.y * 1e3, c["pressure"], style, color=colour, lw=1,
                         label=f"{load:g} N" if nu == NUS[0] else None)  # fmt: skip
    axes[0].set_xlabel("indentation [mm]", fontsize=8)
    axes[0].set_ylabel("load on the pad [N]", fontsize=8)
    axes[0].legend(fontsize=7)
    axes[1].set_xlabel("y across the face [mm]", fontsize=8)
    axes[1].set_ylabel("contact pressure [Pa]", fontsize=8)
    axes[1].set_title("dotted nu 0, dashed 0.3, dash-dot 0.45", fontsize=8)
    axes[1].legend(fontsize=7)
    for ax in axes:
        ax.tick_params(labelsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    print(f"wrote {path}")


if __name__ == "__main__":
    raise SystemExit(main())
