#!/usr/bin/env bash
# Create ./.venv and install JuggleRL (editable) with its test tools. Safe to re-run.
# EXTRAS=test,ray adds the optional Ray extra (cluster=ray and its tests; CI installs it).
# Prints a line per step; pip's own output (pages of setuptools warnings) only when a step fails.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-python3.11}
command -v "$PYTHON" >/dev/null 2>&1 || PYTHON=python3
LOG=$(mktemp -t jugglerl-setup.XXXXXX.log)
trap 'rm -f "$LOG"' EXIT

step() {  # step DESCRIPTION COMMAND...: run quietly, show the log if it fails
    echo "setup: $1"
    if ! "${@:2}" >"$LOG" 2>&1; then
        cat "$LOG" >&2
        echo "setup: failed: $1" >&2
        exit 1
    fi
}

[ -x .venv/bin/python ] || step "creating .venv with $PYTHON" "$PYTHON" -m venv .venv
step "upgrading pip" .venv/bin/python -m pip install --quiet --upgrade pip
# torch first, pinned: on this project's machines 2.13.0 is a local CPU build, while a looser
# request lets pip resolve the newest release with several GB of CUDA wheels.
step "installing torch 2.13.0" .venv/bin/python -m pip install --quiet "torch==2.13.0"
EXTRAS=${EXTRAS:-test}
step "installing jugglerl (editable) with [$EXTRAS]" \
    .venv/bin/python -m pip install --quiet -e ".[$EXTRAS]"
echo "setup: done: .venv/bin/python ($(.venv/bin/python --version 2>&1))"
.venv/bin/python -c 'import ctypes.util, sys; sys.exit(ctypes.util.find_library("EGL") is None)' ||
    echo "setup: note: no libEGL here; evaluate.py video=true needs it (apt-get install libegl1 libgl1-mesa-dri)"
