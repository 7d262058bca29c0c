#!/usr/bin/env bash
# Installs what is missing, configures and builds one CMake preset.
# Usage: scripts/build.sh [preset]   (release by default; see CMakePresets.json)
set -euo pipefail
cd "$(dirname "$0")/.."
preset="${1:-release}"
bash scripts/install-deps.sh
# The Python API (python/) builds where its environment is: the presets that
# build it find nanobind through .venv's Python.
py=()
if [ "$preset" != asan ] && [ "$preset" != fuzz ]; then
  bash scripts/python-env.sh
  py=(-DPython_EXECUTABLE="$PWD/.venv/bin/python")
fi
cmake --preset "$preset" "${py[@]}" >/dev/null
cmake --build --preset "$preset" -j "$(nproc)"
