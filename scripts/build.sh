#!/usr/bin/env bash
# Installs what is missing, configures and builds one CMake preset.
# Usage: scripts/build.sh [preset]   (release by default; see CMakePresets.json)
set -euo pipefail
cd "$(dirname "$0")/.."
preset="${1:-release}"
bash scripts/install-deps.sh
# The Python API (python/) builds where its environment is: the presets that
# build it find nanobind through .venv's Python.
# Without PyPI (offline) the rest still builds: a warning, no module; under
# CI (CI set) or with CELLRAY_REQUIRE_PYTHON=1 that is an error instead.
py=()
if [ "$preset" != asan ] && [ "$preset" != fuzz ]; then
  if bash scripts/python-env.sh; then
    py=(-DPython_EXECUTABLE="$PWD/.venv/bin/python")
  elif [ -n "${CI:-}" ] || [ "${CELLRAY_REQUIRE_PYTHON:-0}" = 1 ]; then
    echo "cellray: scripts/python-env.sh failed: the Python module and its tests cannot be built" >&2
    exit 1
  else
    echo "cellray: warning: no Python environment (scripts/python-env.sh failed; PyPI unreachable?): building without the Python module" >&2
  fi
fi
cmake --preset "$preset" "${py[@]}" >/dev/null
cmake --build --preset "$preset" -j "$(nproc)"
