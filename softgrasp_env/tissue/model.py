"""Static description of all tissue in a world: struct-of-arrays, float64, built once.

Several tissue bodies share one model so that one solver call handles them all (and their
contacts with each other). Particles of a body are contiguous: ``body_particle_offsets[b]`` to
``body_particle_offsets[b + 1]``.

Rest quantities are expressed in each body's *rest frame*: the core's centre-of-mass frame for a
combined body, the world frame at build time for free tissue.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

CONTINUUM_COLUMNS = 14
"""Columns of TissueModel.group_continuum (builder.continuum_groups writes them, the solver packs
them, compliant.continuum_groups reads them)."""


@dataclass(frozen=True, eq=False)
class TissueModel:
    # --- particles -------------------------------------------------------------------------------
    particle_rest_x: np.ndarray
    """(N, 3) rest position in the body's rest frame [m]."""
    particle_rest_q: np.ndarray
    """(N, 4) rest orientation [x, y, z, w] in the body's rest frame."""
    particle_radii: np.ndarray
    """(N, 3) ellipsoid semi-axes a, b, c along the particle's own axes [m]."""
    particle_mass: np.ndarray
    """(N,) mass [kg]."""
    particle_inv_mass: np.ndarray
    """(N,) 1 / mass [1/kg]."""
    particle_body: np.ndarray
    """(N,) int32 index of the tissue body the particle belongs to."""
    particle_partner: np.ndarray
    """(N,) int32 the attached <-> outer partner (thesis 5.2.1), -1 for none."""
    particle_attached: np.ndarray
    """(N,) bool: sits on the core surface and is tied to it (thesis 5.1.1)."""
    # --- implicit shape-matching groups (Mueller & Chentanez 2011 sec. 4; thesis 5.2.1) ----------
    group_offsets: np.ndarray
    """(N + 1,) int32 CSR offsets; group i is centred on particle i."""
    group_members: np.ndarray
    """(G,) int32 particle indices; the first member of each group is its centre."""
    group_rest_offset: np.ndarray
    """(G, 3) rest offset of each member from its group's rest centre of mass, x_bar_j - c_bar [m]."""
    # --- bodies ----------------------------------------------------------------------------------
    body_particle_offsets: np.ndarray
    """(B + 1,) int32 particle ranges of each tissue body."""
    body_core_shape: np.ndarray
    """(B,) int32 index of the body's core among the world's collision shapes, -1 for free tissue."""
    body_friction: np.ndarray
    """(B, 2) Coulomb friction coefficients (static, dynamic) of the tissue surface."""
    group_kappa: np.ndarray
    """(N,) stiffness per unit mass of each group's shape matching, kappa = G / (rho l^2) [1/s^2]
    (builder.group_kappa; compliant.py solves it)."""
    body_max_deviation: np.ndarray | None = None
    """(B,) the strain limit of each body [m]: the farthest a free particle may be from the spot its
    core carries it to (anchors.limit_deviation); None: all inf (none)."""
    body_contact_cone: np.ndarray | None = None
    """(B,) bool: besides its patch's bound on what the patch transmits, each contact's friction is
    bounded by its own cone, mu_s lambda_n (friction.friction_patches; TissueConfig.contact_cone);
    None: all False (the patch bound alone, the default law)."""
    body_contact_law: np.ndarray | None = None
    """(B,) bool: Coulomb's law per contact, every contact its own friction patch with its own
    stick/slide state (TissueConfig.friction_law "contact"; friction.load_anchors); None: all False
    (the patch law)."""
    group_continuum: np.ndarray | None = None
    """(N, CONTINUUM_COLUMNS) per group, the continuum group energy E = G V ||F - R||_F^2
    (TissueConfig.group_energy "continuum"; builder.continuum_groups, compliant.continuum_groups):
    [A_qq^+ (6: xx, xy, xz, yy, yz, zz) [1/(kg m^2)], 2 G V [N m], beta [1/s^2] (the hourglass
    term's stiffness per unit mass), A_qq (6) [kg m^2]], A_qq = sum_j m_j q_j q_j^T the group's rest second moment and V the volume it
    stands for; a row of zeros is a shape-matching group. None: all zeros (every group shape
    matching, the default material)."""

    def __post_init__(self) -> None:
        if self.body_max_deviation is None:
            object.__setattr__(self, "body_max_deviation", np.full(self.body_core_shape.shape[0], np.inf))
        if self.body_contact_cone is None:
            object.__setattr__(self, "body_contact_cone", np.zeros(self.body_core_shape.shape[0], dtype=np.bool_))
        if self.body_contact_law is None:
            object.__setattr__(self, "body_contact_law", np.zeros(self.body_core_shape.shape[0], dtype=np.bool_))
        if self.group_continuum is None:
            object.__setattr__(self, "group_continuum", np.zeros((self.group_offsets.shape[0] - 1, CONTINUUM_COLUMNS)))

    @property
    def continuum(self) -> bool:
        """Any group under the continuum group energy (group_continuum)."""
        return bool((self.group_continuum[:, 6] > 0.0).any())

    @property
    def particle_count(self) -> int:
        return int(self.particle_mass.shape[0])

    @property
    def body_count(self) -> int:
        return int(self.body_core_shape.shape[0])

    def body_slice(self, body: int) -> slice:
        return slice(int(self.body_particle_offsets[body]), int(self.body_particle_offsets[body + 1]))

    def particle_inertia_local(self) -> np.ndarray:
        """(N, 3) principal moments of each solid ellipsoid, I = m/5 (b^2 + c^2, ...) [kg m^2]."""
        r2 = self.particle_radii**2
        m5 = self.particle_mass[:, None] / 5.0
        return m5 * np.stack([r2[:, 1] + r2[:, 2], r2[:, 0] + r2[:, 2], r2[:, 0] + r2[:, 1]], axis=1)


