#!/usr/bin/env python3
"""Full-size conformance run: for each scene x ray kind, generate a ray set,
trace it with each structure x backend x precision (x extra options), and
check every answer against the fp64 reference. Prints a Markdown table (and
JSON lines with --json); exit 1 when a robust or fp64 answer is wrong.

  bench/conformance.py [--scenes balls,gears,...|spd|meshes|scale|geometry|all|FILE|gen:KIND:N]
                       [--accels grid,octree,bvh] [--backends scalar,simd:sse4,opencl:packet,...]
                       [--kinds primary,shadow,diffuse,random,axis] [--queries auto|closest|occlusion|both]
                       [--precision robust,fp64] [--options "--bvh-quality high;--octree-margin ray"]
                       [--transform S,TX,TY,TZ] [--rays 262144] [--bin build/release/bin/cellray]

Shadow rays are checked as occlusion queries, the others as closest-hit
queries (--queries auto); `both` traces every kind both ways. The `axis`
kind is the diffuse set (random where a scene has no diffuse rays) with
degenerate directions: axis-aligned, one component zero, one component of
1e-40 .. 1e-30, and tmin in {0, 1e-3, 0.5}, tmax in {10, 1e5, inf}.
--transform moves an NFF scene: every position x becomes S x + T, radii and
the hither distance S times theirs (the scene written to a temporary file),
e.g. `--transform 1,1e5,-3e4,7e4` (far from the origin) or `1e-6,0,0,0`
(tiny). --options runs every configuration once per entry (';'-separated
sets of extra `trace` options). Meshes are read from ../shared/scenes/meshes/
(never copied into the repository). This is the sweep of docs/TOLERANCE.md,
"On scenes the tests had not seen".
"""
import argparse
import json
import math
import os
import random
import struct
import sys
import tempfile

from benchlib import ROOT, run

SPD = ["balls", "gears", "jacks", "lattice", "mount", "rings", "shells", "sombrero", "teapot", "tetra", "tree"]
MESHES = ["bunny", "dragon100k", "igea", "sponza", "sibenik", "conference"]
SCALE = ["ground-sphere", "ground-quad", "mixed-scales"]
GEOMETRY = ["quadrics", "csg", "sdf", "polyhedra"]


def scene_path(name):
    if name in MESHES:
        return os.path.join(ROOT, "..", "shared", "scenes", "meshes", name + ".obj")
    if name in SCALE:
        return os.path.join(ROOT, "scenes", "scale", name + ".nff")
    if name in GEOMETRY:
        return os.path.join(ROOT, "scenes", "geometry", name + ".nff")
    if os.path.exists(name) or name.startswith("gen:"):
        return name
    return os.path.join(ROOT, "scenes", "spd", name + ".nff")


def transform_nff(src, dst, s, t):
    """Writes src with every position x -> s x + t and every radius and the hither distance times s.
    Statements this does not know (NFF extensions: quadrics, CSG, SDF, boxes) stop it."""
    def pos(v):
        return " ".join(repr(s * float(v[i]) + t[i]) for i in range(3))
    lines = open(src).read().split("\n")
    out, i = [], 0
    while i < len(lines):
        line = lines[i]
        w = line.split()
        i += 1
        if not w or w[0].startswith("#") or w[0] in ("v", "up", "angle", "resolution", "b", "f"):
            out.append(line)
        elif w[0] in ("from", "at"):
            out.append(w[0] + " " + pos(w[1:4]))
        elif w[0] == "hither":
            out.append("hither " + repr(float(w[1]) * s))
        elif w[0] == "l":
            out.append("l " + pos(w[1:4]) + "".join(" " + x for x in w[4:]))
        elif w[0] == "s":
            out.append("s " + pos(w[1:4]) + " " + repr(float(w[4]) * s))
        elif w[0] == "c" and len(w) >= 9:
            out.append("c " + pos(w[1:4]) + " " + repr(float(w[4]) * s) + " " + pos(w[5:8]) + " " + repr(float(w[8]) * s))
        elif w[0] == "c":
            out.append("c")
            for _ in range(2):
                a = lines[i].split()
                i += 1
                out.append(pos(a[0:3]) + " " + repr(float(a[3]) * s))
        elif w[0] in ("p", "pp") and len(w) > 2:  # the vertices on the statement's line
            k, n = (6 if w[0] == "pp" else 3), int(w[1])
            v = w[2:]
            if len(v) != k * n:
                raise SystemExit(f"--transform: {src}:{i}: expected {n} vertices on the line")
            out.append(f"{w[0]} {n} " + "  ".join(pos(v[j * k:j * k + 3]) + "".join(" " + x for x in v[j * k + 3:j * k + k])
                                                  for j in range(n)))
        elif w[0] in ("p", "pp"):
            out.append(line)
            for _ in range(int(w[1])):
                a = lines[i].split()
                i += 1
                out.append(pos(a[0:3]) + "".join(" " + x for x in a[3:]))
        else:
            raise SystemExit(f"--transform: {src}:{i}: statement '{w[0]}' is not transformed by this script")
    with open(dst, "w") as f:
        f.write("\n".join(out) + "\n")


