"""Finger kind 'tissue' (the thesis): each finger core is a combined body, wrapped in
oriented-particle tissue (Mueller & Chentanez 2011) that the world steps together with pybullet
and couples both ways (thesis 5.1.3, 5.2.2; softgrasp_env/sim/world.py).

The tissue's material and discretisation are ``SceneConfig.tissue`` (a TissueConfig: particle
density, pad depth, stiffness, friction); this kind's own setting is which faces of a core get
tissue. Its combination rules (``check``) refuse settings that tear the tissue.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..config import TissueConfig
from ..sim.world import TissueSpec, World
from ..tissue.builder import CoreShape, build_combined_body, core_shape_from_bullet, surface_particles
from ..tissue.compliant import world_substeps as compliant_world_substeps
from ..validation import check_choice
from .base import FingerConfig, FingerKind, FingerSite, Visual
from .tactile import TaxelGrid, face_footprints, tissue_loads, tissue_shear

TISSUE_FACES: tuple[str, ...] = ("all", "contact")
"""Which faces of a core get tissue (TissueFingerConfig.faces)."""
CONTACT_FACES = {0: ("+x", "-z"), 1: ("-x", "-z")}
"""faces='contact', per core link, in the core's frame: the inner face (toward the other finger:
+x for the left core, -x for the right one) and the tip (-z). The back and top never meet the
cylinder; the sides only when it is offset past the face's end, and then the bare core's pybullet
contact takes it."""

MAX_CONSISTENT_SQUEEZE_IMPULSE = 0.125
"""Largest finger_force * dt the consistent coupling accepts [N s]: a core sliding on its joint
under the motor's force is projected against the tissue every step, and a large impulse per step
drives it through the pad. 0.125 keeps below every impulse that was seen to diverge (the
package's documentation, Finger kinds, gives the probe)."""
MAX_PARTICLE_RADIUS = 0.0125
"""Widest tangential particle radius (radius_scale * spacing) accepted on the fingers [m]. Wider
particles overhang the cores' edges (a face is 4 cm wide) and catch on the cylinder's rim; the
``fast`` preset's 1.2 cm (2,500 per m^2) and the default's 0.95 cm run."""
MAX_PARTICLE_SPEED = 20.0
"""A particle faster than this [m/s] has diverged (as a rigid body faster than 20 m/s)."""
MAX_DEVIATION = 0.03
"""A particle farther than this from the spot its core carries it to [m] is torn off."""

TISSUE_RGBA = (0.95, 0.55, 0.6, 1.0)
ATTACHED_RGBA = (0.75, 0.35, 0.45, 1.0)


@dataclass(frozen=True, eq=False)
class TissueFingerConfig(FingerConfig):
    """Settings of the tissue fingers beyond the tissue's material (SceneConfig.tissue)."""

    kind = "tissue"
    faces: str = "contact"
    """Which faces of a finger core get tissue: 'contact' (default) - only the inner face and the
    tip, where the fingers can touch the cylinder (the rest of the core meets the world through
    pybullet's contacts); or 'all' - every face (2.5x the particles, the same grasp: penetration
    0.098 mm vs 0.095, at 0.6x the steps/s). Model no more than the scene needs."""

    def __post_init__(self) -> None:
        check_choice("faces", self.faces, TISSUE_FACES, owner="TissueFingerConfig")


class TissueFingers(FingerKind):
    name = "tissue"
    config_type = TissueFingerConfig
    has_tissue = True
    description = "rigid cores wrapped in oriented-particle tissue (ours, the thesis)"

    @classmethod
    def pad_thickness(cls, config: FingerConfig, tissue: TissueConfig) -> float:
        """The tissue out to its outer particles' ellipsoids: extrude plus their normal radius."""
        return tissue.extrude + tissue.normal_radius

    @classmethod
    def check(cls, scene_config) -> None:
        cfg, sim, tissue = scene_config, scene_config.sim, scene_config.tissue
        # The consistent coupling's squeeze per step (MAX_CONSISTENT_SQUEEZE_IMPULSE).
        impulse = cfg.finger_force * sim.dt
        if sim.coupling == "consistent" and impulse > MAX_CONSISTENT_SQUEEZE_IMPULSE:
            raise ValueError(
                f"SceneConfig: coupling='consistent' with finger_force={cfg.finger_force:g} N at dt="
                f"{sim.dt:g} s pushes {impulse:.3g} N s per step into the tissue, more than "
                f"{MAX_CONSISTENT_SQUEEZE_IMPULSE:g} N s; at this dt finger_force must be at most "
                f"{MAX_CONSISTENT_SQUEEZE_IMPULSE / sim.dt:.3g} N (or use coupling='thesis')")  # fmt: skip
        # Coarse pads of wide particles overhang the core's edges and catch on the cylinder.
        reach = tissue.radius_scale * tissue.spacing
        if reach > MAX_PARTICLE_RADIUS:
            raise ValueError(
                f"SceneConfig: the tissue particles are too wide: radius_scale={tissue.radius_scale:g} "
                f"times the spacing {tissue.spacing:.4f} m (particle_density={tissue.particle_density:g} per m^2) "
                f"gives {reach:.4f} m, more than {MAX_PARTICLE_RADIUS:g} m; raise the particle density to at least "
                f"{(tissue.radius_scale / MAX_PARTICLE_RADIUS) ** 2:.0f} per m^2 or lower radius_scale")  # fmt: skip

    @property
    def world_substeps(self) -> int:
        """World steps per physics step for the tissue's material: the fewest that keep its groups
        within compliant.MAX_STEP_STIFFNESS and the pad's stiffness
        against its core within compliant.MAX_COUPLING_FOLD."""
        return world_substeps(self.scene_config)

    def mount(self, site: FingerSite) -> list[TissueSpec]:
        super().mount(site)
        specs = []
        for k, link in enumerate(site.core_links):
            core, offset, orn = core_shape_from_bullet(site.client, site.gripper, link)
            if abs(orn[3]) < 1.0 - 1e-12:
                raise ValueError("finger collision shape must be aligned with its link frame")
            faces = CONTACT_FACES[k] if self.config.faces == "contact" else None
            body = build_combined_body(core, self.scene_config.tissue, shape_offset=offset, faces=faces)
            specs.append(TissueSpec(body, site.core_shapes[k]))
        return specs

    _footprint: np.ndarray | None = None
    """Each particle's face cell (fingers.tactile.face_footprints), made at the first tactile read."""
    _surface: np.ndarray | None = None
    """The pads' surface particles (tissue.builder.surface_particles), with _footprint."""

    def contact_force(self) -> np.ndarray:
        """pybullet's core contacts plus the tissue's contacts with the cylinder."""
        f = super().contact_force()
        return f + self.world.solver.contact_normal_force(self.site.cylinder_shape)

    def tactile(self, grid: TaxelGrid) -> np.ndarray:
        """The bare cores' pybullet contacts (a core touches only through a crushed pad), the
        tissue's contacts of the last world step, and its shear under each taxel
        (fingers/tactile.py)."""
        out = super().tactile(grid)
        w: World = self.world
        m, sv, col = w.model, w.solver, w.colliders
        if self._footprint is None:
            self._surface = surface_particles(m)
            self._footprint = face_footprints(m.particle_rest_x, self._surface, m.body_particle_offsets,
                                              grid.half_width, grid.half_height)  # fmt: skip
        params = grid.params()
        core_rigid = col.shape_rigid[m.body_core_shape]
        lc = sv.last_contacts()
        tissue_loads(lc.count, lc.particle, lc.inner, lc.normal_lambda, lc.normal, lc.friction, lc.patch, lc.patch_slide,
                     lc.patch_change, m.particle_body, m.particle_rest_x, self._footprint, col.rigid_q, core_rigid,
                     sv.sim.dt, params, out, lc.single)  # fmt: skip
        tissue_shear(w.state.particle_x, m.particle_rest_x, self._footprint, self._surface,
                     m.body_particle_offsets, col.rigid_x, col.rigid_q, core_rigid, params, out)  # fmt: skip
        return out

    def penetration(self) -> tuple[float, float]:
        """The tissue's deepest overlap with any rigid shape (and of its outer particles with their
        own core), and pybullet's contacts of the bare cores."""
        pen, intrusion = self.world.penetration()
        core_pen, _ = super().penetration()
        return max(pen, core_pen), intrusion

    def divergence(self) -> str | None:
        w: World = self.world
        pv = float(np.abs(w.state.particle_v).max())
        if pv > MAX_PARTICLE_SPEED:
            return f"a tissue particle at {pv:.1f} m/s (limit {MAX_PARTICLE_SPEED:g} m/s)"
        dev = float(w.tissue_deviation())
        if dev > MAX_DEVIATION:
            return (f"tissue torn: a particle {dev * 100:.1f} cm from where its core holds it "
                    f"(limit {MAX_DEVIATION * 100:g} cm)")  # fmt: skip
        return None

    def visuals(self) -> list[Visual]:
        """The cores, and every particle as its ellipsoid (attached ones darker)."""
        model, state = self.world.model, self.world.state
        rgba = np.where(model.particle_attached[:, None], np.asarray(ATTACHED_RGBA), np.asarray(TISSUE_RGBA))
        return super().visuals() + [Visual("points", rgba, radii=model.particle_radii,
                                           positions=lambda: state.particle_x, orientations=lambda: state.particle_q,
                                           in_scene=False)]  # fmt: skip


def world_substeps(scene_config) -> int:
    """World steps per physics step of ``scene_config`` with tissue fingers (TissueFingers.world_substeps):
    compliant.world_substeps on the pads mount() builds, on cores of ``finger_mass``, for its
    material solve (SimConfig.material_solve)."""
    return _world_substeps(scene_config.tissue, tuple(scene_config.finger_half_extents), scene_config.fingers.faces,
                           scene_config.finger_mass, scene_config.sim.dt, scene_config.sim.material_solve)  # fmt: skip


@functools.lru_cache(maxsize=64)
def _world_substeps(tissue: TissueConfig, half_extents: tuple[float, float, float], faces: str, core_mass: float,
                    dt: float, material_solve: str = "groups") -> int:  # fmt: skip
    """The pads built as mount() builds them (the same builder, the same core boxes), once per
    setting, before the scene: it must know its pybullet time step before the first motor command."""
    core = CoreShape("box", half_extents=half_extents)
    n = 1
    for k in (0, 1):
        model = build_combined_body(core, tissue, faces=CONTACT_FACES[k] if faces == "contact" else None)
        n = max(n, compliant_world_substeps(model, np.array([core_mass]), dt, material_solve))
    return n


__all__ = [
    "MAX_CONSISTENT_SQUEEZE_IMPULSE",
    "MAX_PARTICLE_RADIUS",
    "TISSUE_FACES",
    "TissueFingerConfig",
    "TissueFingers",
    "world_substeps",
]  # fmt: skip
