#!/usr/bin/env python3
"""The GPU compile table on an NVIDIA GPU: the programs the host built there,
read back from cellray's OpenCL program cache (NVIDIA's OpenCL binaries are
PTX), assembled by ptxas for the GPU's architecture, with the resources ptxas
reports per kernel: registers, stack frame (local memory: the traversal
stacks), spill stores and loads, shared memory, and the occupancy in warps
per SM that the registers allow. bench/gpu_compile.py is the same table for
an AMD GPU compiled here without one.

  bench/ptx_resources.py CACHE_DIR [--arch sm_90] [--ptxas ptxas] [--out DIR]
  bench/ptx_resources.py --from-json ptx_resources.json [--out DIR]   (the table again, no GPU)

CACHE_DIR is where `cellray` kept the programs ($CELLRAY_CACHE_DIR, else
$XDG_CACHE_HOME/cellray or ~/.cache/cellray); run `cellray trace` or `bench`
with `--backend opencl` on the GPU first. A configuration is named by its
build options (precision, primitive types, structure, query, variant, ray
source). Writes DIR/ptx_resources.json and DIR/ptx_resources.md; exits 2
when ptxas or the cache is missing, 1 when a program fails to assemble.
"""
import argparse
import glob
import json
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile

MAGIC = b"CRCLPROG"
HEADER = 64  # host/cl/cl_program_cache.h: kClCacheHeaderBytes
# sm_80/sm_90: 65,536 registers per SM, allocated per warp in units of 256
# (8 per thread), at most 64 warps (2,048 threads) per SM, 255 per thread.
REGS_PER_SM, WARPS_PER_SM, REG_UNIT = 65536, 64, 256


def die(msg, code=2):
    print(f"ptx_resources: {msg}", file=sys.stderr)
    sys.exit(code)


def read_entry(path):
    """(key text, payload bytes) of one cache file, or None when it is not one."""
    raw = open(path, "rb").read()
    if len(raw) < HEADER or raw[:8] != MAGIC:
        return None
    key_bytes = struct.unpack_from("<I", raw, 12)[0]
    payload_bytes = struct.unpack_from("<Q", raw, 32)[0]
    key = raw[HEADER:HEADER + key_bytes].decode("utf-8", "replace")
    payload = raw[HEADER + key_bytes:HEADER + key_bytes + payload_bytes]
    return key, payload


def label(options):
    """A short name of a configuration from its build options."""
    d = dict(re.findall(r"-D(\w+)(?:=(\S+))?", options))
    prec = "fp64" if "CR_FP64" in d else "fast" if "CR_FAST" in d else "robust"
    accel = next((k[9:].lower() for k in d if k.startswith("CR_ACCEL_") and k != "CR_ACCEL_ONE"), "generic")
    types = "".join(k[7] for k, v in sorted(d.items()) if k.startswith("CR_HAS_") and k != "CR_HAS_MOTION" and v == "1")
    query = "any" if d.get("CR_ANYHIT") == "1" else "closest"
    variant = "packet" if "CR_VARIANT_PACKET" in d else "stackless" if "CR_BVH_STACKLESS" in d else "ray"
    source = "camera" if "CR_SOURCE_CAMERA" in d else "rays"
    motion = " motion" if d.get("CR_HAS_MOTION") == "1" else ""
    return f"{prec} {accel} {types or '-'} {query} {variant} {source}{motion}"


def parse_ptxas(text):
    """{function: {field: int}} from `ptxas -v` output."""
    out, cur = {}, None
    for line in text.splitlines():
        m = re.search(r"(?:Compiling entry function|Function properties for) '?(\w+)'?", line)
        if m:
            cur = out.setdefault(m.group(1), {})
            continue
        if cur is None:
            continue
        m = re.search(r"(\d+) bytes stack frame, (\d+) bytes spill stores, (\d+) bytes spill loads", line)
        if m:
            cur.update(stack_bytes=int(m.group(1)), spill_store_bytes=int(m.group(2)),
                       spill_load_bytes=int(m.group(3)))
        m = re.search(r"Used (\d+) registers", line)
        if m:
            cur["registers"] = int(m.group(1))
            m2 = re.search(r"(\d+) bytes smem", line)
            cur["smem_bytes"] = int(m2.group(1)) if m2 else 0
    return out