def axis_rays(src, dst, seed=7):
    """The rays of src (CRRAYS01 or CRRAYS02) with degenerate directions and mixed [tmin, tmax]."""
    b = open(src, "rb").read()
    magic, n = b[:8], struct.unpack("<Q", b[8:16])[0]
    size = 36 if magic == b"CRRAYS02" else 32
    rng = random.Random(seed)
    out = bytearray(b[:16])
    for i in range(n):
        rec = list(struct.unpack("<%df" % (size // 4), b[16 + size * i:16 + size * (i + 1)]))
        d = [rng.gauss(0, 1) for _ in range(3)]
        m = i % 4
        if m == 0:
            d = [0.0, 0.0, 0.0]
            d[rng.randrange(3)] = rng.choice([-1.0, 1.0])
        elif m == 1:
            d[rng.randrange(3)] = 0.0
        elif m == 2:
            d[rng.randrange(3)] = rng.choice([1e-40, -1e-40, 1e-30, -3e-39])
        rec[3] = rng.choice([0.0, 0.0, 1e-3, 0.5])
        rec[4:7] = d
        rec[7] = rng.choice([float("inf"), float("inf"), 10.0, 1e5])
        out += struct.pack("<%df" % (size // 4), *rec)
    with open(dst, "wb") as f:
        f.write(bytes(out))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default="spd")
    ap.add_argument("--accels", default="grid,octree,bvh")
    ap.add_argument("--backends", default="scalar")
    ap.add_argument("--kinds", default="primary,shadow,diffuse,random")
    ap.add_argument("--queries", default="auto", choices=["auto", "closest", "occlusion", "both"])
    ap.add_argument("--precision", default="robust", help="comma-separated: fast,robust,fp64")
    ap.add_argument("--options", default="", help="';'-separated sets of extra trace options")
    ap.add_argument("--transform", default="", help="S,TX,TY,TZ: every position x -> S x + T (NFF scenes)")
    ap.add_argument("--rays", type=int, default=262144)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "release", "bin", "cellray"))
    ap.add_argument("--json", action="store_true", help="also print one JSON line per row")
    a = ap.parse_args()
    groups = {"spd": SPD, "meshes": MESHES, "scale": SCALE, "geometry": GEOMETRY,
              "all": SPD + MESHES + SCALE + GEOMETRY}
    scenes = [x for name in a.scenes.split(",") for x in groups.get(name, [name])]
    xf = None
    if a.transform:
        v = [float(x) for x in a.transform.split(",")]
        if len(v) != 4 or v[0] <= 0:
            raise SystemExit("--transform: expected S,TX,TY,TZ with S > 0")
        xf = (v[0], v[1:])
    option_sets = [o.split() for o in a.options.split(";")] if a.options else [[]]
    side = int(math.ceil(math.sqrt(a.rays)))
    total_wrong = 0
    print("| scene | kind | query | rays | accel | backend | precision | options | agree | ties | flips | wrong | "
          "max rel t err | Mrays/s |")
    print("| --- | --- | --- | ---: | --- | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    with tempfile.TemporaryDirectory(prefix="cellray_conf_") as tmp:
        for scene in scenes:
            path = scene_path(scene)
            label = os.path.basename(scene).replace(":", "_")
            if xf:
                if not path.endswith(".nff"):
                    print(f"<!-- {scene}: not an NFF file, --transform skips it -->", flush=True)
                    continue
                moved = os.path.join(tmp, label + "_moved.nff")
                transform_nff(path, moved, xf[0], xf[1])
                path = moved
            for kind in a.kinds.split(","):
                rays = os.path.join(tmp, f"{label}_{kind}.rays")
                source = "diffuse" if kind == "axis" else kind
                gen = [a.bin, "rays", path, "--kind", source, "-o", rays]
                gen += ["--size", f"{side}x{side}"] if kind == "primary" else ["--count", str(a.rays), "--size", "512x512"]
                nrays = run(gen)["rays"]
                if kind == "axis":
                    if nrays == 0:
                        nrays = run([a.bin, "rays", path, "--kind", "random", "--count", str(a.rays), "-o", rays])["rays"]
                    axis_rays(rays, rays)
                if nrays == 0:
                    print(f"<!-- {label} {kind}: no rays -->", flush=True)
                    continue
                queries = {"auto": ["occlusion" if kind == "shadow" else "closest"], "both": ["closest", "occlusion"]}
                for query in queries.get(a.queries, [a.queries]):
                    occ = ["--occlusion"] if query == "occlusion" else []
                    for backend in a.backends.split(","):
                        # BACKEND[:VARIANT_OPTION], e.g. simd:sse4 (--isa) or opencl:packet (--variant)
                        name, _, opt = backend.partition(":")
                        extra = []
                        if opt:
                            extra = ["--isa" if name == "simd" and opt in ("sse4", "avx2", "avx512") else "--variant", opt]
                        for accel in a.accels.split(","):
                            for precision in a.precision.split(","):
                                for options in option_sets:
                                    hits = os.path.join(tmp, "out.hits")
                                    t = run([a.bin, "trace", path, "--rays", rays, "--accel", accel, "--backend", name,
                                             "--precision", precision, "-o", hits] + occ + extra + options)
                                    c = run([a.bin, "check", path, "--rays", rays, "--hits", hits] + occ)
                                    if precision != "fast":
                                        total_wrong += c["wrong"]
                                    print(f"| {label} | {kind} | {query} | {nrays} | {accel} | {backend} | {precision} | "
                                          f"{' '.join(options)} | {c['agree']} | {c['ties']} | {c['flips']} | {c['wrong']} | "
                                          f"{c['max_rel_t_err']:.2e} | {t['mrays_per_s']:.2f} |", flush=True)
                                    if a.json:
                                        print(json.dumps({"scene": scene, "kind": kind, "query": query, "accel": accel,
                                                          "backend": backend, "precision": precision,
                                                          "options": options, "trace": t, "check": c}), flush=True)
    print(f"\ntotal wrong (robust and fp64): {total_wrong}")
    return 1 if total_wrong else 0


if __name__ == "__main__":
    sys.exit(main())
