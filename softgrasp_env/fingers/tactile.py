"""Tactile pads: a fixed grid of taxels on each finger core's inner face, read from the
simulation's state (no new physics).

A taxel carries five channels (:data:`TAXEL_CHANNELS`), in the finger core's frame (x across the
gap, y along the face, z up; the two cores share the gripper's yaw, so y and z mean the same
direction on both pads):

- ``pressure`` [Pa]: the normal load the pad takes from whatever touches it under the taxel, the
  contact forces' component into the face over the taxel's area (compressive positive);
- ``traction_y``, ``traction_z`` [Pa]: the tangential (friction) load on the pad under the taxel
  along y and z, per area;
- ``shear_y``, ``shear_z`` [m]: how far the tissue under the taxel has sheared, the mean
  displacement along y and z of its free particles from the spots their core carries them to.
  Only tissue deforms: a rigid pad reads 0 here, always.

Each tissue particle stands for a cell of the face (the builder spreads them over a cell-centred
grid): its contact's load and its displacement are spread over the taxels its cell covers, by
area, so a grid finer or coarser than the particles reads a field whose total is the load (the
default pad has 3 x 4 free particles on its inner face, 13 x 15 mm cells).

The rigid kinds bin pybullet's contact points and forces (normal force and both lateral friction
forces, the same law as the tissue's) onto the same grid: every signal their engine gives. The
tissue reads its solver's contacts of the last world step (each contact binned where its
particle sits at rest, a taxel being fixed to the core) and its particles' displacements.

Rows run from the top of the face (row 0, z = +half height) down; columns from -y to +y. The grid
covers the inner face only: a contact elsewhere (the tip, the back) is not under any taxel.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

from ..tissue.rotation import qmat
from ..validation import check_int

TAXEL_CHANNELS: tuple[str, ...] = ("pressure", "traction_y", "traction_z", "shear_y", "shear_z")
"""The channels of a taxel, in order (the last axis of a tactile reading)."""
INNER_NORMAL = (1.0, -1.0)
"""Sign of each core's inner face normal along its x axis (left core +x, right core -x: toward the
other finger; fingers.tissue.CONTACT_FACES)."""
MAX_TAXELS = 32
"""Largest rows or columns of a grid: a pad is a few cm; finer taxels than its particles say nothing more."""


@dataclass(frozen=True)
class TaxelGrid:
    """``rows`` x ``cols`` taxels over a face of half extents ``half_width`` (along the core's y)
    and ``half_height`` (z) [m], centred on the face."""

    rows: int
    cols: int
    half_width: float
    half_height: float

    def __post_init__(self) -> None:
        check_int("rows", self.rows, 1, MAX_TAXELS, owner="TaxelGrid")
        check_int("cols", self.cols, 1, MAX_TAXELS, owner="TaxelGrid")
        for name in ("half_width", "half_height"):
            v = getattr(self, name)
            if not (isinstance(v, float | int) and np.isfinite(v) and v > 0.0):
                raise ValueError(f"TaxelGrid.{name} must be a finite length > 0 [m], got {v!r}")

    @property
    def area(self) -> float:
        """One taxel's area [m^2]."""
        return 4.0 * self.half_width * self.half_height / (self.rows * self.cols)

    @property
    def shape(self) -> tuple[int, int, int, int]:
        """The shape of a reading: (fingers, rows, cols, channels)."""
        return (2, self.rows, self.cols, len(TAXEL_CHANNELS))

    def empty(self) -> np.ndarray:
        return np.zeros(self.shape)

    def params(self) -> np.ndarray:
        """(rows, cols, half_width, half_height, area) for the kernels."""
        return np.array([self.rows, self.cols, self.half_width, self.half_height, self.area], dtype=np.float64)

    def taxel(self, y: float, z: float) -> tuple[int, int] | None:
        """(row, col) of the taxel over the face point (y, z) in the core frame, or None off the face."""
        k = _taxel(y, z, self.params())
        return None if k < 0 else divmod(k, self.cols)


@nb.njit(cache=True, inline="always")
def _taxel(y, z, grid):
    """Flat index row * cols + col of the taxel over (y, z), or -1 off the face (a point on an
    edge belongs to the taxel inside it)."""
    rows, cols, hw, hh = int(grid[0]), int(grid[1]), grid[2], grid[3]
    if not (-hw <= y <= hw and -hh <= z <= hh):
        return -1
    c = min(int((y + hw) / (2.0 * hw) * cols), cols - 1)
    r = min(int((hh - z) / (2.0 * hh) * rows), rows - 1)
    return r * cols + c


@nb.njit(cache=True)
def _spread(y, z, hy, hz, grid, index, weight):
    """The taxels a footprint of half extents (hy, hz) centred on (y, z) covers, with the share of
    its on-face area over each (summing to 1): ``index`` / ``weight`` filled, the count returned
    (0: entirely off the face). A point (hy = hz = 0) goes whole to its taxel."""
    if hy <= 0.0 or hz <= 0.0:
        t = _taxel(y, z, grid)
        if t < 0:
            return 0
        index[0] = t
        weight[0] = 1.0
        return 1
    rows, cols, hw, hh = int(grid[0]), int(grid[1]), grid[2], grid[3]
    y0, y1 = max(y - hy, -hw), min(y + hy, hw)
    z0, z1 = max(z - hz, -hh), min(z + hz, hh)
    if y1 <= y0 or z1 <= z0:
        return 0
    cw = 2.0 * hw / cols
    rh = 2.0 * hh / rows
    c0 = min(int((y0 + hw) / cw), cols - 1)
    c1 = min(int((y1 + hw) / cw), cols - 1)
    r0 = min(int((hh - z1) / rh), rows - 1)
    r1 = min(int((hh - z0) / rh), rows - 1)
    total = (y1 - y0) * (z1 - z0)
    n = 0
    for r in range(r0, r1 + 1):
        top = hh - r * rh
        oz = min(z1, top) - max(z0, top - rh)
        if oz <= 0.0:
            continue
        for c in range(c0, c1 + 1):
            left = -hw + c * cw
            oy = min(y1, left + cw) - max(y0, left)
            if oy <= 0.0:
                continue
            index[n] = r * cols + c
            weight[n] = oy * oz / total
            n += 1
    return n


@nb.njit(cache=True)
def bin_loads(finger, points, forces, sign, grid, out):
    """Add point loads to finger ``finger``'s taxels: ``points`` (N, 3) where each acts and
    ``forces`` (N, 3) the force on the pad [N], both in the core's frame; ``sign`` its inner face
    normal along x (INNER_NORMAL). Pressure is the force into the face, -F . n, per area."""
    cols = int(grid[1])
    area = grid[4]
    for k in range(points.shape[0]):
        t = _taxel(points[k, 1], points[k, 2], grid)
        if t < 0:
            continue
        r, c = t // cols, t % cols
        out[finger, r, c, 0] -= sign * forces[k, 0] / area
        out[finger, r, c, 1] += forces[k, 1] / area
        out[finger, r, c, 2] += forces[k, 2] / area


@nb.njit(cache=True)
def bin_contacts(finger, rows, core_pose, sign, grid, out):
    """pybullet's contact points of one finger onto its taxels: ``rows`` (N, 16) per point its
    position on the finger (3), contactNormalOnB (3), lateralFrictionDir1 (3), lateralFrictionDir2
    (3), normal force, lateral friction 1 and 2 [N], and the sense (+1 / -1) the friction acts on
    the finger in; ``core_pose`` the core's centre of mass and orientation (x, y, z, qx, qy, qz,
    qw). The force on the finger, N n + sense (f1 d1 + f2 d2), into the core's frame (R^T), is
    binned by :func:`bin_loads`."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = qmat((core_pose[3], core_pose[4], core_pose[5], core_pose[6]))
    n = rows.shape[0]
    points = np.empty((n, 3))
    forces = np.empty((n, 3))
    for k in range(n):
        px, py, pz = rows[k, 0] - core_pose[0], rows[k, 1] - core_pose[1], rows[k, 2] - core_pose[2]
        points[k, 0] = r00 * px + r10 * py + r20 * pz
        points[k, 1] = r01 * px + r11 * py + r21 * pz
        points[k, 2] = r02 * px + r12 * py + r22 * pz
        sense, normal, f1, f2 = rows[k, 15], rows[k, 12], rows[k, 13], rows[k, 14]
        fx = normal * rows[k, 3] + sense * (f1 * rows[k, 6] + f2 * rows[k, 9])
        fy = normal * rows[k, 4] + sense * (f1 * rows[k, 7] + f2 * rows[k, 10])
        fz = normal * rows[k, 5] + sense * (f1 * rows[k, 8] + f2 * rows[k, 11])
        forces[k, 0] = r00 * fx + r10 * fy + r20 * fz
        forces[k, 1] = r01 * fx + r11 * fy + r21 * fz
        forces[k, 2] = r02 * fx + r12 * fy + r22 * fz
    bin_loads(finger, points, forces, sign, grid, out)


@nb.njit(cache=True, inline="always")
def _core_rotations(rig_q, core_rigid):
    """(2, 9) each finger core's rotation matrix, row-major (rotation.qmat)."""
    out = np.empty((2, 9))
    for b in range(min(core_rigid.shape[0], 2)):
        r = core_rigid[b]
        m = qmat((rig_q[r, 0], rig_q[r, 1], rig_q[r, 2], rig_q[r, 3]))
        for a in range(9):
            out[b, a] = m[a]
    return out


@nb.njit(cache=True)
def tissue_loads(nc, c_particle, c_inner, c_lambda, c_normal, c_friction, c_patch, patch_slide, patch_change, p_body,
                 rest_x, footprint, rig_q, core_rigid, dt, grid, out, single):  # fmt: skip
    """The tissue's contacts of its last step on each body's (finger's) taxels: the force the
    shape put on the particle, (lambda n + f) / dt^2 (Mueller et al. 2020 eq. 6: the multipliers
    are positional impulses), f the friction's positional impulse (friction.friction_patches). A
    sliding patch takes as much friction again in its velocity pass (kinetic friction is half on
    positions, half on velocities), so its contacts' friction counts twice; a single contact's
    patch (rows from ``single`` on: friction_law "contact") applies its kinetic friction at
    position level alone, so it counts once. A contact's load is
    spread over the taxels under its particle's footprint at rest (``rest_x`` and ``footprint``,
    the half extents of the face cell the particle stands for: a taxel is fixed to the core),
    turned into the core's frame by its orientation ``rig_q[core_rigid[body]]``. A particle's
    contact with its own core (inner) is internal, not a load on the pad."""
    cols = int(grid[1])
    area = grid[4]
    inv = 1.0 / (dt * dt)
    index = np.empty(int(grid[0]) * cols, dtype=np.int64)
    weight = np.empty(int(grid[0]) * cols)
    rot = _core_rotations(rig_q, core_rigid)
    for c in range(nc):
        lam = c_lambda[c]
        if c_inner[c] or lam <= 0.0:
            continue
        i = c_particle[c]
        b = p_body[i]
        if b > 1:
            continue
        n = _spread(rest_x[i, 1], rest_x[i, 2], footprint[i, 0], footprint[i, 1], grid, index, weight)
        if n == 0:
            continue
        k = 1.0
        pt = c_patch[c]
        if 0 <= pt < single and patch_slide[pt] and not patch_change[pt]:
            k = 2.0
        fx = (lam * c_normal[c, 0] + k * c_friction[c, 0]) * inv
        fy = (lam * c_normal[c, 1] + k * c_friction[c, 1]) * inv
        fz = (lam * c_normal[c, 2] + k * c_friction[c, 2]) * inv
        lx = rot[b, 0] * fx + rot[b, 3] * fy + rot[b, 6] * fz  # R^T f: into the core's frame
        ly = rot[b, 1] * fx + rot[b, 4] * fy + rot[b, 7] * fz
        lz = rot[b, 2] * fx + rot[b, 5] * fy + rot[b, 8] * fz
        sign = 1.0 if b == 0 else -1.0
        for e in range(n):
            row, col = index[e] // cols, index[e] % cols
            w = weight[e] / area
            out[b, row, col, 0] -= sign * lx * w
            out[b, row, col, 1] += ly * w
            out[b, row, col, 2] += lz * w


@nb.njit(cache=True)
def tissue_shear(x, rest_x, footprint, surface, offsets, rig_x, rig_q, core_rigid, grid, out):
    """Each taxel's shear displacement along y and z [m]: over the surface particles (``surface``,
    (N,) bool: the free outer particles, tissue.builder.surface_particles; with one layer through
    the thickness every free particle) of the pad's inner face (rest x beyond the core's centre
    plane, toward the other finger) whose footprints cover it, the footprint-weighted mean of their
    displacement from the spot their core carries them to, in the core's frame. A pad's inner
    layers (TissueConfig.layers > 1) are left out: they shear less than the surface the taxel
    reads."""
    cols = int(grid[1])
    counts = np.zeros((2, out.shape[1], out.shape[2]))
    index = np.empty(int(grid[0]) * cols, dtype=np.int64)
    weight = np.empty(int(grid[0]) * cols)
    rot = _core_rotations(rig_q, core_rigid)
    for b in range(min(offsets.shape[0] - 1, 2)):
        sign = 1.0 if b == 0 else -1.0
        r = core_rigid[b]
        r01, r11, r21 = rot[b, 1], rot[b, 4], rot[b, 7]  # the y and z rows of R^T
        r02, r12, r22 = rot[b, 2], rot[b, 5], rot[b, 8]
        for i in range(offsets[b], offsets[b + 1]):
            if not surface[i] or sign * rest_x[i, 0] <= 0.0:
                continue
            n = _spread(rest_x[i, 1], rest_x[i, 2], footprint[i, 0], footprint[i, 1], grid, index, weight)
            if n == 0:
                continue
            dx = x[i, 0] - rig_x[r, 0]
            dy = x[i, 1] - rig_x[r, 1]
            dz = x[i, 2] - rig_x[r, 2]
            ly = r01 * dx + r11 * dy + r21 * dz - rest_x[i, 1]
            lz = r02 * dx + r12 * dy + r22 * dz - rest_x[i, 2]
            for e in range(n):
                row, col = index[e] // cols, index[e] % cols
                out[b, row, col, 3] += weight[e] * ly
                out[b, row, col, 4] += weight[e] * lz
                counts[b, row, col] += weight[e]
    for b in range(2):
        for row in range(out.shape[1]):
            for col in range(out.shape[2]):
                if counts[b, row, col] > 0.0:
                    out[b, row, col, 3] /= counts[b, row, col]
                    out[b, row, col, 4] /= counts[b, row, col]


SLIP_RATIO = 0.9
"""A taxel reads as sliding when its traction is at least this share of mu times its pressure
(:func:`sliding_share`): under Coulomb's law a contact slides at the cone, and a taxel averages
its contacts, so the edge of a partially slipping strip reads just under mu."""
SLIP_SHARE = 0.1
"""The share of a pad's pressure on sliding taxels at which :func:`slip_warning` warns."""


def sliding_share(taxels: np.ndarray, mu: float, *, ratio: float = SLIP_RATIO) -> np.ndarray:
    """Per pad, the share of its pressure that sits on taxels whose traction reaches ``ratio`` x
    ``mu`` x their pressure: Cattaneo and Mindlin's slip annulus read through the taxels (Johnson,
    Contact Mechanics, sec. 7.2: under a growing tangential load a contact's edges slide first and
    the sliding zone grows inward until the whole contact slides at Q = mu P). ``taxels``: (2, rows,
    cols, channels) as the pads read (:data:`TAXEL_CHANNELS`), or a batch (..., 2, rows, cols,
    channels); ``mu``: the friction coefficient the detector assumes. Returns (..., 2); a pad
    pressing nothing reads 0."""
    if not (np.isfinite(mu) and mu > 0.0):
        raise ValueError(f"mu must be a finite coefficient > 0, got {mu!r}")
    if not (0.0 < ratio <= 1.0):
        raise ValueError(f"ratio must be in (0, 1], got {ratio!r}")
    taxels = np.asarray(taxels, dtype=np.float64)
    if taxels.ndim < 4 or taxels.shape[-4] != 2 or taxels.shape[-1] != len(TAXEL_CHANNELS):
        raise ValueError(f"taxels must be (..., 2, rows, cols, {len(TAXEL_CHANNELS)}), got shape {taxels.shape}")
    pressure = np.maximum(taxels[..., 0], 0.0)
    traction = np.hypot(taxels[..., 1], taxels[..., 2])
    sliding = (pressure > 0.0) & (traction >= ratio * mu * pressure)
    total = pressure.sum(axis=(-2, -1))
    return np.where(total > 0.0, (pressure * sliding).sum(axis=(-2, -1)) / np.where(total > 0.0, total, 1.0), 0.0)


def slip_warning(taxels: np.ndarray, mu: float, *, ratio: float = SLIP_RATIO, share: float = SLIP_SHARE) -> np.ndarray:
    """True where either pad's :func:`sliding_share` reaches ``share``: part of the grip slides,
    the rest still sticks. Shape (...) for taxels (..., 2, rows, cols, channels)."""
    if not (0.0 < share <= 1.0):
        raise ValueError(f"share must be in (0, 1], got {share!r}")
    return (sliding_share(taxels, mu, ratio=ratio) >= share).any(axis=-1)


SHEAR_LAG = 0.25
"""The :func:`shear_lag` at which :func:`shear_lag_warning` warns. Under a steady hold the
v4 tissue's pads read at most 0.18 below half the slip load (the pad's own uneven shear near its
boundary), and 0.27-0.54 at three quarters of it."""
PRESSED_SHARE = 0.2
"""A taxel takes part in :func:`shear_lag` when its pressure is at least this share of the pad's
largest: the contact strip and its edges, not the bare face around it, whose shear only follows
the tissue beside it."""


def _check_taxels(taxels) -> np.ndarray:
    taxels = np.asarray(taxels, dtype=np.float64)
    if taxels.ndim < 4 or taxels.shape[-4] != 2 or taxels.shape[-1] != len(TAXEL_CHANNELS):
        raise ValueError(f"taxels must be (..., 2, rows, cols, {len(TAXEL_CHANNELS)}), got shape {taxels.shape}")
    if not np.isfinite(taxels).all():
        raise ValueError("taxels must be finite (a reading with NaN or inf)")
    return taxels


def _along_net(taxels: np.ndarray, channels: slice, pressed: float) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                                          np.ndarray]:  # fmt: skip
    """What :func:`shear_lag` and :func:`edge_friction` read: per taxel, whether it is pressed (at
    least ``pressed`` times its pad's largest pressure), its pressure, and the in-face vector of
    ``channels`` (shear or traction) projected on the direction of the pad's sum of it over the
    pressed taxels; per pad, the size of that sum (0: no direction)."""
    if not (np.isfinite(pressed) and 0.0 <= pressed <= 1.0):
        raise ValueError(f"pressed must be a share of the pad's largest pressure in [0, 1], got {pressed!r}")
    taxels = _check_taxels(taxels)
    pressure = np.maximum(taxels[..., 0], 0.0)
    vec = taxels[..., channels]
    on = (pressure > 0.0) & (pressure >= pressed * pressure.max(axis=(-2, -1), keepdims=True))
    total = (vec * on[..., None]).sum(axis=(-3, -2))
    size = np.linalg.norm(total, axis=-1)
    direction = total / np.where(size > 0.0, size, 1.0)[..., None]
    return on, pressure, (vec * direction[..., None, None, :]).sum(axis=-1), size


