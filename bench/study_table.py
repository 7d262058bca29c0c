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
        # Only the structures the runs hold get columns (a run without the
        # classic octree shows no column of zeros for it).
        present = {r["accel"] for r in sel}
        shown = [a for a in STRUCTS if a in present]
        measured = [a for a in ("hgrid", "octree", "octree-ray", "bvh") if a in present]
        out.append("| scene | kind | " + " | ".join(shown) + " | best grid / bvh | best octree / bvh | " +
                   " | ".join(f"{a} IT / TS" for a in measured) + " |")
        out.append("|---|---|" + "---:|" * (len(shown) + 2 + len(measured)))
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
                ratio = lambda x: f"{x:.2f}" if x > 0 else "–"
                out.append(f"| {s} | {k} | {cells} | {ratio(g)} | {ratio(o)} | " +
                           " | ".join(measures(a) for a in measured) + " |")
        mean = lambda v: f"{gmean(v):.2f}" if v else "–"
        out.append("| geometric mean | |" + " |" * len(shown) + f" {mean(grid_ratio)} | {mean(octree_ratio)} |" +
                   " |" * len(measured))
        out.append("")
        def at_bar(name, v):
            return f"best {name} form {sum(r >= BAR for r in v)} of {len(v)}" if v else f"no {name} rows"
        out.append(f"{be}: rows at or above the bar ({BAR:.2f}): {at_bar('grid', grid_ratio)}, "
                   f"{at_bar('octree', octree_ratio)}; geometric means (Mrays/s): " +
                   ", ".join(f"{a} {gmean(v):.2f}" for a, v in per_struct.items() if v))
    print("\n".join(out))


if __name__ == "__main__":
    main()
