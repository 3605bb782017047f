"""Finger kind 'rigid': the bare cores touch the cylinder through pybullet's own contacts - the
rigid-only twin the thesis compares the tissue against. It adds nothing to the interface's
defaults; the friction of the core links is the finger surface's static coefficient
(``SceneConfig.tissue.friction_static``), pybullet having one coefficient per body."""

from __future__ import annotations

from dataclasses import dataclass

from .base import FingerConfig, FingerKind


@dataclass(frozen=True, eq=False)
class RigidConfig(FingerConfig):
    """Rigid fingers have no settings of their own."""

    kind = "rigid"


class RigidFingers(FingerKind):
    name = "rigid"
    config_type = RigidConfig
    description = "the bare cores through pybullet's rigid contacts (the rigid-only twin)"


__all__ = ["RigidConfig", "RigidFingers"]