def shear_lag(taxels: np.ndarray, *, pressed: float = PRESSED_SHARE) -> np.ndarray:
    """Per pad, how far the least sheared of its pressed taxels lags behind the most sheared, along
    the pad's mean shear: 1 - min / max of the taxels' shear projected on the direction of the
    pad's summed shear, over the taxels pressed with at least ``pressed`` times the pad's largest
    pressure; dimensionless, in [0, 1] (0: the pad shears as one; 1: a pressed taxel has not
    sheared at all, or sheared backward). It needs neither the friction coefficient nor the load.

    Why it reads slip before it happens (Cattaneo and Mindlin; Johnson, Contact Mechanics, sec.
    7.2): under a tangential load Q below mu P, the stick zone at the contact's centre moves with
    the object and the surface there is displaced by the whole tangential displacement, while in
    the slip annulus at the edges, where the pressure is lowest, the surface slides back against
    the object and is displaced less, by the slip accumulated there. The annulus grows inward as Q
    nears mu P, so the shear field, even while the contact sticks (an elastic pad shears as one
    layer), grows uneven across the contact: its edges lag its centre. Gross slip is Q = mu P.

    ``taxels``: (2, rows, cols, channels) as the pads read (:data:`TAXEL_CHANNELS`), or a batch
    (..., 2, rows, cols, channels). Returns (..., 2). A pad that presses nothing, or has not
    sheared along its mean direction (the rigid kinds read no shear), reads 0: no signal, not
    "no slip"."""
    on, _, along, size = _along_net(taxels, slice(3, 5), pressed)
    most = np.where(on, along, -np.inf).max(axis=(-2, -1))
    least = np.where(on, along, np.inf).min(axis=(-2, -1))
    signal = on.any(axis=(-2, -1)) & (size > 0.0) & (most > 0.0)
    return np.where(signal, np.clip(1.0 - least / np.where(signal, most, 1.0), 0.0, 1.0), 0.0)


