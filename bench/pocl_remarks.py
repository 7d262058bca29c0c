#!/usr/bin/env python3
"""What PoCL's work-item loop vectoriser made of a kernel: traces one scene
with a fresh program (no cellray or PoCL cache, kernels built with -g),
collects LLVM's loop-vectoriser remarks (POCL_VECTORIZER_REMARKS=1), and,
from the compiled work-group function that ran, lists every vectorised
loop with its width and the source lines it covers. docs/OPENCL.md records
its output for each structure and variant.

  bench/pocl_remarks.py [--scene balls] [--accel grid] [--variant packet]
                        [--size 64] [--bin build/release/bin/cellray]

Needs PoCL (the CPU device) and, for the list of vectorised loops, clang 15
(the LLVM of PoCL 3.1) to disassemble the work-group function; without it
only the remarks are printed. The remarks name a location only for loops
that have one: PoCL's work-item loops have none, so a refused work-item loop
is reported at the instruction that stopped it, and a vectorised one as
<unknown> (the list of vectorised loops says where they are).
"""
import argparse
import collections
import glob
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CLANG15 = ["/usr/lib/llvm-15/bin/clang", "clang-15"]


def remarks(text):
    """(location, message) pairs of the loop vectoriser in PoCL's stderr."""
    text = text.replace("\n", " ")
    parts = re.split(r"((?:kernels/[\w.]+:\d+:\d+|<unknown>:0:0): )", text)
    out = []
    for i in range(1, len(parts) - 1, 2):
        msg = parts[i + 1].strip()
        if msg.startswith("vectorized loop") or msg.startswith("loop not vectorized:"):
            out.append((parts[i][:-2], msg))
    return out


def vector_loops(ll):
    """[(width, [(file:line, count)...])] of every vector.body block of an IR text."""
    meta = {}
    for m in re.finditer(r"^!(\d+) = (distinct )?(!\w+)\((.*)\)$", ll, re.M):
        meta[m.group(1)] = (m.group(3), m.group(4))

    def field(body, name):
        m = re.search(name + r": (!?\"?[^,\"]*\"?)", body)
        return m.group(1).strip('"') if m else None

    def file_of(scope):
        seen = 0
        while scope and seen < 50:
            kind, body = meta.get(scope.lstrip("!"), (None, ""))
            f = field(body, "file")
            if f and f.startswith("!"):
                fk, fb = meta.get(f.lstrip("!"), (None, ""))
                return os.path.basename(field(fb, "filename") or "?")
            scope = field(body, "scope")
            seen += 1
        return "?"

    def loc(n):
        kind, body = meta.get(n, (None, ""))
        if kind != "!DILocation":
            return None
        return f"{file_of(field(body, 'scope'))}:{field(body, 'line')}"

    loops = []
    for m in re.finditer(r"^(vector\.body\d*):.*?\n(.*?)(?=^\S.*:|\Z)", ll, re.M | re.S):
        body = m.group(2)
        widths = [int(w) for w in re.findall(r"<(\d+) x (?:float|double|i32|i1|i64|ptr)>", body)]
        lines = collections.Counter(loc(d) for d in re.findall(r"!dbg !(\d+)", body))
        lines.pop(None, None)
        loops.append((max(widths) if widths else 0, lines.most_common(4)))
    return loops


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default="balls")
    ap.add_argument("--accel", default="grid")
    ap.add_argument("--variant", default="packet")
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "release", "bin", "cellray"))
    a = ap.parse_args()
    scene = a.scene if os.path.exists(a.scene) else os.path.join(ROOT, "scenes", "spd", a.scene + ".nff")
    with tempfile.TemporaryDirectory() as work:
        rays = os.path.join(work, "p.rays")
        subprocess.run([a.bin, "rays", scene, "--kind", "primary", "--size", f"{a.size}x{a.size}", "-o", rays],
                       check=True, capture_output=True)
        env = dict(os.environ, POCL_VECTORIZER_REMARKS="1", POCL_EXTRA_BUILD_FLAGS="-g", POCL_KERNEL_CACHE="1",
                   POCL_CACHE_DIR=os.path.join(work, "pocl"), POCL_LEAVE_KERNEL_COMPILER_TEMP_FILES="1",
                   CELLRAY_CACHE_DIR=os.path.join(work, "cellray"))
        p = subprocess.run([a.bin, "trace", scene, "--rays", rays, "--accel", a.accel, "--backend", "opencl",
                            "--variant", a.variant, "-o", os.path.join(work, "h")],
                           cwd=ROOT, env=env, capture_output=True, text=True)
        if p.returncode != 0:
            sys.stderr.write(p.stderr[-2000:])
            raise SystemExit(p.returncode)
        print(f"# {a.scene} --accel {a.accel} --variant {a.variant}")
        print("Loop-vectoriser remarks (distinct; PoCL compiles a kernel more than once):")
        # PoCL prints the remarks on stdout, before cellray's JSON.
        for (where, msg), n in sorted(collections.Counter(remarks(p.stdout + p.stderr)).items()):
            print(f"  {n:3d}x {where}: {msg}")
        clang = next((c for c in CLANG15 if shutil.which(c) or os.path.exists(c)), None)
        # The work-group function that ran: specialised to the local size (not 0-0-0).
        bcs = [b for b in glob.glob(os.path.join(work, "pocl", "*", "*", "*", "*", "parallel.bc"))
               if "/0-0-0" not in b]
        if not clang or not bcs:
            print("(no clang 15 or no compiled work-group function: vectorised loops not listed)")
            return
        ll = subprocess.run([clang, "-S", "-emit-llvm", "-Xclang", "-disable-llvm-passes", bcs[0], "-o", "-"],
                            capture_output=True, text=True).stdout
        # The same loop can appear more than once (PoCL replicates the code
        # after a barrier for each path that reaches it): counted as copies.
        loops = collections.Counter()
        for width, lines in vector_loops(ll):
            loops[(width, ", ".join(f"{l} ({n})" for l, n in lines))] += 1
        print(f"Vectorised loops of the work-group function that ran "
              f"({os.path.basename(os.path.dirname(bcs[0]))}; source lines by instruction count):")
        for (width, where), copies in loops.items():
            print(f"  width {width:2d}, {copies} cop{'y' if copies == 1 else 'ies'}: {where}")


if __name__ == "__main__":
    main()
