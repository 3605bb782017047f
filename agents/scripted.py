"""The scripted grasp policy, under its old name: it lives in the installed package now
(``softgrasp_env.policies.scripted``), so that a pip install has it; this module keeps
``from agents.scripted import ScriptedGraspPolicy`` working in the repository."""

from softgrasp_env.policies.scripted import ScriptedGraspPolicy

__all__ = ["ScriptedGraspPolicy"]
