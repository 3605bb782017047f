"""Policies that come with the package: the scripted grasp and the trained baselines.

    from softgrasp_env.policies import ScriptedGraspPolicy, list_baselines, load_baseline

``ScriptedGraspPolicy`` needs nothing beyond the core install. ``list_baselines`` and
``baseline_card`` read the shipped model cards; ``load_baseline`` loads a model with its
observation statistics and needs stable-baselines3 and torch (``pip install 'softgrasp-env[train]'``),
imported only then.
"""

from .baselines import TRAINED, Baseline, baseline_card, baseline_path, list_baselines, load_baseline
from .scripted import ScriptedGraspPolicy

__all__ = ["TRAINED", "Baseline", "ScriptedGraspPolicy", "baseline_card", "baseline_path", "list_baselines",
           "load_baseline"]  # fmt: skip
