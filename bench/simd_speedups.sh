#!/usr/bin/env bash
# Speed-ups of the SIMD backend over the scalar backend, one thread, same
# rays, median of --repeat runs (cellray trace reports the median as
# trace_ms), and the two-thread scaling of AVX2 packets on primary rays, for
# each structure. Prints markdown tables (docs/SIMD.md holds them).
#
# usage: bench/simd_speedups.sh [-b BIN] [-s WxH] [-r REPEAT] [-S "scene ..."] [-A "accel ..."] [-T]
#   BIN     the cellray binary (default build/release/bin/cellray)
#   WxH     primary image size; secondary and random sets get W*H rays (default 512x512)
#   REPEAT  timed repetitions per cell (default 5)
#   scenes  SPD scene names (default "balls gears teapot tree")
#   accels  structures (default "bvh grid octree")
#   -T      only the two-thread tables (they need both cores idle)
# The `auto` column is the default variant (what it chose: p packet, s
# single). The answers of the scalar backend and of both AVX2 variants are
# checked against the fp64 reference (`wrong`: scalar / packet / single; the
# SIMD backend must match the scalar count). Timings on a loaded machine are
# noise: the script prints the load average before and after.
set -euo pipefail

BIN=build/release/bin/cellray
SIZE=512x512
REPEAT=5
SCENES="balls gears teapot tree"
ACCELS="bvh grid octree"
ONLY_SCALING=0
while getopts "b:s:r:S:A:T" opt; do
  case $opt in
    b) BIN=$OPTARG ;;
    s) SIZE=$OPTARG ;;
    r) REPEAT=$OPTARG ;;
    S) SCENES=$OPTARG ;;
    A) ACCELS=$OPTARG ;;
    T) ONLY_SCALING=1 ;;
    *) sed -n '2,20p' "$0"; exit 2 ;;
  esac
done
ROOT=$(cd "$(dirname "$0")/.." && pwd)
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
COUNT=$(( ${SIZE%x*} * ${SIZE#*x} ))
ISA=$("$BIN" info | python3 -c 'import json,sys; print(json.load(sys.stdin)["simd_isa"])')

ms() {  # ms SCENE RAYS OCCL ARGS... -> median trace_ms
  local scene=$1 rays=$2 occl=$3; shift 3
  "$BIN" trace "$ROOT/scenes/spd/$scene.nff" --rays "$rays" $occl --threads 1 --repeat "$REPEAT" "$@" \
    | python3 -c 'import json,sys; print(json.load(sys.stdin)["trace_ms"])'
}
auto() {  # auto SCENE RAYS OCCL ACCEL -> "median_ms letter" of the default variant
  local scene=$1 rays=$2 occl=$3 accel=$4
  "$BIN" trace "$ROOT/scenes/spd/$scene.nff" --rays "$rays" $occl --threads 1 --repeat "$REPEAT" --backend simd \
    --accel "$accel" | python3 -c 'import json,sys; j=json.load(sys.stdin); print(j["trace_ms"], j["variant"].split()[1][0])'
}
wrong() {  # wrong SCENE RAYS OCCL ARGS... -> wrong answers of one run
  local scene=$1 rays=$2 occl=$3; shift 3
  "$BIN" trace "$ROOT/scenes/spd/$scene.nff" --rays "$rays" $occl "$@" -o "$TMP/x.hits" > /dev/null
  "$BIN" check "$ROOT/scenes/spd/$scene.nff" --rays "$rays" --hits "$TMP/x.hits" $occl \
    | python3 -c 'import json,sys; print(json.load(sys.stdin)["wrong"])'
}
cell() {  # cell BASE_MS MS -> "MS (SPEEDUPx)"
  python3 -c "import sys; b, t = float(sys.argv[1]), float(sys.argv[2]); print(f'{t:.1f} ({b / t:.2f}x)')" "$1" "$2"
}

echo "cellray SIMD speed-ups: $SIZE rays, --threads 1, median of $REPEAT, best ISA here: $ISA"
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
for scene in $SCENES; do
  for kind in primary shadow diffuse random; do
    rays="$TMP/$scene.$kind.rays"
    if [ "$kind" = primary ]; then
      "$BIN" rays "$ROOT/scenes/spd/$scene.nff" --kind primary --size "$SIZE" -o "$rays" > /dev/null
    else
      "$BIN" rays "$ROOT/scenes/spd/$scene.nff" --kind "$kind" --size "$SIZE" --count "$COUNT" -o "$rays" > /dev/null
    fi
  done
done
for accel in $ACCELS; do
  if [ "$ONLY_SCALING" = 0 ]; then
    echo
    echo "Structure: $accel"
    echo
    echo "| scene | rays | scalar ms | avx2 packet | avx2 single | avx2 auto | sse4 packet | sse4 single | wrong |"
    echo "|---|---|---|---|---|---|---|---|---|"
    for scene in $SCENES; do
      for kind in primary shadow diffuse random; do
        rays="$TMP/$scene.$kind.rays"
        occl=""
        [ "$kind" = shadow ] && occl=--occlusion
        base=$(ms "$scene" "$rays" "$occl" --accel "$accel" --backend scalar)
        row="| $scene | $kind | $(printf '%.1f' "$base")"
        for isa in avx2 sse4; do
          for variant in packet single; do
            if [ "$isa" = avx2 ] && [ "$ISA" != avx2 ]; then row="$row | n/a"; continue; fi
            t=$(ms "$scene" "$rays" "$occl" --accel "$accel" --backend simd --isa "$isa" --variant "$variant")
            row="$row | $(cell "$base" "$t")"
          done
          if [ "$isa" = avx2 ]; then
            read -r t v < <(auto "$scene" "$rays" "$occl" "$accel")
            row="$row | $(cell "$base" "$t") $v"
          fi
        done
        w="$(wrong "$scene" "$rays" "$occl" --accel "$accel" --backend scalar)"
        if [ "$ISA" = avx2 ]; then
          w="$w / $(wrong "$scene" "$rays" "$occl" --accel "$accel" --backend simd --isa avx2 --variant packet)"
          w="$w / $(wrong "$scene" "$rays" "$occl" --accel "$accel" --backend simd --isa avx2 --variant single)"
        fi
        echo "$row | $w |"
      done
    done
  fi
  echo
  echo "Two-thread scaling, $accel, $ISA packets, primary rays (median of $REPEAT):"
  echo
  echo "| scene | 1 thread ms | 2 threads ms | scaling |"
  echo "|---|---|---|---|"
  for scene in $SCENES; do
    rays="$TMP/$scene.primary.rays"
    one=$(ms "$scene" "$rays" "" --accel "$accel" --backend simd --variant packet)
    two=$("$BIN" trace "$ROOT/scenes/spd/$scene.nff" --rays "$rays" --threads 2 --repeat "$REPEAT" --backend simd \
          --accel "$accel" --variant packet | python3 -c 'import json,sys; print(json.load(sys.stdin)["trace_ms"])')
    echo "| $scene | $(printf '%.1f' "$one") | $(printf '%.1f' "$two") | $(python3 -c "print(f'{$one / $two:.2f}x')") |"
  done
done
echo
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
