#!/usr/bin/env bash
# Builds the libFuzzer targets of the input readers (preset "fuzz", clang) and
# runs them; see docs/FUZZING.md.
#
#   scripts/fuzz.sh smoke                 every target over its seed corpus, then a
#                                         short fixed-seed run (what CI does)
#   scripts/fuzz.sh campaign SECONDS [T]  a long run of target T (default: all, one
#                                         after the other); corpus kept in
#                                         build/fuzz/corpus/T, findings in
#                                         build/fuzz/findings/T
#   scripts/fuzz.sh run T [ARGS...]       the target's binary with its dictionary
#                                         and limits, plus libFuzzer ARGS (e.g. a
#                                         crash file to reproduce it)
#
# Every run gives each input at most 10 s (-timeout: a hang is a finding) and
# refuses a single allocation above 256 MiB or a resident size above 2 GiB (a
# count in the input that asks for a huge allocation is a finding: the readers
# must refuse it with an InputError instead).
set -euo pipefail
cd "$(dirname "$0")/.."

targets=(nff obj rays_hits)
# Fixed-seed smoke runs, sized for about 10 s each on one CI core.
declare -A smoke_runs=([nff]=20000 [obj]=6000 [rays_hits]=8000)

build() {
  bash scripts/install-deps.sh
  cmake --preset fuzz >/dev/null
  cmake --build --preset fuzz -j "$(nproc)" >/dev/null
}

# The libFuzzer flags every run uses for target $1.
flags() {
  local t=$1
  local f=(-timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=256 -max_len=8192 -print_final_stats=1)
  [ -f "tests/fuzz/$t.dict" ] && f+=("-dict=tests/fuzz/$t.dict")
  printf '%s\n' "${f[@]}"
}

run_target() {
  local t=$1
  shift
  mapfile -t f < <(flags "$t")
  "build/fuzz/bin/fuzz_$t" "${f[@]}" "$@"
}

smoke() {
  local scratch rc=0
  scratch=$(mktemp -d "${TMPDIR:-/tmp}/cellray_fuzz_smoke.XXXXXX")
  trap 'rm -rf "$scratch"' RETURN
  for t in "${targets[@]}"; do
    mkdir -p "$scratch/$t/corpus" "$scratch/$t/findings"
    # New inputs go to the scratch corpus (the first directory), never into
    # the seed corpus in the repository.
    if run_target "$t" -seed=1 -runs="${smoke_runs[$t]}" -max_total_time=60 \
         -artifact_prefix="$scratch/$t/findings/" "$scratch/$t/corpus" "tests/fuzz/corpus/$t" \
         >"$scratch/$t/log.txt" 2>&1; then
      echo "cellray: fuzz smoke: $t: $(grep -m1 -o 'stat::number_of_executed_units: *[0-9]*' "$scratch/$t/log.txt" |
        awk '{print $2}') inputs, $(grep -o 'cov: [0-9]*' "$scratch/$t/log.txt" | tail -1), no finding"
    else
      rc=1
      echo "cellray: fuzz smoke: $t FAILED; the end of its log:" >&2
      tail -n 60 "$scratch/$t/log.txt" >&2
      mkdir -p build/fuzz/findings/"$t"
      cp -r "$scratch/$t/findings/." build/fuzz/findings/"$t"/ 2>/dev/null || true
      echo "cellray: the input is in build/fuzz/findings/$t/ (docs/FUZZING.md: reproduce, minimise, fix)" >&2
    fi
  done
  return $rc
}

campaign() {
  local seconds=$1
  shift
  local list=("$@")
  [ ${#list[@]} -eq 0 ] && list=("${targets[@]}")
  for t in "${list[@]}"; do
    mkdir -p "build/fuzz/corpus/$t" "build/fuzz/findings/$t"
    echo "cellray: fuzz campaign: $t for $seconds s; log build/fuzz/campaign-$t.log"
    # One process, one core: run two targets side by side with two invocations.
    run_target "$t" -max_total_time="$seconds" -artifact_prefix="build/fuzz/findings/$t/" \
      "build/fuzz/corpus/$t" "tests/fuzz/corpus/$t" >"build/fuzz/campaign-$t.log" 2>&1 || {
      echo "cellray: fuzz campaign: $t stopped on a finding: build/fuzz/findings/$t/ (log build/fuzz/campaign-$t.log)" >&2
      return 1
    }
    grep -E '^stat::|^Done' "build/fuzz/campaign-$t.log" | sed 's/^/  /'
  done
}

case "${1:-smoke}" in
  smoke) build && smoke ;;
  campaign)
    [ $# -ge 2 ] || { echo "usage: scripts/fuzz.sh campaign SECONDS [TARGET...]" >&2; exit 2; }
    build && campaign "${@:2}" ;;
  run)
    [ $# -ge 2 ] || { echo "usage: scripts/fuzz.sh run TARGET [LIBFUZZER ARGS...]" >&2; exit 2; }
    build && run_target "${@:2}" ;;
  *) echo "usage: scripts/fuzz.sh smoke | campaign SECONDS [TARGET...] | run TARGET [ARGS...]" >&2; exit 2 ;;
esac
