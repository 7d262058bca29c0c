#!/usr/bin/env python3
"""The tables of docs/BENCHMARKS.md "Which structure, where": from the
results.json of

    cellray bench --backend simd,opencl --accel grid,octree,bvh,hgrid \\
                  --kinds primary,diffuse --precision robust --no-images -o DIR

one table per backend of Mrays/s (median of the timed runs; for a structure
with several variants, the fastest) per scene and ray kind, the ratios of the
best grid form (uniform or hierarchical) and of the octree to the BVH, and
Havran's measures (IT intersection tests, TS traversal steps per ray), then the
geometric means. The issue-18 bar is a ratio of at least 1/1.5 = 0.67.

usage: bench/study_table.py DIR/results.json > tables.md
"""
import json
import math
import sys

STRUCTS = ("grid", "hgrid", "octree", "bvh")
BAR = 1.0 / 1.5


def gmean(v):
    return math.exp(sum(map(math.log, v)) / len(v)) if v else float("nan")


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    with open(sys.argv[1]) as f:
        rows = [r for r in json.load(f)["rows"] if r["precision"] == "robust" and r["backend"] in ("simd", "opencl")]
    scenes = []
    for r in rows:
        if r["scene"] not in scenes:
            scenes.append(r["scene"])
    out = []
    for be in ("simd", "opencl"):
        sel = [r for r in rows if r["backend"] == be]
        if not sel:
            continue
        out.append(f"\n**{be}** (Mrays/s, median of the timed runs; ratio = best grid form or octree / BVH)\n")
        out.append("| scene | kind | grid | hgrid | octree | bvh | best grid / bvh | octree / bvh "
                   "| hgrid IT / TS | octree IT / TS | bvh IT / TS |")
        out.append("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        grid_ratio, octree_ratio = [], []
        per_struct = {a: [] for a in STRUCTS}
        for s in scenes:
            for k in ("primary", "diffuse"):
                speed, stats = {}, {}
                for r in sel:
                    if r["scene"] == s and r["kind"] == k:
                        a, v = r["accel"], r["mrays_per_s"]["median"]
                        if v > speed.get(a, 0.0):
                            speed[a] = v
                            stats[a] = r.get("per_ray") or stats.get(a) or {}
                if "bvh" not in speed:
                    continue
                for a in STRUCTS:
                    if a in speed:
                        per_struct[a].append(speed[a])
                g = max(speed.get("grid", 0.0), speed.get("hgrid", 0.0)) / speed["bvh"]
                o = speed.get("octree", 0.0) / speed["bvh"]
                grid_ratio.append(g)
                octree_ratio.append(o)

                def measures(a):
                    st = stats.get(a)
                    if not st:
                        return "–"
                    return f"{st.get('intersection_tests', float('nan')):.1f} / {st.get('traversal_steps', float('nan')):.1f}"

                cells = " | ".join(f"{speed.get(a, 0.0):.2f}" for a in STRUCTS)
                out.append(f"| {s} | {k} | {cells} | {g:.2f} | {o:.2f} | {measures('hgrid')} | {measures('octree')} "
                           f"| {measures('bvh')} |")
        out.append(f"| geometric mean | | | | | | {gmean(grid_ratio):.2f} | {gmean(octree_ratio):.2f} | | | |")
        out.append("")
        out.append(f"{be}: rows at or above the bar ({BAR:.2f}): best grid form "
                   f"{sum(r >= BAR for r in grid_ratio)} of {len(grid_ratio)}, octree "
                   f"{sum(r >= BAR for r in octree_ratio)} of {len(octree_ratio)}; geometric means (Mrays/s): " +
                   ", ".join(f"{a} {gmean(v):.2f}" for a, v in per_struct.items() if v))
    print("\n".join(out))


if __name__ == "__main__":
    main()
