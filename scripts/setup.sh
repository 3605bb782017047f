#!/usr/bin/env bash
# One-command setup: a venv in .venv with softgrasp_env (editable) and its test tools.
# torch is pinned to the CPU build first, so no CUDA build is downloaded.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x .venv/bin/python ] || python3 -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q "torch==2.13.0"
.venv/bin/python -m pip install -q -e ".[test]"
# numba compiles the solver's kernels on first use (about half a minute) and caches them on disk:
# do it now, so that the first demo, test or training run starts at once.
echo "compiling the solver's kernels (first time only, about half a minute)..."
.venv/bin/python -c "from softgrasp_env.scene import GraspScene; s = GraspScene(); s.world.step(); s.world.penetration(); s.close()"
echo "setup done: activate with 'source .venv/bin/activate'"
