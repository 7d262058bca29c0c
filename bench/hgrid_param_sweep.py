#!/usr/bin/env python3
"""Sweeps the hierarchical grid's densities (--hgrid-top-density T, root cells
per primitive; --hgrid-density S, child cells per reference of a crowded cell) over
scenes and ray kinds, and prints a table of trace times with, per row, the
uniform grid and the BVH on the same backend for scale. The last row is the
geometric mean over rows of time / best time of the row, so the pair with the
lowest value is the best overall. The defaults of host/accel/hgrid_builder.cpp
were chosen with this script.

usage: bench/hgrid_param_sweep.py [--bin CELLRAY] [--top 0.25,1,4]
         [--sub 1,2,4] [--kinds primary,diffuse] [--size 256] [--backend simd]
         [--threads 1] [--repeat 3] [--json OUT] [SCENE...]
Defaults: build/release/bin/cellray, scenes/spd/*.nff. Times are the fastest
of --repeat runs (trace_ms_min). Every configuration's answers are checked
against the fp64 reference once (a wrong answer aborts the sweep).
"""
import argparse
import glob
import json
import math
import os
import sys
import tempfile

from benchlib import run, run_text


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default="build/release/bin/cellray")
    ap.add_argument("--top", default="0.25,1,4")
    ap.add_argument("--sub", default="1,2,4")
    ap.add_argument("--kinds", default="primary,diffuse")
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--backend", default="simd")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", help="write every row here")
    ap.add_argument("scenes", nargs="*")
    a = ap.parse_args()
    if not os.access(a.bin, os.X_OK):
        sys.exit(f"hgrid_param_sweep: no cellray binary at {a.bin} (build first or pass --bin)")
    scenes = a.scenes or sorted(glob.glob("scenes/spd/*.nff"))
    pairs = [(float(t), float(s)) for t in a.top.split(",") for s in a.sub.split(",")]
    work = tempfile.mkdtemp(prefix="hgrid_sweep_")
    rows = []
    for scene in scenes:
        name = os.path.splitext(os.path.basename(scene))[0]
        for kind in a.kinds.split(","):
            rays = os.path.join(work, f"{name}.{kind}.rays")
            gen = [a.bin, "rays", scene, "--kind", kind, "-o", rays]
            gen += ["--size", f"{a.size}x{a.size}"] if kind == "primary" else ["--count", str(a.size * a.size)]
            run_text(gen)
            occl = ["--occlusion"] if kind == "shadow" else []
            base = [a.bin, "trace", scene, "--rays", rays, "--backend", a.backend, "--threads", str(a.threads)] + occl

            def timed(extra):
                return run(base + extra + ["--repeat", str(a.repeat)])["trace_ms_min"]

            row = {"scene": name, "kind": kind, "grid": timed(["--accel", "grid"]), "bvh": timed(["--accel", "bvh"])}
            for t, s in pairs:
                extra = ["--accel", "hgrid", "--hgrid-top-density", str(t), "--hgrid-density", str(s)]
                row[f"{t:g}/{s:g}"] = timed(extra)
                hits = os.path.join(work, "h.hits")
                run_text(base + extra + ["-o", hits])
                chk = run([a.bin, "check", scene, "--rays", rays, "--hits", hits] + occl)
                if chk["wrong"]:
                    sys.exit(f"hgrid_param_sweep: {name} {kind} {t:g}/{s:g}: {chk['wrong']} wrong answers")
            rows.append(row)
            best = min(row[f"{t:g}/{s:g}"] for t, s in pairs)
            print(f"{name:9s} {kind:8s} grid {row['grid']:7.2f} bvh {row['bvh']:7.2f} best hgrid {best:7.2f} ms",
                  flush=True)
    keys = [f"{t:g}/{s:g}" for t, s in pairs]
    print()
    print("| scene | kind | grid | bvh | " + " | ".join(keys) + " |")
    print("|---|---|---:|---:|" + "---:|" * len(keys))
    for r in rows:
        print(f"| {r['scene']} | {r['kind']} | {r['grid']:.2f} | {r['bvh']:.2f} | " +
              " | ".join(f"{r[k]:.2f}" for k in keys) + " |")
    gm = {}
    for k in keys:
        gm[k] = math.exp(sum(math.log(r[k] / min(r[q] for q in keys)) for r in rows) / len(rows))
    gm_grid = math.exp(sum(math.log(r["grid"] / min(r[q] for q in keys)) for r in rows) / len(rows))
    gm_bvh = math.exp(sum(math.log(r["bvh"] / min(r[q] for q in keys)) for r in rows) / len(rows))
    print(f"| geo-mean time / best hgrid | | {gm_grid:.2f} | {gm_bvh:.2f} | " +
          " | ".join(f"{gm[k]:.2f}" for k in keys) + " |")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
