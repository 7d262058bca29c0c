#!/usr/bin/env bash
# Sweeps the uniform grid's density (cells per primitive, --grid-density) over
# scenes and ray kinds and prints a table of trace times; the last row is the
# geometric mean over rows of time / best time of the row (the best of the
# fixed densities), so the density with the lowest value is the best overall.
# Density 0 is the cost model (host/accel/grid_cost.cpp, the default), shown
# as "cost": its row of the mean is its distance from each scene's best
# fixed density. The former fixed default (16) was chosen with this script.
#
# usage: bench/grid_density_sweep.sh [-b CELLRAY] [-d "0 1 2 4 8 16"] [-k "primary shadow"]
#                                    [-B scalar] [-s 512] [-t 1] [-r 5] [-w WORKDIR] [SCENE...]
# Defaults: build/release/bin/cellray, scenes/spd/*.nff, 512x512 primary rays
# and as many of the other kinds, scalar backend (-B: simd, opencl), 1 thread, the fastest of 5
# runs (the minimum, not the median: on a shared machine other processes only
# ever add time, so the minimum is the least disturbed figure).
# Every trace is also checked against the fp64 reference (a wrong answer
# aborts the sweep: timing a wrong tracer is meaningless).
set -euo pipefail

bin=build/release/bin/cellray
densities="0 1 2 4 8 16"
backend=scalar
kinds="primary shadow"
size=512
threads=1
repeat=5
work=""
while getopts "b:d:k:B:s:t:r:w:h" opt; do
  case $opt in
    b) bin=$OPTARG ;;
    d) densities=$OPTARG ;;
    k) kinds=$OPTARG ;;
    B) backend=$OPTARG ;;
    s) size=$OPTARG ;;
    t) threads=$OPTARG ;;
    r) repeat=$OPTARG ;;
    w) work=$OPTARG ;;
    *) awk 'NR > 1 && !/^#/ { exit } NR > 1 { print }' "$0"; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
scenes=("$@")
[ ${#scenes[@]} -eq 0 ] && scenes=(scenes/spd/*.nff)
[ -x "$bin" ] || { echo "grid_density_sweep: no cellray binary at $bin (build first or pass -b)" >&2; exit 2; }
if [ -z "$work" ]; then
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
fi
mkdir -p "$work"

field() { sed -n "s/.*\"$1\":\([0-9.eE+-]*\).*/\1/p"; }

count=$((size * size))
table="$work/table.tsv"
: >"$table"
for scene in "${scenes[@]}"; do
  name=$(basename "$scene")
  name=${name%.*}
  for kind in $kinds; do
    rays="$work/$name.$kind.rays"
    if [ "$kind" = primary ]; then
      "$bin" rays "$scene" --kind primary --size "${size}x${size}" -o "$rays" >/dev/null
    else
      "$bin" rays "$scene" --kind "$kind" --count "$count" -o "$rays" >/dev/null
    fi
    occ=()
    [ "$kind" = shadow ] && occ=(--occlusion)
    row="$name	$kind"
    for d in $densities; do
      out=$("$bin" trace "$scene" --rays "$rays" "${occ[@]}" --accel grid --backend "$backend" --threads "$threads" \
        --grid-density "$d" --repeat "$repeat" -o "$work/hits")
      wrong=$("$bin" check "$scene" --rays "$rays" --hits "$work/hits" "${occ[@]}" | field wrong)
      if [ "$wrong" != 0 ]; then
        echo "grid_density_sweep: $name $kind density $d: $wrong wrong answers" >&2
        exit 1
      fi
      row="$row	$(echo "$out" | field trace_ms_min)"
    done
    echo "$row" >>"$table"
    echo "$row" | awk -F'\t' '{ printf "%s %s done\n", $1, $2 }' >&2
  done
done

awk -F'\t' -v repeat="$repeat" -v dens="$densities" -v threads="$threads" -v size="$size" -v backend="$backend" '
BEGIN { nd = split(dens, D, " "); for (i = 1; i <= nd; i++) L[i] = D[i] == 0 ? "cost" : "d=" D[i] }
{
  rows++
  best = -1
  for (i = 1; i <= nd; i++) if (D[i] != 0 && (best < 0 || $(i + 2) < best)) best = $(i + 2)
  if (best < 0) best = $3
  for (i = 1; i <= nd; i++) lsum[i] += log($(i + 2) / best)
  line[rows] = $0
}
END {
  printf "grid trace time (ms, min of %d), %s backend, %d thread(s), %dx%d rays per set\n", repeat, backend, threads, size, size
  printf "%-10s %-8s", "scene", "rays"
  for (i = 1; i <= nd; i++) printf " %10s", L[i]
  printf "\n"
  for (r = 1; r <= rows; r++) {
    n = split(line[r], F, "\t")
    printf "%-10s %-8s", F[1], F[2]
    for (i = 1; i <= nd; i++) printf " %10.1f", F[i + 2]
    printf "\n"
  }
  printf "%-19s", "geomean time/best"
  bi = 1
  for (i = 1; i <= nd; i++) {
    g = exp(lsum[i] / rows)
    printf " %10.3f", g
    if (i == 1 || g < bg) { bg = g; bi = i }
  }
  printf "\nbest overall: %s\n", L[bi]
}' "$table"