def concatenate(models: list[TissueModel]) -> TissueModel:
    """One model holding all bodies of ``models`` in order (indices re-based)."""
    if not models:
        raise ValueError("concatenate needs at least one TissueModel")
    p_off = 0
    g_off = 0
    b_off = 0
    group_offsets = [np.zeros(1, dtype=np.int32)]
    members, bodies, partners, body_offsets = [], [], [], [np.zeros(1, dtype=np.int32)]
    for m in models:
        members.append(m.group_members + p_off)
        group_offsets.append(m.group_offsets[1:] + g_off)
        bodies.append(m.particle_body + b_off)
        partners.append(np.where(m.particle_partner >= 0, m.particle_partner + p_off, -1))
        body_offsets.append(m.body_particle_offsets[1:] + p_off)
        p_off += m.particle_count
        g_off += int(m.group_members.shape[0])
        b_off += m.body_count

    def cat(name: str) -> np.ndarray:
        return np.ascontiguousarray(np.concatenate([getattr(m, name) for m in models]))

    return TissueModel(
        particle_rest_x=cat("particle_rest_x"),
        particle_rest_q=cat("particle_rest_q"),
        particle_radii=cat("particle_radii"),
        particle_mass=cat("particle_mass"),
        particle_inv_mass=cat("particle_inv_mass"),
        particle_body=np.concatenate(bodies).astype(np.int32),
        particle_partner=np.concatenate(partners).astype(np.int32),
        particle_attached=cat("particle_attached"),
        group_offsets=np.concatenate(group_offsets).astype(np.int32),
        group_members=np.concatenate(members).astype(np.int32),
        group_rest_offset=cat("group_rest_offset"),
        body_particle_offsets=np.concatenate(body_offsets).astype(np.int32),
        body_core_shape=cat("body_core_shape"),
        body_friction=cat("body_friction"),
        group_kappa=cat("group_kappa"),
        body_max_deviation=cat("body_max_deviation"),
        body_contact_cone=cat("body_contact_cone"),
        body_contact_law=cat("body_contact_law"),
        group_continuum=cat("group_continuum"),
    )


def with_core_shapes(model: TissueModel, core_shapes: np.ndarray) -> TissueModel:
    """Copy of ``model`` whose bodies point at the given collision-shape indices."""
    core_shapes = np.asarray(core_shapes, dtype=np.int32)
    if core_shapes.shape != (model.body_count,):
        raise ValueError(f"core_shapes must have shape ({model.body_count},), got {core_shapes.shape}")
    from dataclasses import replace

    return replace(model, body_core_shape=core_shapes)