def shear_lag_warning(taxels: np.ndarray, *, lag: float = SHEAR_LAG, pressed: float = PRESSED_SHARE) -> np.ndarray:
    """True where either pad's :func:`shear_lag` reaches ``lag`` (in (0, 1]): the edges of a
    contact have begun to slide while its centre sticks. Unlike :func:`slip_warning` it does not
    need mu, so a policy can use it; it reads the tissue's shear, which rigid pads do not have
    (there it never warns). Shape (...) for taxels (..., 2, rows, cols, channels)."""
    if not (np.isfinite(lag) and 0.0 < lag <= 1.0):
        raise ValueError(f"lag must be in (0, 1], got {lag!r}")
    return (shear_lag(taxels, pressed=pressed) >= lag).any(axis=-1)


def edge_friction(taxels: np.ndarray, *, pressed: float = PRESSED_SHARE) -> np.ndarray:
    """Per pad, the largest traction-to-pressure ratio over its pressed taxels (pressure at least
    ``pressed`` times the pad's largest), the traction taken along the pad's summed traction;
    dimensionless. While part of the contact slides (:func:`shear_lag_warning` on), its sliding
    edge carries Coulomb's mu times its pressure, so this reads mu without being told it; while the
    whole contact sticks it reads less (a lower bound). Taking the traction along the pad's net
    traction leaves out the in-face part of the normal force on a curved contact's flanks (the
    contact normals fan out across the strip and their in-face components cancel over the pad), which
    would read as friction. Same ``taxels`` as :func:`shear_lag`; (..., 2), 0 for a pad that
    presses nothing or carries no traction."""
    on, pressure, along, size = _along_net(taxels, slice(1, 3), pressed)
    ratio = np.where(on, along / np.where(on, pressure, 1.0), 0.0).max(axis=(-2, -1))
    return np.where(size > 0.0, np.maximum(ratio, 0.0), 0.0)


