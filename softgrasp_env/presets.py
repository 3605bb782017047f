"""Named settings of the soft fingers, chosen from the speed/accuracy chart (benchmarks/methods.py;
docs/RESULTS.md has the figures): model no more than the scene needs.

- ``fast``: tissue only where the fingers can touch the cylinder (each core's inner face and tip),
  coarse (4,000 particles per m^2 of face: 60 particles in all), 4 iterations. It meets every
  accuracy target of the defaults' tests except that its pads are coarse.
- ``default``: the defaults of SceneConfig / SimConfig / TissueConfig: the whole core covered
  (352 particles), 10,000 per m^2, 3 iterations at 1/240 s.
- ``accurate``: the default tissue at half the time step (dt 1/480 s) with 2 iterations: smaller
  steps converge faster than more iterations (penetration 0.06 mm, half the in-hand sag).

``scene_config(name, **overrides)`` gives the SceneConfig; the env takes ``preset=name``.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from .config import SceneConfig, SimConfig, TissueConfig

PRESETS: dict[str, dict[str, Any]] = {
    "fast": dict(tissue_faces="contact", tissue=dict(density=4_000.0), sim=dict(iterations=4)),
    "default": dict(),
    "accurate": dict(sim=dict(dt=1.0 / 480.0, iterations=2)),
}
"""Each preset as overrides of the defaults: SceneConfig fields, with ``tissue`` and ``sim`` as
overrides of TissueConfig and SimConfig fields."""


def scene_config(name: str, *, base: SceneConfig | None = None) -> SceneConfig:
    """The SceneConfig of preset ``name`` applied on ``base`` (the defaults if None)."""
    if name not in PRESETS:
        raise ValueError(f"preset must be one of {tuple(PRESETS)}, got {name!r}")
    base = base if base is not None else SceneConfig()
    spec = dict(PRESETS[name])
    tissue = replace(base.tissue, **spec.pop("tissue", {}))
    sim = replace(base.sim, **spec.pop("sim", {}))
    return replace(base, tissue=tissue, sim=sim, **spec)


def tissue_and_sim(name: str) -> tuple[TissueConfig, SimConfig, dict[str, Any]]:
    """(TissueConfig, SimConfig, other SceneConfig fields) of preset ``name`` on the defaults."""
    cfg = scene_config(name)
    rest = {k: v for k, v in PRESETS[name].items() if k not in ("tissue", "sim")}
    return cfg.tissue, cfg.sim, rest
