"""Loading a policy trained by ``agents.rllib_train`` for evaluation, without a Ray cluster: the
RLModule's weights from the checkpoint and the observation filter's running mean and std frozen,
so ``agents.evaluate`` runs an RLlib policy exactly as it runs an SB3 one (same env, same seeds).

A run is a Tune trial directory with the ``run.json`` agents.rllib_train wrote (it names the final
checkpoint), or any of its ``checkpoint_<N>/`` directories.
"""

from __future__ import annotations

import pickle
from pathlib import Path
from typing import Any

import numpy as np

from agents.runs import read_meta

MARKER = "rllib_checkpoint.json"
"""The file RLlib writes at the top of every Algorithm checkpoint."""


def is_rllib_run(path: str | Path) -> bool:
    """True if ``path`` is an RLlib trial directory (run.json with ``"backend": "rllib"``) or one
    of its checkpoints."""
    path = Path(path)
    if (path / MARKER).exists():
        return True
    run_json = path / "run.json"
    if not run_json.exists():
        return False
    try:
        return read_meta(run_json).get("backend") == "rllib"
    except ValueError:
        return False


def locate(path: str | Path) -> tuple[dict[str, Any], Path]:
    """``(run.json's contents, checkpoint directory)`` for a trial directory or a checkpoint in one;
    ValueErrors name what is missing."""
    path = Path(path).resolve()
    if (path / MARKER).exists():
        checkpoint, run_json = path, path.parent / "run.json"
        if not run_json.exists():
            raise ValueError(f"{str(path)!r} is an RLlib checkpoint, but its trial directory has no run.json "
                             "(written by agents.rllib_train): the env it trained on is unknown")  # fmt: skip
        meta = read_meta(run_json)
    else:
        meta = read_meta(path / "run.json")
        if meta.get("backend") != "rllib":
            raise ValueError(f"{str(path / 'run.json')!r} is not an RLlib run (no \"backend\": \"rllib\")")
        checkpoint = path / str(meta.get("checkpoint", ""))
        if not (checkpoint / MARKER).exists():
            raise ValueError(f"{str(path / 'run.json')!r} names checkpoint {meta.get('checkpoint')!r}, "
                             f"which is not an RLlib checkpoint in {str(path)!r}")  # fmt: skip
    return meta, checkpoint


class RLlibPolicy:
    """``policy(obs) -> action`` and SB3's ``predict`` for an RLlib checkpoint: observations through
    the frozen mean/std filter, the module's deterministic action (the Gaussian's mean), clipped to
    the action space as SB3 clips its own."""

    def __init__(self, checkpoint: str | Path, action_low: np.ndarray, action_high: np.ndarray) -> None:
        try:
            import torch
            import tree
            from ray.rllib.core.rl_module.rl_module import RLModule
            from ray.rllib.utils.filter import MeanStdFilter, RunningStat
        except ImportError as exc:  # the main venv has no Ray: RLlib pins its own gymnasium
            raise ValueError(f"loading an RLlib checkpoint needs Ray RLlib ({exc}); install the extra in its own "
                             "venv: scripts/setup.sh --rllib, then .venv-rllib/bin/python -m agents.evaluate ...") from None  # fmt: skip
        checkpoint = Path(checkpoint).resolve()
        module_dir = checkpoint / "learner_group" / "learner" / "rl_module" / "default_policy"
        if not module_dir.exists():
            raise ValueError(f"{str(checkpoint)!r} has no RLModule at {str(module_dir)!r}")
        self._torch = torch
        self.module = RLModule.from_checkpoint(str(module_dir))  # RLlib wants an absolute path
        self.module.eval()
        self._dist = self.module.get_inference_action_dist_cls()
        filter_state = checkpoint / "env_runner" / "env_to_module_connector" / "MeanStdFilter" / "state.pkl"
        self._filter = None
        if filter_state.exists():
            state = pickle.loads(filter_state.read_bytes())[None]
            f = MeanStdFilter(state["shape"], demean=state["de_mean_to_zero"], destd=state["de_std_to_one"],
                              clip=state["clip_by_value"])  # fmt: skip
            f.running_stats = tree.unflatten_as(f.shape, [RunningStat.from_state(s) for s in state["running_stats"]])
            self._filter = f
        self._low = np.asarray(action_low, dtype=np.float32)
        self._high = np.asarray(action_high, dtype=np.float32)

    def __call__(self, obs) -> np.ndarray:
        return self.predict(obs)[0]

    def predict(self, observation, state=None, episode_start=None, deterministic: bool = True):
        """SB3's interface: ``(action, state)`` for one observation or a batch (leading axis)."""
        obs = np.asarray(observation, dtype=np.float32)
        single = obs.ndim == 1
        batch = obs[None] if single else obs
        if self._filter is not None:
            batch = np.stack([self._filter(o, update=False) for o in batch]).astype(np.float32)
        torch = self._torch
        with torch.no_grad():
            out = self.module.forward_inference({"obs": torch.as_tensor(batch)})
            dist = self._dist.from_logits(out["action_dist_inputs"])
            action = (dist.to_deterministic() if deterministic else dist).sample().numpy()
        action = np.clip(action, self._low, self._high).astype(np.float32)
        return (action[0] if single else action), state


def load_rllib_policy(path: str | Path, env, *, other_env: bool = False) -> RLlibPolicy:
    """The policy of the RLlib run at ``path`` for ``env``: the run's env id (another only with
    ``other_env``) and always its spaces (:func:`agents.runs.check_env_matches`)."""
    from agents.runs import check_env_matches

    meta, checkpoint = locate(path)
    run_json = Path(path) / "run.json"
    if not run_json.exists():  # a checkpoint: its trial directory holds the run.json
        run_json = checkpoint.parent / "run.json"
    check_env_matches(meta, env, run_json, other_id=other_env)
    return RLlibPolicy(checkpoint, env.action_space.low, env.action_space.high)
