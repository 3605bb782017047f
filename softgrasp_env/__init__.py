"""softgrasp_env: rigid pybullet cores wrapped in oriented-particle soft tissue (Mueller &
Chentanez 2011), after the thesis "Combining rigid body simulations with oriented particles".

Importing the package registers the Gymnasium environments listed in ``ENV_IDS``::

    import gymnasium as gym
    import softgrasp_env

    env = gym.make("SoftGrasp-v5")
"""

from ._jit_cache import invalidate_stale_kernels

invalidate_stale_kernels()

from .registration import ENV_IDS, register_envs  # noqa: E402

register_envs()

__version__ = "0.9.0.dev0"
__all__ = ["ENV_IDS", "register_envs", "__version__"]