def warps_per_sm(regs):
    per_warp = -(-max(regs, 1) * 32 // REG_UNIT) * REG_UNIT
    return min(WARPS_PER_SM, REGS_PER_SM // per_warp)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cache", nargs="?")
    ap.add_argument("--from-json", help="write the table from an earlier run's ptx_resources.json")
    ap.add_argument("--arch", default="sm_90")
    ap.add_argument("--ptxas", default=shutil.which("ptxas") or "/usr/local/cuda/bin/ptxas")
    ap.add_argument("--out", default=".")
    a = ap.parse_args()
    if a.from_json:
        j = json.load(open(a.from_json))
        for r in j["programs"]:
            r["config"] = label(r["options"])
        return write(sorted(j["programs"], key=lambda r: r["config"]), j["arch"], a.out, 0)
    if not a.cache:
        die("name the program cache directory (or --from-json FILE)")
    if not os.path.exists(a.ptxas):
        die(f"no ptxas ({a.ptxas}): install CUDA's compiler or name it with --ptxas")
    files = sorted(glob.glob(os.path.join(a.cache, "*.clbin")))
    if not files:
        die(f"{a.cache}: no cached programs (run cellray with --backend opencl first)")
    results, failed = [], 0
    with tempfile.TemporaryDirectory() as tmp:
        for f in files:
            e = read_entry(f)
            if e is None:
                continue
            key, payload = e
            m = re.search(r"^options=(.*)$", key, re.M)
            options = m.group(1) if m else ""
            start = payload.find(b"//")
            if b".entry" not in payload or start < 0:
                continue  # not PTX (another device's binary)
            ptx = os.path.join(tmp, "p.ptx")
            open(ptx, "wb").write(payload[start:].rstrip(b"\0"))
            r = subprocess.run([a.ptxas, f"-arch={a.arch}", "-v", ptx, "-o", os.devnull],
                               capture_output=True, text=True)
            row = dict(config=label(options), options=options, file=os.path.basename(f))
            if r.returncode != 0:
                failed += 1
                row["error"] = (r.stderr.strip().splitlines() or ["ptxas failed"])[-1][:300]
            else:
                kernels = {k: v for k, v in parse_ptxas(r.stdout + r.stderr).items() if "registers" in v}
                for v in kernels.values():
                    v["warps_per_sm"] = warps_per_sm(v["registers"])
                row["kernels"] = kernels
            results.append(row)
    results.sort(key=lambda r: r["config"])
    return write(results, a.arch, a.out, failed)


def write(results, arch, out, failed):
    os.makedirs(out, exist_ok=True)
    json.dump(dict(arch=arch, programs=results), open(os.path.join(out, "ptx_resources.json"), "w"), indent=1)
    lines = [f"| configuration | kernel | registers | stack B | spill stores B | smem B | warps/SM |",
             "|---|---|---:|---:|---:|---:|---:|"]
    for r in results:
        if "error" in r:
            lines.append(f"| {r['config']} | failed: {r['error']} | | | | | |")
            continue
        for k, v in sorted(r["kernels"].items()):
            lines.append(f"| {r['config']} | {k} | {v['registers']} | {v.get('stack_bytes', 0)} | "
                         f"{v.get('spill_store_bytes', 0)} | {v.get('smem_bytes', 0)} | {v['warps_per_sm']} |")
    ks = [v for r in results for v in r.get("kernels", {}).values()]
    summary = (f"{len(results)} programs, {len(ks)} kernels for {arch}: "
               f"{sum(1 for v in ks if v.get('stack_bytes', 0) == 0)} without a stack frame, "
               f"{sum(1 for v in ks if v.get('spill_store_bytes', 0) == 0)} without spills, "
               f"{sum(1 for v in ks if v['warps_per_sm'] >= 32)} at 32 warps/SM or more (half occupancy)")
    open(os.path.join(out, "ptx_resources.md"), "w").write("\n".join(lines) + "\n\n" + summary + "\n")
    print(summary)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
