#!/usr/bin/env bash
# Quick start, second command: set up, build with warnings as errors, and run
# every test (unit, conformance against the fp64 reference, bad input, OpenCL
# on whatever device is present).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh ci
ctest --preset ci -j "$(nproc)" "$@"
