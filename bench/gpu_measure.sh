#!/usr/bin/env bash
# The measurements to take on a machine with an OpenCL GPU, in one run (a lent
# GPU is held for minutes): correctness of every primitive type's kernels on
# that GPU's compiler (the hard-case suite and the geometry scenes, robust and
# fp64 against the reference), the bench rows (every structure on OpenCL, the
# SIMD BVH and Embree on the host's cores, 2^20 rays per set), and the
# compile table of the programs the GPU's driver built (NVIDIA: PTX through
# ptxas, bench/ptx_resources.py).
#
#   bench/gpu_measure.sh BIN OUT [MESH_DIR] [SECONDS]
#
# BIN: the cellray binary; OUT: a new directory for the logs and results;
# MESH_DIR: the .obj meshes (default ../shared/scenes/meshes; skipped when
# absent); SECONDS: a budget for the whole run (default 480): each step runs
# under what is left of it, and a step cut short still leaves the earlier ones'
# files. Run from the source root. The steps, in order of what a short lease
# most needs: info, every structure and variant on OpenCL over the SPD scenes
# and meshes, the compile table, the geometry scenes (every primitive type),
# the hard cases, the host's SIMD and Embree rows. docs/OPENCL.md ("On a
# GPU") records what it found.
set -uo pipefail
bin="$1"; out="$2"; meshes="${3:-../shared/scenes/meshes}"; budget="${4:-480}"
mkdir -p "$out"
export CELLRAY_CACHE_DIR="${CELLRAY_CACHE_DIR:-$out/clcache}"
start=$(date +%s)
left() { echo $(( budget - ($(date +%s) - start) )); }
step() {  # step NAME COMMAND...: runs under the budget left, logs to $out/NAME.log
  local name="$1"; shift
  local l; l=$(left)
  if [ "$l" -le 5 ]; then echo "== $name: skipped (budget spent)"; return; fi
  echo "== $name ($(date -u +%T), ${l} s left): $*"
  timeout "$l" "$@" >"$out/$name.log" 2>&1
  local rc=$?
  echo "== $name: rc $rc after $(( $(date +%s) - start )) s"
  rm -rf "$out"/*/rays  # the bench's ray sets (32 MiB per 2^20 rays): the results are what comes back
}
rays=1048576
common=(--kinds primary,shadow,diffuse --rays "$rays" --repeat 3 --no-images --no-plots --no-stats)

step info "$bin" info
mesh_list=()
for m in bunny sponza dragon100k sibenik igea conference; do
  [ -f "$meshes/$m.obj" ] && mesh_list+=("$meshes/$m.obj")
done
scenes=(balls gears mount rings teapot tetra tree "${mesh_list[@]}")
# Every structure and variant on the GPU, robust, against the reference.
for s in "${scenes[@]}"; do
  n=$(basename "$s" .obj)
  step "cl-$n" "$bin" bench "$s" --backend opencl --precision robust "${common[@]}" -o "$out/cl-$n"
done
# The compile table of the programs the driver built for those rows.
step ptx python3 bench/ptx_resources.py "$CELLRAY_CACHE_DIR" --out "$out"
# Every primitive type on the GPU's compiler: robust and fp64 must be 0 wrong.
step geometry "$bin" bench scenes/geometry/csg.nff scenes/geometry/sdf.nff scenes/geometry/quadrics.nff \
  scenes/geometry/polyhedra.nff scenes/distributed/motion.nff scenes/scale/ground-sphere.nff \
  scenes/scale/mixed-scales.nff --backend opencl --accel bvh,hgrid --precision robust,fp64 "${common[@]}" \
  -o "$out/geometry"
step hard "$bin" hard --backend opencl --precision robust --precision fp64 -o "$out/hard.md"
# The host's SIMD BVH and Embree on the same rays, for the GPU/CPU ratios.
for s in "${scenes[@]}"; do
  n=$(basename "$s" .obj)
  step "cpu-$n" "$bin" bench "$s" --backend simd,embree --accel bvh --precision robust "${common[@]}" -o "$out/cpu-$n"
done
echo "== done after $(( $(date +%s) - start )) s"
