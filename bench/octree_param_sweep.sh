#!/usr/bin/env bash
# Sweeps the octree's build parameters, --octree-leaf K (max references per
# leaf) and --octree-depth D (max depth), over the SPD scenes: scalar backend,
# one thread, primary rays (closest hit) and shadow rays (occlusion). Prints
# one row per (K, D):
#   time_sum   sum over scenes and both ray kinds of the trace time (ms): the
#              fastest of REPEAT runs (TIME=trace_ms for the median), since
#              other work on a shared machine only ever adds time
#   rel_gmean  geometric mean over scenes x kinds of time / best time of that
#              scene and kind over all (K, D): 1.00 = best everywhere
#   IT, TS     intersection tests and traversal steps per ray, mean over
#              scenes x kinds (Havran's N_IT and N_TS; machine independent)
#   build_ms   sum of build times; MiB  sum of structure sizes
# Timings are only as good as the machine is quiet.
#
# Measured when the defaults were chosen (256x256, fastest of 5, a shared
# 2-core machine): time_sum in ms at D = 8 / 10 / 12
#   K = 4: 1226 / 1103 / 1096    K = 8: 1178 / 1037 / 1025
#   K = 6: 1202 / 1047 / 1055    K = 12: 1152 / 1012 / 1010 (964 / 961 rerun)
#   K = 16: 1151 / 1012 / 1005 (966 / 957 rerun)   K = 24: 1011 / 1022 and
#   K = 32: 1093 / 1091 at D = 10 / 12.
# Hence leaf 12, depth 10: as fast as any, and depth 12 only adds memory
# (20.7 against 13.9 MiB summed over the scenes) and build time.
#
# Usage: bench/octree_param_sweep.sh   (from the repository root)
# Environment: CELLRAY (binary), SCENES, LEAVES, DEPTHS, SIZE (WxH), REPEAT,
# TIME (trace_ms_min or trace_ms), RAW (a file to keep the per-scene table in:
# K D scene kind ms IT TS build_ms bytes).
set -euo pipefail

CELLRAY=${CELLRAY:-build/release/bin/cellray}
SCENES=${SCENES:-"balls gears jacks lattice mount rings shells sombrero teapot tetra tree"}
LEAVES=${LEAVES:-"4 8 12 16 24 32"}
DEPTHS=${DEPTHS:-"8 10 12"}
SIZE=${SIZE:-256x256}
REPEAT=${REPEAT:-5}
TIME=${TIME:-trace_ms_min}
RAW=${RAW:-}

[ -x "$CELLRAY" ] || { echo "octree_param_sweep: no cellray binary at $CELLRAY (build first or set CELLRAY)" >&2; exit 2; }
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

# A number field of cellray's one-line JSON output (the first occurrence).
field() { grep -o "\"$1\":[-0-9.eE+]*" <<<"$2" | head -n 1 | cut -d: -f2; }

for s in $SCENES; do
  for kind in primary shadow; do
    "$CELLRAY" rays "scenes/spd/$s.nff" --kind "$kind" --size "$SIZE" -o "$WORK/$s.$kind.rays" >/dev/null
  done
done

# One line per (K, D, scene, kind): time, IT, TS, build ms, bytes.
RESULTS="$WORK/results.tsv"
# Configurations innermost: a change of load on a shared machine then hits
# every (K, D) of a scene alike instead of biasing whole rows.
for s in $SCENES; do
  for kind in primary shadow; do
    for K in $LEAVES; do
      for D in $DEPTHS; do
        occl=()
        [ "$kind" = shadow ] && occl=(--occlusion)
        common=("scenes/spd/$s.nff" --rays "$WORK/$s.$kind.rays" "${occl[@]}" --accel octree --backend scalar
                --threads 1 --octree-leaf "$K" --octree-depth "$D")
        timed=$("$CELLRAY" trace "${common[@]}" --repeat "$REPEAT")
        stats=$("$CELLRAY" trace "${common[@]}" --stats)
        printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$K" "$D" "$s" "$kind" "$(field "$TIME" "$timed")" \
          "$(field intersection_tests "$stats")" "$(field traversal_steps "$stats")" \
          "$(field build_ms "$timed")" "$(field bytes "$stats")" >>"$RESULTS"
      done
    done
  done
done

[ -n "$RAW" ] && cp "$RESULTS" "$RAW"
echo "octree parameter sweep: $(echo $SCENES | wc -w) SPD scenes, primary + shadow rays at $SIZE, scalar, 1 thread, $TIME of $REPEAT"
awk -F'\t' '
  { key = $1 " " $2; sk = $3 " " $4; t[key, sk] = $5; keys[key] = 1; sks[sk] = 1
    if (!(sk in best) || $5 < best[sk]) best[sk] = $5
    sum[key] += $5; it[key] += $6; ts[key] += $7; n[key]++
    if ($4 == "primary") { build[key] += $8; bytes[key] += $9 } }
  END {
    printf "%4s %4s %10s %10s %8s %8s %10s %8s\n", "K", "D", "time_sum", "rel_gmean", "IT", "TS", "build_ms", "MiB"
    for (key in keys) {
      lg = 0; m = 0
      for (sk in sks) { lg += log(t[key, sk] / best[sk]); m++ }
      split(key, kd, " ")
      printf "%4d %4d %10.1f %10.3f %8.2f %8.2f %10.1f %8.2f\n", kd[1], kd[2], sum[key], exp(lg / m),
             it[key] / n[key], ts[key] / n[key], build[key], bytes[key] / 1048576
    }
  }' "$RESULTS" | { read -r header; echo "$header"; sort -k1,1n -k2,2n; }
