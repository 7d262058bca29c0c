#!/usr/bin/env bash
# Builds the preset "asan" (GCC, AddressSanitizer + UndefinedBehaviorSanitizer,
# LeakSanitizer at exit) and runs the unit, conformance and bad-input tests
# under it (test preset "asan": small scenes, no benchmark or numerical
# hard-case suite; see DEVELOPERS.md). The run fails on any report of any
# process, the `cellray` runs of the bad-input tests included:
# - ASan and LSan write each process's report to its own file in
#   build/asan/sanitizer-reports/ (log_path), which must stay empty, so a
#   report is seen even where the test that caused it passed;
# - UBSan (GCC's libubsan ignores log_path) aborts the process with exit code
#   86 and its report on stderr: the test fails, since every test that runs
#   `cellray` asserts its exact exit code (0, 1 or 2).
# Usage: scripts/sanitize.sh [ctest arguments]
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh asan
reports=build/asan/sanitizer-reports
rm -rf "$reports"
mkdir -p "$reports"
# log_path sends each process's report to its own file (asan.PID) instead of
# the stderr that a bad-input test captures; the test preset appends the rest
# of the options (CMakePresets.json).
export ASAN_OPTIONS="log_path=$PWD/$reports/asan${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
status=0
ctest --preset asan -j "$(nproc)" "$@" || status=$?
# LeakSanitizer's at-exit tracer (GCC 12) now and then dies itself on a
# 2-core machine under load ("Tracer caught signal 11 ... LeakSanitizer has
# encountered a fatal error"): the tool failed, it found nothing, and the
# process's exit code fails its test. Where every report is such a failure
# and the failed tests (at least one) are no more than such reports, they run
# once more, alone, with an empty report folder; that run's results decide.
# Any other report (a leak, an invalid access) is never retried.
tool_failure() {
  grep -q 'LeakSanitizer has encountered a fatal error' "$1" &&
    ! grep -qE 'ERROR: (AddressSanitizer|LeakSanitizer: detected)' "$1"
}
n=$(find "$reports" -type f | wc -l)
if [ "$n" -ne 0 ]; then
  crashes=0
  for f in "$reports"/*; do tool_failure "$f" && crashes=$((crashes + 1)); done
  failed_log=build/asan/Testing/Temporary/LastTestsFailed.log
  failed=0
  [ "$status" -ne 0 ] && [ -f "$failed_log" ] && failed=$(wc -l < "$failed_log")
  if [ "$crashes" -eq "$n" ] && [ "$failed" -ge 1 ] && [ "$failed" -le "$crashes" ]; then
    echo "cellray: sanitizers: LeakSanitizer's tracer failed in $n process(es)" \
      "(no finding); rerunning the $failed failed test(s) once:" >&2
    head -n 3 "$reports"/* >&2
    rm -rf "$reports"
    mkdir -p "$reports"
    status=0
    ctest --preset asan -j 1 --rerun-failed "$@" || status=$?
    n=$(find "$reports" -type f | wc -l)
  fi
fi
if [ "$n" -ne 0 ]; then
  echo "cellray: sanitizers: $n report(s) in $reports:" >&2
  for f in "$reports"/*; do
    echo "---- $f" >&2
    head -n 60 "$f" >&2
  done
  exit 1
fi
[ "$status" -eq 0 ] || exit "$status"
echo "cellray: sanitizers: 0 reports (ASan, LSan, UBSan)"
