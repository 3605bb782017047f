"""Finger kinds behind one interface (base.py) and the registry the scene, the env, the renderer,
the benchmarks and the tests iterate: ``FINGERS[name]`` is the kind, ``FINGERS[name].config_type``
its settings. Adding a kind is one module and one entry here."""

from __future__ import annotations

from .base import FingerConfig, FingerKind, FingerSite, Visual
from .fem import FemConfig, FemFingers
from .rigid import PATCH_SPINNING_FRICTION, RigidConfig, RigidFingers, TorsionalRigidConfig, TorsionalRigidFingers
from .segmented import SegmentedConfig, SegmentedFingers
from .tissue import TissueFingerConfig, TissueFingers

FINGERS: dict[str, type[FingerKind]] = {
    kind.name: kind for kind in (TissueFingers, RigidFingers, SegmentedFingers, FemFingers, TorsionalRigidFingers)
}
"""Every finger kind by name: 'tissue' (ours, the thesis), 'rigid' (the rigid-only twin),
'segmented' (the thesis' traditional fix), 'fem' (pybullet's FEM pads), 'rigid_torsion' (the rigid twin with
torsional friction of the tissue's own contact patch)."""


def finger_config(fingers: str | FingerConfig, *, owner: str | None = None) -> FingerConfig:
    """The kind's settings: a name gives its defaults, a config is checked to be a registered kind's.
    ``owner`` prefixes the name in the error (``SceneConfig.fingers``; bare: the gym.make argument)."""
    label = f"{owner}.fingers" if owner else "fingers"
    if isinstance(fingers, FingerConfig):
        kind = FINGERS.get(fingers.kind)
        if kind is None or type(fingers) is not kind.config_type:
            raise ValueError(f"{label}={fingers!r} is not the config of a registered finger kind {tuple(FINGERS)}")
        return fingers
    if not isinstance(fingers, str) or fingers not in FINGERS:
        raise ValueError(f"{label} must be one of {tuple(FINGERS)} or a finger kind's config, got {fingers!r}")
    return FINGERS[fingers].config_type()


__all__ = ["FINGERS", "PATCH_SPINNING_FRICTION", "FemConfig", "FingerConfig", "FingerKind", "FingerSite", "RigidConfig",
           "SegmentedConfig", "TissueFingerConfig", "TorsionalRigidConfig", "Visual", "finger_config"]  # fmt: skip
