#!/usr/bin/env python3
"""The GPU compile table: every OpenCL kernel configuration compiled for an
AMD GPU (gfx906 by default: Vega 20, the MI50/MI60 and Radeon VII) by clang 15
with libclc's builtins, and the resources the compiler reports for each
kernel: VGPRs and SGPRs, scratch (private memory spilled or kept in memory:
the traversal stacks), LDS, code size, and the occupancy in waves per SIMD
that the registers allow. docs/OPENCL.md records its output and reads it.

  bench/gpu_compile.py [--mcpu gfx906] [--out DIR] [--jobs N] [--filter TEXT] [--exclude TEXT,...]
                       [--accels grid,octree,bvh,hgrid] [--precisions fast,robust,fp64]
                       [--type-sets T,ST,STC,all]
                       [--cold auto|call|inline] [--check-host BIN]

A configuration is what host/cl/cl_options.cpp (ClBuildOptions) passes to a
GPU: the precision, the primitive types of the scene (CR_HAS_*), one
structure (CR_ACCEL_ONE), the query (closest or any hit), the variant (ray
or packet, 8x8 work-groups as the host picks off the CPU), the ray source
(a buffer or the camera, generated in double where the device has fp64, as
gfx906 has), with -cl-fp32-correctly-rounded-divide-sqrt (the kernels'
bit-identical float answers rest on it) and the cold paths as calls
(--cold inline: inlined, as CELLRAY_CL_COLD=inline builds them), plus the `generic` programs (every
type and structure, chosen by arguments). The type sets are those of the SPD
scenes: triangles (gears, teapot, tetra and the meshes), spheres and
triangles (balls, mount), spheres, triangles and cones (rings, tree), and
all four with boxes. The structure and type lists come from kernels/types.h.
--check-host BIN compares the options built here with those the host itself
reports (`cellray trace --backend opencl --stats` on PoCL) for one scene.

Writes DIR/gpu_compile.json and DIR/gpu_compile.md; exits 1 when a
configuration fails to compile (the table lists it), 2 when clang 15 or
libclc is missing (77 with --skip-missing: ctest's test of the table).
"""
import argparse
import concurrent.futures
import itertools
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
KERNELS = os.path.join(ROOT, "kernels")
CLANG15 = ["/usr/lib/llvm-15/bin/clang", "clang-15"]
LIBCLC = "/usr/lib/clc"

# The type sets of the SPD scenes (and one with every type), by type name.
TYPE_SETS = [("T", ["TRIANGLE"]), ("ST", ["SPHERE", "TRIANGLE"]), ("STC", ["SPHERE", "TRIANGLE", "CONE"])]
QUERIES = [("closest", 0, "RAYS"), ("any", 1, "RAYS"), ("camera", 0, "CAMERA")]
VARIANTS = ["ray", "stackless", "packet"]  # stackless: the ray kernel with the BVH walked without a stack
PRECISIONS = ["fast", "robust", "fp64"]
PACKET = (8, 8)  # host/cl/cl_options.cpp: 8x8 work-groups off the CPU


SKIP = 77  # --skip-missing: ctest's SKIP_RETURN_CODE


def die(msg, code=2):
    print(f"cellray: bench/gpu_compile.py: {msg}", file=sys.stderr)
    sys.exit(code)


def type_and_accel_lists():
    """(types, accels) in kernels/types.h order: CR_PRIM_TYPES' and CR_ACCEL_TYPES' upper-case names."""
    text = open(os.path.join(KERNELS, "types.h")).read()

    def macro(name):
        m = re.search(r"#define " + name + r"\(X\)((?:.*\\\n)*.*)", text)
        if not m:
            die(f"kernels/types.h: no {name}")
        return m.group(1)

    types = re.findall(r"X\(\s*\w+\s*,\s*(\w+)\s*,", macro("CR_PRIM_TYPES"))
    accels = re.findall(r"X\(\s*\w+\s*,\s*(\w+)\s*,", macro("CR_ACCEL_TYPES"))
    if not types or not accels:
        die("kernels/types.h: could not read CR_PRIM_TYPES / CR_ACCEL_TYPES")
    return types, accels


def build_options(precision, types_present, all_types, accel, anyhit, variant, source, generic=False, cold="auto"):
    """ClBuildOptions (host/cl/cl_options.cpp) for a GPU with fp64 and correctly rounded divide/sqrt (8x8
    packets); `cold`: the cold paths as calls (auto, the host's default, or call) or inlined
    (CELLRAY_CL_COLD=inline)."""
    o = ["-cl-std=CL1.2", "-cl-fp32-correctly-rounded-divide-sqrt"]
    if precision == "fast":
        o.append("-DCR_FAST")
    if precision == "fp64":
        o.append("-DCR_FP64")
    o.append("-DCR_CAMERA_FP64")
    inline = cold == "inline"
    if inline:
        o.append("-DCR_COLD_INLINE")
    o += [f"-DCR_PACKET_W={PACKET[0]}", f"-DCR_PACKET_H={PACKET[1]}"]
    if not generic:
        o += [f"-DCR_HAS_{t}={int(t in types_present)}" for t in all_types]
        # Static scenes (a moving scene's programs are the generic ones'
        # motion code, compiled in every generic configuration).
        o.append("-DCR_HAS_MOTION=0")
        o += ["-DCR_ACCEL_ONE", f"-DCR_ACCEL_{accel}"]
        o += [f"-DCR_ANYHIT={anyhit}", "-DCR_UNIFIED=0"]
        o.append("-DCR_VARIANT_PACKET" if variant == "packet" else "-DCR_VARIANT_RAY")
        if variant == "stackless":
            o.append("-DCR_BVH_STACKLESS")
        o.append(f"-DCR_SOURCE_{source}")
    return o


