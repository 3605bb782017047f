"""softgrasp_env: rigid pybullet cores wrapped in oriented-particle soft tissue (Mueller &
Chentanez 2011), after the thesis "Combining rigid body simulations with oriented particles"."""

from ._jit_cache import invalidate_stale_kernels

invalidate_stale_kernels()

__version__ = "0.1.0"
