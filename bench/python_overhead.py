#!/usr/bin/env python3
"""The Python API's overhead (issue 22): tracing N rays (default 10^6) through tracer.intersect against
`cellray trace --repeat R` on the same .rays file, structure and backend; both the median of R runs. Also
checks that the API traced the caller's array in place (the address it read is the array's) and that the
answers are the CLI's bit for bit.

    PYTHONPATH=build/release/python .venv/bin/python bench/python_overhead.py [--scene scenes/spd/balls.nff]
        [--rays 1000000] [--kind diffuse] [--accel bvh] [--backend simd] [--repeat 7]
"""
import argparse
import json
import os
import subprocess
import tempfile
import time

import numpy as np

import cellray

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", default=os.path.join(ROOT, "build", "release", "bin", "cellray"))
    ap.add_argument("--scene", default="scenes/spd/balls.nff")
    ap.add_argument("--rays", type=int, default=1_000_000)
    ap.add_argument("--kind", default="diffuse")
    ap.add_argument("--accel", default="bvh")
    ap.add_argument("--backend", default="simd")
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--variant", default=None,
                    help="the traversal variant on both sides (simd auto decides per call by timing a pilot, so the "
                         "two sides may decide differently)")
    a = ap.parse_args()
    scene = cellray.Scene.load(a.scene)
    rays = scene.rays(a.kind, count=a.rays)
    occlusion = a.kind in ("shadow", "soft")
    with tempfile.TemporaryDirectory() as d:
        rays_path, hits_path = os.path.join(d, "r.rays"), os.path.join(d, "r.hits")
        cellray.write_rays(rays_path, rays)
        cmd = [a.binary, "trace", a.scene, "--rays", rays_path, "--accel", a.accel, "--backend", a.backend,
               "--repeat", str(a.repeat), "-o", hits_path] + (["--occlusion"] if occlusion else []) + (
                   ["--variant", a.variant] if a.variant else [])
        cli = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout.strip().splitlines()[-1])
        cli_hits = cellray.read_hits(hits_path)
    tracer = scene.tracer(accel=a.accel, backend=a.backend, variant=a.variant)
    hits = tracer.intersect(rays, occlusion=occlusion)  # warm-up, as the CLI's Prepare
    times, reuse = [], []
    for _ in range(a.repeat):
        # A fresh result per call (its memory is new pages to the process) ...
        t0 = time.perf_counter()
        hits = tracer.intersect(rays, occlusion=occlusion)
        times.append(1e3 * (time.perf_counter() - t0))
    for _ in range(a.repeat):
        # ... and written over (out=), as `cellray trace --repeat` reuses its hit buffer.
        t0 = time.perf_counter()
        tracer.intersect(rays, occlusion=occlusion, out=hits)
        reuse.append(1e3 * (time.perf_counter() - t0))
    raw = []
    for _ in range(a.repeat):
        # The native call alone: intersect less its check of the rays (NaN, zero directions, tmin > tmax), the
        # pass the CLI makes when it reads the .rays file, outside its trace_ms.
        t0 = time.perf_counter()
        tracer._t._trace_into(rays, None, occlusion, hits)
        raw.append(1e3 * (time.perf_counter() - t0))
    py_ms = float(np.median(times))
    py_out_ms = float(np.median(reuse))
    raw_ms = float(np.median(raw))
    in_place = tracer._t._last_input_address == rays.__array_interface__["data"][0]
    same = np.array_equal(hits.records().view(np.uint32), cli_hits.view(np.uint32))
    out = {"scene": a.scene, "rays": len(rays), "kind": a.kind, "accel": a.accel, "backend": tracer.backend,
           "cli_variant": cli["variant"], "python_variant": tracer.variant,
           "cli_trace_ms": cli["trace_ms"], "python_intersect_ms": py_ms, "python_intersect_out_ms": py_out_ms,
           "python_native_out_ms": raw_ms,
           "overhead": py_ms / cli["trace_ms"] - 1.0, "overhead_out": py_out_ms / cli["trace_ms"] - 1.0,
           "overhead_native_out": raw_ms / cli["trace_ms"] - 1.0,
           "traced_in_place": in_place, "same_hits_as_cli": same}
    print(json.dumps(out))


if __name__ == "__main__":
    main()
