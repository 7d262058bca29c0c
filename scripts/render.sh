#!/usr/bin/env bash
# Quick start, first command: set up, build, and render the default scene
# (the sphereflake, scenes/spd/balls.nff) to balls.png.
# Extra arguments go to `cellray render`, e.g. scripts/render.sh scenes/spd/tree.nff -o tree.png
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh release >/dev/null
if [ $# -eq 0 ]; then set -- scenes/spd/balls.nff -o balls.png; fi
build/release/bin/cellray render "$@"
