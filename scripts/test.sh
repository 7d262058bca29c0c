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
stage_done() { echo "cellray: test stage $1 passed in $((SECONDS - $2)) s"; }
if [[ $stages == *" ci "* ]]; then
  t0=$SECONDS
  bash scripts/build.sh ci
  ctest --preset ci -j "$(nproc)" "$@"
  stage_done ci "$t0"
fi
if [[ $stages == *" asan "* ]]; then
  t0=$SECONDS
  bash scripts/sanitize.sh
  stage_done asan "$t0"
fi
if [[ $stages == *" fuzz "* ]]; then
  t0=$SECONDS
  bash scripts/fuzz.sh smoke
  stage_done fuzz "$t0"
fi
