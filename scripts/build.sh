#!/usr/bin/env bash
# Installs what is missing, configures and builds one CMake preset.
# Usage: scripts/build.sh [preset]   (release by default; see CMakePresets.json)
set -euo pipefail
cd "$(dirname "$0")/.."
preset="${1:-release}"
bash scripts/install-deps.sh
cmake --preset "$preset" >/dev/null
cmake --build --preset "$preset" -j "$(nproc)"