def find_clang():
    for c in CLANG15:
        p = shutil.which(c) or (c if os.path.exists(c) else None)
        if p:
            return p
    return None


INFO = {
    "code_bytes": r"codeLenInByte = (\d+)",
    "sgprs": r"NumSgprs: (\d+)",
    "vgprs": r"NumVgprs: (\d+)",
    "scratch_bytes": r"ScratchSize: (\d+)",
    "lds_bytes": r"LDSByteSize: (\d+)",
    "waves_per_simd": r"Occupancy: (\d+)",
}


def parse_kernels(asm):
    """{kernel: {field: int}} from the '; Kernel info:' blocks of an AMDGPU assembly listing."""
    out = {}
    name = None
    for line in asm.splitlines():
        m = re.match(r"^([A-Za-z_]\w*):\s*;\s*@", line)
        if m:
            name = m.group(1)
            continue
        if line.startswith("; Kernel info:") and name:
            out[name] = {}
            cur = out[name]
            continue
        if name in out:
            for key, rx in INFO.items():
                m = re.search(r"^; " + rx, line)
                if m:
                    out[name][key] = int(m.group(1))
    calls = len(re.findall(r"\bs_swappc_b64\b", asm))
    for k in out.values():
        k["calls"] = calls  # calls in the listing (cold paths kept out of line)
    return out


def compile_one(clang, mcpu, bc, cfg, tmp):
    src = os.path.join(KERNELS, "trace.cl")
    asm = os.path.join(tmp, cfg["id"] + ".s")
    cmd = [clang, "-x", "cl", "-target", "amdgcn-mesa-mesa3d", f"-mcpu={mcpu}", "-nogpulib",
           "-Xclang", "-finclude-default-header", "-Xclang", "-mlink-builtin-bitcode", "-Xclang", bc,
           "-O3", "-I", KERNELS, "-S", "-o", asm, src] + cfg["options"]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        return dict(cfg, error=(r.stderr.strip().splitlines() or ["clang failed"])[-1][:300])
    kernels = parse_kernels(open(asm).read())
    return dict(cfg, kernels=kernels)


def configurations(args, types, accels):
    cfgs = []
    sets = [x for x in TYPE_SETS + [("all", list(types))] if x[0] in args.type_sets]
    for accel, variant, (qname, anyhit, source), prec, (tname, tset) in itertools.product(
            [a for a in accels if a.lower() in args.accels], VARIANTS, QUERIES,
            [p for p in PRECISIONS if p in args.precisions], sets):
        if variant == "stackless" and accel != "BVH":
            continue  # the BVH's walk (--variant stackless)
        cid = f"{accel.lower()}-{variant}-{qname}-{prec}-{tname}"
        cfgs.append(dict(id=cid, accel=accel.lower(), variant=variant, query=qname, precision=prec, types=tname,
                         options=build_options(prec, tset, types, accel, anyhit, variant, source,
                                               cold=args.cold)))
    for prec in [p for p in PRECISIONS if p in args.precisions]:
        cfgs.append(dict(id=f"generic-{prec}", accel="all", variant="both", query="all", precision=prec, types="all",
                         options=build_options(prec, types, types, None, 0, None, None, generic=True,
                                               cold=args.cold)))
    if args.filter:
        cfgs = [c for c in cfgs if args.filter in c["id"]]
    excluded = [x for x in args.exclude.split(",") if x]
    cfgs = [c for c in cfgs if not any(x in c["id"] for x in excluded)]
    return cfgs


def check_host(binary, types):
    """Options the host builds for tree (spheres, triangles, cones) on PoCL against ours for the same query."""
    scene = os.path.join(ROOT, "scenes", "spd", "tree.nff")
    r = subprocess.run([binary, "trace", scene, "--primary", "8x8", "--backend", "opencl", "--stats",
                        "--accel", "bvh", "--variant", "packet"], capture_output=True, text=True)
    if r.returncode != 0:
        die(f"--check-host: {binary} trace failed: {r.stderr.strip()[-300:]}", 1)
    host = json.loads(r.stdout.strip().splitlines()[-1])["build_options"].split()
    ours = build_options("robust", ["SPHERE", "TRIANGLE", "CONE"], types, "BVH", 0, "packet", "CAMERA")
    # The host's run is on a CPU (4x4 work-groups) with statistics on.
    norm = lambda o: sorted(x for x in o if not x.startswith(("-DCR_PACKET_", "-DCR_STATS")))
    if norm(host) != norm(ours):
        die(f"--check-host: the host builds {' '.join(norm(host))}\n  this script builds {' '.join(norm(ours))}", 1)
    print("host options agree: " + " ".join(norm(host)))


