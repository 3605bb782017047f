#!/usr/bin/env bash
# One-command setup: a venv in .venv with softgrasp_env (editable), every extra but Ray and docs, and the
# test tools. torch is pinned to the CPU build first, so no CUDA build is downloaded (the [train]
# extra's torch range admits 2.13.0, so pip keeps it).
#   ./scripts/setup.sh            the main venv (.venv): everything but Ray
#   ./scripts/setup.sh --rllib    also .venv-rllib: the same package with Ray RLlib (the [rllib] extra).
#                                 RLlib pins its own gymnasium (1.2.2 for Ray 2.60.0), older than the
#                                 main venv's, so it gets a venv of its own.
set -euo pipefail
cd "$(dirname "$0")/.."
rllib=0
for arg in "$@"; do
    case "$arg" in
        --rllib) rllib=1 ;;
        *) echo "usage: $0 [--rllib]" >&2; exit 2 ;;
    esac
done
make_venv() {  # make_venv DIR EXTRAS
    [ -x "$1/bin/python" ] || python3 -m venv "$1"
    "$1/bin/python" -m pip install -q --upgrade pip
    "$1/bin/python" -m pip install -q "torch==2.13.0"
    "$1/bin/python" -m pip install -q -e ".[$2]"
}
make_venv .venv "train,plots,video,offline,reference,multigrid,peers,test"
# numba compiles the solver's kernels on first use (about a minute) and caches them on disk:
# do it now, so that the first demo, test or training run starts at once.
.venv/bin/python -m softgrasp_env.compile
if [ "$rllib" = 1 ]; then
    make_venv .venv-rllib "train,test,rllib"
    .venv-rllib/bin/python -m softgrasp_env.compile
    echo "RLlib venv done: .venv-rllib/bin/python -m agents.rllib_train --help"
fi
echo "setup done: activate with 'source .venv/bin/activate'"
