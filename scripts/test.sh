#!/usr/bin/env bash
# Quick start, second command: set up, build with warnings as errors, and run
# every test (unit, conformance against the fp64 reference, bad input, OpenCL
# on whatever device is present); then the unit, conformance and bad-input
# tests again under ASan + UBSan (scripts/sanitize.sh), and a smoke run of the
# input readers' fuzz targets (scripts/fuzz.sh smoke).
# Arguments go to the first ctest run. CELLRAY_TEST_STAGES picks the stages
# (default "ci asan fuzz"; e.g. CELLRAY_TEST_STAGES=ci for the first only).
set -euo pipefail
cd "$(dirname "$0")/.."
stages=" ${CELLRAY_TEST_STAGES:-ci asan fuzz} "
if [[ $stages == *" ci "* ]]; then
  bash scripts/build.sh ci
  ctest --preset ci -j "$(nproc)" "$@"
fi
if [[ $stages == *" asan "* ]]; then
  bash scripts/sanitize.sh
fi
if [[ $stages == *" fuzz "* ]]; then
  bash scripts/fuzz.sh smoke
fi
