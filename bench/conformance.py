#!/usr/bin/env python3
"""Full-size conformance run: for each scene x ray kind, generate a ray set,
trace it with each structure x backend, and check every answer against the
fp64 reference. Prints a Markdown table (and JSON lines with --json).

  bench/conformance.py [--scenes balls,gears,...|spd|meshes|scale|all] [--accels grid,octree,bvh]
                       [--backends scalar,simd:sse4,opencl:packet,...] [--kinds primary,shadow,diffuse,random]
                       [--rays 262144] [--bin build/release/bin/cellray]

Shadow rays are checked as occlusion queries. Meshes are read from
../shared/scenes/meshes/ (never copied into the repository).
"""
import argparse
import json
import math
import os
import sys
import tempfile

from benchlib import ROOT, run

SPD = ["balls", "gears", "jacks", "lattice", "mount", "rings", "shells", "sombrero", "teapot", "tetra", "tree"]
MESHES = ["bunny", "dragon100k", "igea", "sponza", "sibenik", "conference"]
SCALE = ["ground-sphere", "ground-quad", "mixed-scales"]


def scene_path(name):
    if name in MESHES:
        return os.path.join(ROOT, "..", "shared", "scenes", "meshes", name + ".obj")
    if name in SCALE:
        return os.path.join(ROOT, "scenes", "scale", name + ".nff")
    if os.path.exists(name):
        return name
    return os.path.join(ROOT, "scenes", "spd", name + ".nff")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default="spd")
    ap.add_argument("--accels", default="grid,octree,bvh")
    ap.add_argument("--backends", default="scalar")
    ap.add_argument("--kinds", default="primary,shadow,diffuse,random")
    ap.add_argument("--precision", default="robust")
    ap.add_argument("--rays", type=int, default=262144)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "release", "bin", "cellray"))
    ap.add_argument("--json", action="store_true", help="also print one JSON line per row")
    a = ap.parse_args()
    scenes = {"spd": SPD, "meshes": MESHES, "scale": SCALE, "all": SPD + MESHES + SCALE}.get(a.scenes,
                                                                                       a.scenes.split(","))
    side = int(math.ceil(math.sqrt(a.rays)))
    total_wrong = 0
    print("| scene | kind | rays | accel | backend | agree | ties | flips | wrong | max rel t err | Mrays/s |")
    print("| --- | --- | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    with tempfile.TemporaryDirectory(prefix="cellray_conf_") as tmp:
        for scene in scenes:
            path = scene_path(scene)
            for kind in a.kinds.split(","):
                rays = os.path.join(tmp, f"{os.path.basename(scene)}_{kind}.rays")
                gen = [a.bin, "rays", path, "--kind", kind, "-o", rays]
                gen += ["--size", f"{side}x{side}"] if kind == "primary" else ["--count", str(a.rays), "--size", "512x512"]
                nrays = run(gen)["rays"]
                occ = ["--occlusion"] if kind == "shadow" else []
                for backend in a.backends.split(","):
                    for accel in a.accels.split(","):
                        hits = os.path.join(tmp, "out.hits")
                        # BACKEND[:VARIANT_OPTION], e.g. simd:sse4 (--isa) or opencl:packet (--variant)
                        name, _, opt = backend.partition(":")
                        extra = []
                        if opt:
                            extra = ["--isa" if name == "simd" and opt in ("sse4", "avx2", "avx512") else "--variant", opt]
                        t = run([a.bin, "trace", path, "--rays", rays, "--accel", accel, "--backend", name,
                                 "--precision", a.precision, "-o", hits] + occ + extra)
                        c = run([a.bin, "check", path, "--rays", rays, "--hits", hits] + occ)
                        total_wrong += c["wrong"]
                        print(f"| {os.path.basename(scene)} | {kind} | {nrays} | {accel} | {backend} | {c['agree']} | "
                              f"{c['ties']} | {c['flips']} | {c['wrong']} | {c['max_rel_t_err']:.2e} | {t['mrays_per_s']:.2f} |",
                              flush=True)
                        if a.json:
                            print(json.dumps({"scene": scene, "kind": kind, "accel": accel, "backend": backend,
                                              "trace": t, "check": c}), flush=True)
    print(f"\ntotal wrong: {total_wrong}")
    return 1 if total_wrong else 0


if __name__ == "__main__":
    sys.exit(main())