def markdown(results, mcpu):
    lines = [f"| configuration | kernel | VGPRs | SGPRs | scratch B | LDS B | waves/SIMD | code B |",
             "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in results:
        if "error" in r:
            lines.append(f"| {r['id']} | compile error: {r['error']} | | | | | | |")
            continue
        for k, v in sorted(r["kernels"].items()):
            lines.append(f"| {r['id']} | {k} | {v.get('vgprs', '')} | {v.get('sgprs', '')} | "
                         f"{v.get('scratch_bytes', '')} | {v.get('lds_bytes', '')} | {v.get('waves_per_simd', '')} | "
                         f"{v.get('code_bytes', '')} |")
    return f"GPU compile table, {mcpu} (clang 15, libclc)\n\n" + "\n".join(lines) + "\n"


def summary(results):
    ks = [(r["id"], k, v) for r in results if "kernels" in r for k, v in r["kernels"].items()]
    if not ks:
        return "no kernel compiled"
    no_scratch = sum(1 for _, _, v in ks if v.get("scratch_bytes", 0) == 0)
    five = sum(1 for _, _, v in ks if v.get("waves_per_simd", 0) >= 5)
    worst = max(ks, key=lambda x: x[2].get("vgprs", 0))
    return (f"{len(ks)} kernels in {len(results)} configurations: {no_scratch} without scratch, "
            f"{five} at 5 waves/SIMD or more; most VGPRs {worst[2].get('vgprs')} ({worst[0]} {worst[1]})")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mcpu", default="gfx906")
    ap.add_argument("--out", default="gpu-compile-out")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--filter", default="", help="only configurations whose id contains this text")
    ap.add_argument("--exclude", default="",
                    help="comma-separated texts: no configuration whose id contains one of them")
    ap.add_argument("--accels", default="grid,octree,bvh,hgrid")
    ap.add_argument("--precisions", default=",".join(PRECISIONS))
    ap.add_argument("--type-sets", default="T,ST,STC,all",
                    help="type sets compiled: T, ST, STC (the SPD scenes'), all (every type)")
    ap.add_argument("--cold", choices=["auto", "call", "inline"], default="auto",
                    help="cold paths as calls or inlined (auto: as the host builds them, calls unless "
                    "CELLRAY_CL_COLD=inline)")
    ap.add_argument("--define", action="append", default=[], metavar="NAME[=VALUE]",
                    help="an extra -D for every configuration (an experiment, e.g. CR_COLD_INLINE)")
    ap.add_argument("--check-host", metavar="BIN", help="compare with the host's own options (needs PoCL)")
    ap.add_argument("--skip-missing", action="store_true",
                    help=f"exit {SKIP} (a skipped test) when clang 15 or libclc is missing")
    args = ap.parse_args()
    args.accels = args.accels.split(",")
    args.precisions = args.precisions.split(",")
    args.type_sets = args.type_sets.split(",")
    clang = find_clang()
    missing = SKIP if args.skip_missing else 2
    if not clang:
        die("clang 15 not found (Debian: clang-15; scripts/install-deps.sh installs it)", missing)
    bc = os.path.join(LIBCLC, f"{args.mcpu}-amdgcn-mesa-mesa3d.bc")
    if not os.path.exists(bc):
        die(f"{bc} not found (Debian: libclc-15; scripts/install-deps.sh installs it)", missing)
    types, accels = type_and_accel_lists()
    if args.check_host:
        check_host(args.check_host, types)
    cfgs = configurations(args, types, accels)
    for c in cfgs:
        c["options"] += ["-D" + d for d in args.define]
    if not cfgs:
        die("no configuration matches")
    os.makedirs(args.out, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp, concurrent.futures.ThreadPoolExecutor(max(1, args.jobs)) as ex:
        results = list(ex.map(lambda c: compile_one(clang, args.mcpu, bc, c, tmp), cfgs))
    data = {"mcpu": args.mcpu, "clang": subprocess.run([clang, "--version"], capture_output=True,
                                                       text=True).stdout.splitlines()[0],
            "libclc": os.path.basename(bc), "configurations": results}
    tmpjson = os.path.join(args.out, ".gpu_compile.json.tmp")
    with open(tmpjson, "w") as f:
        json.dump(data, f, indent=1)
    os.replace(tmpjson, os.path.join(args.out, "gpu_compile.json"))
    md = markdown(results, args.mcpu)
    tmpmd = os.path.join(args.out, ".gpu_compile.md.tmp")
    with open(tmpmd, "w") as f:
        f.write(md + "\n" + summary(results) + "\n")
    os.replace(tmpmd, os.path.join(args.out, "gpu_compile.md"))
    print(summary(results))
    failed = [r["id"] for r in results if "error" in r]
    if failed:
        print("failed: " + ", ".join(failed), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
