#!/usr/bin/env python3
"""Grid against octree against BVH (and the hierarchical grid) on one scene, from Python: for every backend
this machine has, the speed of tracing one ray set (Mrays/s, median of --repeat runs) and the wrong answers
the fp64 reference finds, plotted with matplotlib.

    .venv/bin/python examples/compare_structures.py scenes/spd/teapot.nff --rays 200000 -o structures.png

Needs the cellray package (docs/PYTHON.md): `pip install .`, or PYTHONPATH=build/release/python.
"""
import argparse
import json
import time

import numpy as np

import cellray


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", nargs="?", default="scenes/spd/teapot.nff")
    ap.add_argument("--rays", type=int, default=200_000, help="diffuse rays (a closest-hit set)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--accels", default="grid,octree,bvh,hgrid")
    ap.add_argument("--backends", default="scalar,simd,opencl")
    ap.add_argument("-o", "--output", default="structures.png")
    a = ap.parse_args()

    scene = cellray.Scene.load(a.scene)
    rays = scene.rays("diffuse", count=a.rays)
    rows = []
    for backend in a.backends.split(","):
        for accel in a.accels.split(","):
            try:
                tracer = scene.tracer(accel=accel, backend=backend)
            except RuntimeError as e:  # e.g. no OpenCL device here
                print(f"{backend}: skipped ({str(e).splitlines()[0]})")
                break
            tracer.intersect(rays[:4096])  # warm-up (an OpenCL program's first launch)
            times = []
            for _ in range(a.repeat):
                t0 = time.perf_counter()
                hits = tracer.intersect(rays)
                times.append(time.perf_counter() - t0)
            ms = 1e3 * float(np.median(times))
            verdict = cellray.check(scene, rays, hits)
            rows.append({"backend": tracer.backend, "accel": accel, "ms": ms, "mrays_per_s": len(rays) / ms / 1e3,
                         "wrong": verdict["wrong"], "ties": verdict["ties"], "build_ms": tracer.stats()["build_ms"]})
            r = rows[-1]
            print(f"{r['backend']:>7} {accel:>7}: {r['mrays_per_s']:7.2f} Mrays/s  build {r['build_ms']:7.1f} ms  "
                  f"wrong {r['wrong']} of {len(rays)}")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    backends = list(dict.fromkeys(r["backend"] for r in rows))
    accels = list(dict.fromkeys(r["accel"] for r in rows))
    fig, ax = plt.subplots(figsize=(8, 4))
    width = 0.8 / len(accels)
    for k, accel in enumerate(accels):
        xs, ys, labels = [], [], []
        for i, b in enumerate(backends):
            for r in rows:
                if r["backend"] == b and r["accel"] == accel:
                    xs.append(i + k * width)
                    ys.append(r["mrays_per_s"])
                    labels.append(f"{r['wrong']} wrong")
        bars = ax.bar(xs, ys, width, label=accel)
        for bar, lab in zip(bars, labels):
            ax.text(bar.get_x() + bar.get_width() / 2, bar.get_height(), lab, ha="center", va="bottom", fontsize=7)
    ax.set_xticks([i + width * (len(accels) - 1) / 2 for i in range(len(backends))], backends)
    ax.set_ylabel("Mrays/s (median)")
    ax.set_title(f"{scene.path}: {len(rays)} diffuse rays, wrong answers against the fp64 reference")
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.output, dpi=110)
    print(json.dumps(rows))


if __name__ == "__main__":
    main()
