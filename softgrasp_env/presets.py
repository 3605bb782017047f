"""Named settings of the soft fingers, chosen at the knee of the speed/accuracy chart
(the package's documentation, Results: the methods side by side): model no more than the scene
needs.
Every preset covers only the faces where the fingers can touch the cylinder (each core's inner
face and tip, ``TissueFingerConfig(faces='contact')``); the backs and sides meet the world through
pybullet's contacts.

- ``fast``: 2,500 particles per m^2 of face (32 particles in all, 20 mm spacing), 2 iterations at
  1/240 s: about 1.3x the default's steps/s, its hold bound a few per cent further under
  Coulomb's than the default's.
- ``default``: the defaults of SceneConfig / SimConfig / TissueConfig: 4,000 per m^2 (60
  particles), 3 iterations at 1/240 s; meets every accuracy target of the defaults' tests.
- ``accurate``: the default tissue at half the time step (dt 1/480 s) with 2 iterations: smaller
  steps converge faster than more iterations, at half the simulated seconds per wall second.
- ``fine`` and ``converged``: the v4 tissue (the continuum group energy with hourglass control,
  Coulomb per contact, layers about as thick as the particle spacing: TISSUE_V4) at 16,000 and at
  64,000 particles per m^2 (one and two element layers). ``converged`` is the cheapest resolution
  whose rows of the spatial convergence table are within 5 % of their reference (the contact
  strip's width: +6.5 %, quantised by the particle columns), or within 10 % where no resolution
  measured is within 5 % (the lowest friction against Coulomb's, the tangential compliance at a
  single load); ``fine`` meets the same but for the
  contact strip's width (+13 %), at about ten times ``converged``'s speed (the package's
  documentation, Results: convergence in space).

``scene_config(name)`` gives the SceneConfig; the env takes ``preset=name``. The soft v4 ids
register the v4 tissue's keywords, which override a preset's material: there every preset is that
tissue at the preset's resolution. ``fine`` and ``converged`` carry the v4 material with them, so
on a v3 id they give the v4 tissue too.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from .config import TissueConfig
from .scene.config import SceneConfig

TISSUE_V4: dict[str, Any] = dict(group_energy="continuum", hourglass_stiffness=1.0, friction_law="contact",
                                 layers="auto")  # fmt: skip
"""The v4 tissue, as TissueConfig fields (and the soft ids' ``gym.make`` keywords,
registration.TISSUE_V4): the continuum group energy (a shear modulus that means the same pad at
every particle density) with hourglass control, Coulomb's law in every contact's own cone, and an
element layer through the pad about as thick as the particle spacing (TissueConfig.auto_layers)."""

PRESETS: dict[str, dict[str, Any]] = {
    "fast": dict(tissue=dict(particle_density=2_500.0), sim=dict(iterations=2)),
    "default": dict(),
    "accurate": dict(sim=dict(dt=1.0 / 480.0, iterations=2)),
    "fine": dict(tissue=dict(TISSUE_V4, particle_density=16_000.0)),
    "converged": dict(tissue=dict(TISSUE_V4, particle_density=64_000.0)),
}
"""Each preset as overrides of the defaults: SceneConfig fields, with ``tissue`` and ``sim`` as
overrides of TissueConfig and SimConfig fields."""


def v4_tissue(**fields: Any) -> TissueConfig:
    """The v4 soft ids' tissue (TISSUE_V4) with ``fields`` (TissueConfig fields) over it; its
    ``layers="auto"``, unless ``layers`` is given, resolved for the density it ends up with
    (TissueConfig.auto_layers)."""
    spec = {**TISSUE_V4, **fields}
    layers = spec.pop("layers")
    tissue = TissueConfig(**spec)
    return replace(tissue, layers=tissue.auto_layers if layers == "auto" else layers)


def scene_config(name: str, *, base: SceneConfig | None = None) -> SceneConfig:
    """The SceneConfig of preset ``name`` applied on ``base`` (the defaults if None)."""
    if name not in PRESETS:
        raise ValueError(f"preset must be one of {tuple(PRESETS)}, got {name!r}")
    base = base if base is not None else SceneConfig()
    spec = dict(PRESETS[name])
    tissue = dict(spec.pop("tissue", {}))
    layers = tissue.pop("layers", None)
    tissue = replace(base.tissue, **tissue)
    if layers is not None:
        tissue = replace(tissue, layers=tissue.auto_layers if layers == "auto" else layers)
    sim = replace(base.sim, **spec.pop("sim", {}))
    return replace(base, tissue=tissue, sim=sim, **spec)
