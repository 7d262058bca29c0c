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

and, optionally, of the same run of the octree with the ray's margins

    cellray bench --backend simd,opencl --accel octree --octree-margin ray \
                  --kinds primary,diffuse --precision robust --no-images -o DIR2

whose rows become the column "octree-ray" (the octree's ratio is then that of
the faster octree form).

usage: bench/study_table.py DIR/results.json [DIR2/results.json ...] > tables.md
"""
import json
import math
import sys

STRUCTS = ("grid", "hgrid", "octree", "octree-ray", "bvh")
BAR = 1.0 / 1.5


def gmean(v):
    return math.exp(sum(map(math.log, v)) / len(v)) if v else float("nan")


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    rows = []
    for path in sys.argv[1:]:
        with open(path) as f:
            d = json.load(f)
        ray = (d.get("options", {}).get("structure_params") or {}).get("octree-margin") == "ray"
        for r in d["rows"]:
            if r["precision"] == "robust" and r["backend"] in ("simd", "opencl"):
                if ray and r["accel"] == "octree":
                    r["accel"] = "octree-ray"
                rows.append(r)
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
        has_ray = any(r["accel"] == "octree-ray" for r in sel)
        shown = [a for a in STRUCTS if a != "octree-ray" or has_ray]
        out.append("| scene | kind | " + " | ".join(shown) + " | best grid / bvh | best octree / bvh "
                   "| hgrid IT / TS | octree IT / TS | " + ("octree-ray IT / TS | " if has_ray else "") + "bvh IT / TS |")
        out.append("|---|---|" + "---:|" * (len(shown) + 2) + "---:|" * (4 if has_ray else 3))
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
                o = max(speed.get("octree", 0.0), speed.get("octree-ray", 0.0)) / speed["bvh"]
                if g > 0:
                    grid_ratio.append(g)
                if o > 0:
                    octree_ratio.append(o)

                def measures(a):
                    st = stats.get(a)
                    if not st:
                        return "–"
                    return f"{st.get('intersection_tests', float('nan')):.1f} / {st.get('traversal_steps', float('nan')):.1f}"

                cells = " | ".join(f"{speed.get(a, 0.0):.2f}" for a in shown)
                ray_cell = f" {measures('octree-ray')} |" if has_ray else ""
                out.append(f"| {s} | {k} | {cells} | {g:.2f} | {o:.2f} | {measures('hgrid')} | {measures('octree')} "
                           f"|{ray_cell} {measures('bvh')} |")
        out.append("| geometric mean | |" + " |" * len(shown) + f" {gmean(grid_ratio):.2f} | {gmean(octree_ratio):.2f} |" +
                   " |" * (4 if has_ray else 3))
        out.append("")
        out.append(f"{be}: rows at or above the bar ({BAR:.2f}): best grid form "
                   f"{sum(r >= BAR for r in grid_ratio)} of {len(grid_ratio)}, best octree form "
                   f"{sum(r >= BAR for r in octree_ratio)} of {len(octree_ratio)}; geometric means (Mrays/s): " +
                   ", ".join(f"{a} {gmean(v):.2f}" for a, v in per_struct.items() if v))
    print("\n".join(out))


if __name__ == "__main__":
    main()
