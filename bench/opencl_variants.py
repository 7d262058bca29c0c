#!/usr/bin/env python3
"""OpenCL per-ray versus packet traversal: Mrays/s of every structure on a few
scenes, for primary rays read from a .rays file, primary rays generated on
the device (trace --primary), and shadow rays (occlusion). Prints a Markdown
table; docs/OPENCL.md holds its output and the command that produced it.

  bench/opencl_variants.py [--scenes balls,gears,teapot,tree] [--accels grid,octree,bvh]
                           [--kinds primary,device,shadow] [--variants ray,packet]
                           [--size 512] [--repeat 5] [--rounds 2] [--device N]
                           [--bin build/release/bin/cellray] [--json]

Each figure is `cellray trace --repeat R` (the median of R timed traces, after
an untimed first launch) and the best such median over --rounds rounds of the
whole matrix: on a shared machine other processes only ever add time, and
the rounds spread a burst of load over different cells. Every answer is
checked against the fp64 reference (a wrong answer aborts: timing a wrong
tracer is meaningless). The load averages at the start and the end are
printed with the table: figures taken under load are not comparable with
figures taken on an idle machine.
"""
import argparse
import datetime
import json
import os
import sys
import tempfile

from benchlib import ROOT, run

KIND_LABEL = {"primary": "primary (.rays)", "device": "primary (device)", "shadow": "shadow"}


def load():
    return "{:.2f} {:.2f} {:.2f}".format(*os.getloadavg())


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default="balls,gears,teapot,tree")
    ap.add_argument("--accels", default="grid,octree,bvh")
    ap.add_argument("--kinds", default="primary,device,shadow")
    ap.add_argument("--variants", default="ray,packet", help="--variant values, e.g. ray,packet,packet:8x8")
    ap.add_argument("--size", type=int, default=512, help="primary rays: size x size; shadow rays: as many")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--device", default="")
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "release", "bin", "cellray"))
    ap.add_argument("--json", action="store_true", help="also print one JSON line per trace on stderr")
    a = ap.parse_args()
    scenes = a.scenes.split(",")
    accels = a.accels.split(",")
    kinds = a.kinds.split(",")
    variants = a.variants.split(",")
    for k in kinds:
        if k not in KIND_LABEL:
            raise SystemExit(f"opencl_variants: unknown kind '{k}' (primary, device, shadow)")
    if not os.access(a.bin, os.X_OK):
        raise SystemExit(f"opencl_variants: no cellray binary at {a.bin} (build first or pass --bin)")

    loadStart = load()
    best = {}  # (scene, kind, accel, variant) -> Mrays/s
    names = {}  # variant -> what ran (precision, variant, tile)
    device = ""
    with tempfile.TemporaryDirectory() as work:
        paths = {}
        for s in scenes:
            scene = s if os.path.exists(s) else os.path.join(ROOT, "scenes", "spd", s + ".nff")
            prim = os.path.join(work, s + ".primary.rays")
            run([a.bin, "rays", scene, "--kind", "primary", "--size", f"{a.size}x{a.size}", "-o", prim])
            paths[s] = {"scene": scene, "primary": prim, "device": prim}
            if "shadow" in kinds:
                sh = os.path.join(work, s + ".shadow.rays")
                run([a.bin, "rays", scene, "--kind", "shadow", "--count", str(a.size * a.size), "-o", sh])
                paths[s]["shadow"] = sh
        hits = os.path.join(work, "hits")
        for r in range(a.rounds):
            for s in scenes:
                for kind in kinds:
                    for accel in accels:
                        for v in variants:
                            p = paths[s]
                            cmd = [a.bin, "trace", p["scene"], "--accel", accel, "--backend", "opencl",
                                   "--variant", v, "--repeat", str(a.repeat), "-o", hits]
                            if a.device:
                                cmd += ["--device", a.device]
                            cmd += ["--primary", f"{a.size}x{a.size}"] if kind == "device" else ["--rays", p[kind]]
                            occ = ["--occlusion"] if kind == "shadow" else []
                            out = run(cmd + occ)
                            # Device rays are the host's primary rays (bit-equal with fp64; the check
                            # adjudicates each answer against the ray it was given either way).
                            chk = run([a.bin, "check", p["scene"], "--rays", p[kind], "--hits", hits] + occ)
                            if chk["wrong"] != 0:
                                raise SystemExit(f"opencl_variants: {s} {kind} {accel} {v}: {chk['wrong']} wrong")
                            key = (s, kind, accel, v)
                            best[key] = max(best.get(key, 0.0), out["mrays_per_s"])
                            names[v] = out["variant"]
                            device = out["device"]
                            if a.json:
                                sys.stderr.write(json.dumps({"round": r, "scene": s, "kind": kind, **out}) + "\n")
                sys.stderr.write(f"opencl_variants: round {r + 1}/{a.rounds} {s} done (load {load()})\n")

    print(f"OpenCL device: {device}; {a.size}x{a.size} rays per set; best over {a.rounds} rounds of the median "
          f"of {a.repeat} traces; load average (1, 5, 15 min) {loadStart} at the start, {load()} at the end; "
          f"{datetime.date.today().isoformat()}.")
    print("Variants: " + "; ".join(f"`{v}` = {names.get(v, '?')}" for v in variants) + ".")
    print()
    head = "| scene | rays | structure | " + " | ".join(f"{v} Mrays/s" for v in variants)
    head += "".join(f" | {v} / {variants[0]}" for v in variants[1:]) + " |"
    print(head)
    print("|" + "---|" * (3 + len(variants) + len(variants) - 1))
    for s in scenes:
        for kind in kinds:
            for accel in accels:
                vals = [best[(s, kind, accel, v)] for v in variants]
                row = f"| {s} | {KIND_LABEL[kind]} | {accel} | " + " | ".join(f"{x:.2f}" for x in vals)
                row += "".join(f" | {x / vals[0]:.2f}" for x in vals[1:]) + " |"
                print(row)


if __name__ == "__main__":
    main()