def face_footprints(rest_x: np.ndarray, surface: np.ndarray, offsets: np.ndarray, half_width: float,
                    half_height: float) -> np.ndarray:  # fmt: skip
    """(N, 2) half extents along y and z of the face cell each particle stands for: the builder
    spreads a face's points over a cell-centred grid (tissue.builder.sample_surface), n_y x n_z
    cells over the inner face, so each inner-face particle (and the rest of its column: its
    attached partner, and the inner layers' particles) stands for a cell of half extents
    (half_width / n_y, half_height / n_z); 0 for the rest (the tip's, the back's). n_y, n_z are
    counted from each body's inner-face surface particles (``surface``, (N,) bool:
    tissue.builder.surface_particles)."""
    out = np.zeros((rest_x.shape[0], 2))
    for b in range(min(len(offsets) - 1, 2)):
        sign = INNER_NORMAL[b]
        idx = np.arange(offsets[b], offsets[b + 1])
        face = idx[(sign * rest_x[idx, 0] > 0.0) & (np.abs(rest_x[idx, 2]) < half_height)
                   & (np.abs(rest_x[idx, 1]) < half_width)]  # fmt: skip
        free = face[surface[face]]
        if free.size == 0:
            continue
        ny = np.unique(np.round(rest_x[free, 1], 9)).size
        nz = np.unique(np.round(rest_x[free, 2], 9)).size
        out[face] = (half_width / ny, half_height / nz)
    return out


__all__ = ["INNER_NORMAL", "MAX_TAXELS", "PRESSED_SHARE", "SHEAR_LAG", "SLIP_RATIO", "SLIP_SHARE", "TAXEL_CHANNELS",
           "TaxelGrid", "bin_contacts", "bin_loads", "edge_friction", "face_footprints", "shear_lag", "shear_lag_warning", "sliding_share",
           "slip_warning",
           "tissue_loads", "tissue_shear"]  # fmt: skip
