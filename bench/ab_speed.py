#!/usr/bin/env python3
"""A/B speed of two cellray builds on identical ray sets: for each scene x ray
kind x configuration, both binaries trace the same .rays file, alternately,
and the table gives the median trace time of each and their ratio (new / base;
below 1 means the new build is faster), with the geometric mean per
configuration and overall. Answers are compared too: the .hits of the two
builds must be identical unless --allow-diff is given (a change that moves
answers then has the count of differing records in each row). Shadow rays
are occlusion queries, whose records name some occluder: there the same rays
must be occluded, by any primitive.

  bench/ab_speed.py --base OTHER/build/release/bin/cellray [--new build/release/bin/cellray]
                    [--scenes balls,gears,...] [--kinds primary,shadow,diffuse]
                    [--configs simd:bvh,simd:grid,simd:octree,scalar:bvh,opencl:bvh]
                    [--precision robust] [--rays 65536] [--repeat 5] [--rounds 2] [--threads 1]
                    [--stat median|min] [--trace-args="--octree-margin ray"]

Run it on a quiet machine: the ratio of two noisy medians is noisier still,
so --rounds repeats the whole alternation and the best median of each build
is kept. A configuration may name a traversal variant (simd:grid:packet,
opencl:bvh:ray): without one, the simd backend's `auto` picks packets or
single rays by a timed pilot, and two builds can pick differently on the
same rays, which then times the choice rather than the kernels.
"""
import argparse
import math
import os
import tempfile

from benchlib import ROOT, run

SPD7 = ["balls", "gears", "mount", "rings", "teapot", "tetra", "tree"]


def Occluded(hits, offset):
    """Whether the .hits record at byte `offset` has an occluder (prim != CR_NO_HIT)."""
    return hits[offset + 4:offset + 8] != b"\xff\xff\xff\xff"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base", required=True, help="the cellray binary to compare against")
    ap.add_argument("--new", default=os.path.join(ROOT, "build", "release", "bin", "cellray"))
    ap.add_argument("--scenes", default=",".join(SPD7))
    ap.add_argument("--kinds", default="primary,shadow,diffuse")
    ap.add_argument("--configs", default="simd:bvh,simd:grid,simd:octree,scalar:bvh,opencl:bvh")
    ap.add_argument("--precision", default="robust")
    ap.add_argument("--rays", type=int, default=65536)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--allow-diff", action="store_true")
    ap.add_argument("--stat", choices=["median", "min"], default="median",
                    help="per run, the median of the --repeat timings (default) or their minimum; PoCL's "
                         "timings on a small machine are bimodal (runs twice as slow as the rest), where the "
                         "minimum is the steadier figure")
    ap.add_argument("--trace-args", default="",
                    help="more `cellray trace` options for both builds, e.g. \"--octree-margin ray\"")
    a = ap.parse_args()
    side = int(math.ceil(math.sqrt(a.rays)))
    logs = {}
    print(f"| scene | kind | config | base ms | new ms | new / base | hits |")
    print("| --- | --- | --- | ---: | ---: | ---: | --- |")
    with tempfile.TemporaryDirectory(prefix="cellray_ab_") as tmp:
        for scene in a.scenes.split(","):
            path = scene if os.path.exists(scene) else os.path.join(ROOT, "scenes", "spd", scene + ".nff")
            for kind in a.kinds.split(","):
                rays = os.path.join(tmp, f"{os.path.basename(scene)}_{kind}.rays")
                gen = [a.new, "rays", path, "--kind", kind, "-o", rays]
                gen += ["--size", f"{side}x{side}"] if kind == "primary" else ["--count", str(a.rays), "--size", "512x512"]
                run(gen)
                occ = ["--occlusion"] if kind == "shadow" else []
                for cfg in a.configs.split(","):
                    backend, accel, *variant = cfg.split(":")
                    var = ["--variant", variant[0]] if variant else []
                    best = {}
                    hits = {}
                    for _ in range(a.rounds):
                        for name, binary in (("base", a.base), ("new", a.new)):
                            out = os.path.join(tmp, f"{name}.hits")
                            r = run([binary, "trace", path, "--rays", rays, "--accel", accel, "--backend", backend,
                                     "--precision", a.precision, "--repeat", str(a.repeat), "--threads",
                                     str(a.threads), "-o", out] + occ + var + a.trace_args.split())
                            ms = r["trace_ms_min"] if a.stat == "min" else r["trace_ms"]
                            best[name] = min(best.get(name, float("inf")), ms)
                            with open(out, "rb") as f:
                                hits[name] = f.read()
                    hb, hn = hits["base"], hits["new"]
                    if occ:
                        # An occlusion record names some occluder (FORMATS.md):
                        # the same rays must be occluded, by any primitive.
                        ndiff = sum(Occluded(hb, i) != Occluded(hn, i) for i in range(16, min(len(hb), len(hn)), 16))
                        same = len(hb) == len(hn) and ndiff == 0
                    else:
                        ndiff = sum(hb[i:i + 16] != hn[i:i + 16] for i in range(16, min(len(hb), len(hn)), 16))
                        same = hb == hn
                    if not same and not a.allow_diff:
                        raise SystemExit(f"ab_speed: {scene} {kind} {cfg}: the two builds answer {ndiff} rays "
                                         "differently (--allow-diff to time them anyway)")
                    ratio = best["new"] / best["base"]
                    logs.setdefault(cfg, []).append(math.log(ratio))
                    print(f"| {os.path.basename(scene)} | {kind} | {cfg} | {best['base']:.2f} | {best['new']:.2f} | "
                          f"{ratio:.3f} | {'same' if same else f'{ndiff} differ'} |", flush=True)
    print()
    print("| config | geometric mean of new / base |")
    print("| --- | ---: |")
    every = []
    for cfg, ls in logs.items():
        every += ls
        print(f"| {cfg} | {math.exp(sum(ls) / len(ls)):.3f} |")
    print(f"| all | {math.exp(sum(every) / len(every)):.3f} |")


if __name__ == "__main__":
    main()
