#!/usr/bin/env python3
"""Parallel efficiency of `cellray render` under MPI (issue 21).

For each scene and distribution mode: one rank x T threads against N ranks x
T threads (mpirun, oversubscribed if need be), the same image (checked bit
for bit), and efficiency = t1 / (N tN), from the render's own time (rank 0's
JSON: the slowest rank's wall time from its first tile to the assembled
frame) and from the whole job's wall time (process start to exit, scene
loading and structure building included: every rank builds its own).

  python3 bench/mpi_efficiency.py [--ranks 2] [--threads 1] [--size 256x256]
        [--scenes balls,gears,...|path.obj] [--modes tiles,bands,bands-data] [-o results.json]

Prints a Markdown table; with bands-data, a second one: the hypercube
paper's heuristic measured (per band: the share of its rays that left the
band, rays it passed on, bytes per ray, the pieces its structure holds, its
structure's bytes and peak memory). Writes the figures as JSON with -o.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SPD = ["balls", "gears", "mount", "rings", "teapot", "tetra", "tree"]


def run(cmd):
    t0 = time.perf_counter()
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        sys.exit(f"mpi_efficiency: {' '.join(cmd)} failed ({p.returncode}):\n{p.stderr}")
    return json.loads(p.stdout.strip().splitlines()[-1]), wall


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", default=os.path.join(ROOT, "build", "release", "bin", "cellray"))
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--size", default="256x256")
    ap.add_argument("--scenes", default=",".join(SPD))
    ap.add_argument("--modes", default="tiles,bands")
    ap.add_argument("--tile-rows", type=int, default=64)
    ap.add_argument("--backend", default="simd")
    ap.add_argument("-o", "--output")
    a = ap.parse_args()
    mpirun = ["mpirun", "-np", str(a.ranks), "--oversubscribe", "--bind-to", "none"]
    if os.geteuid() == 0:
        mpirun.append("--allow-run-as-root")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for scene in a.scenes.split(","):
            path = scene if os.path.exists(scene) else f"scenes/spd/{scene}.nff"
            base = [a.binary, "render", path] + (["--spd"] if path.endswith(".nff") else []) + ["--size", a.size, "--backend", a.backend,
                    "--threads", str(a.threads), "--no-progress"]
            one_img = os.path.join(tmp, "one.exr")
            one, one_wall = run(base + ["-o", one_img])
            t1 = one["stats"]["total_ms"]
            # One rank rendering the same tiles in turn: the efficiency of the
            # distribution itself, apart from what the tile size does to speed.
            tiled, _ = run(base + ["--tile-costs", "--tile-rows", str(a.tile_rows), "-o", os.path.join(tmp, "tiled.exr")])
            t1_tiled = tiled["mpi"]["wall_ms"]
            for mode in a.modes.split(","):
                img = os.path.join(tmp, f"{mode}.exr")
                out, wall = run(mpirun + base + ["--distribute", mode, "--tile-rows", str(a.tile_rows), "-o", img])
                same = open(one_img, "rb").read() == open(img, "rb").read()
                m = out["mpi"]
                tn = m["wall_ms"]
                rows.append({"scene": scene, "mode": mode, "ranks": a.ranks, "threads": a.threads,
                             "t1_ms": t1, "tn_ms": tn, "efficiency": t1 / (a.ranks * tn),
                             "t1_tiled_ms": t1_tiled, "efficiency_vs_tiled": t1_tiled / (a.ranks * tn),
                             "job_t1_s": one_wall, "job_tn_s": wall, "job_efficiency": one_wall / (a.ranks * wall),
                             "busy_ms": [r["busy_ms"] for r in m["per_rank"]],
                             "idle_ms": [r["idle_ms"] for r in m["per_rank"]],
                             "bands": [r["bands"] for r in m["per_rank"]],
                             "bytes": m["bytes_sent"], "messages": m["messages_sent"],
                             "peak_rss_mib": [r["peak_rss_mib"] for r in m["per_rank"]],
                             "bit_identical": same})
                if mode == "bands-data":
                    rows[-1]["bands_data"] = [r["bands_data"] for r in m["per_rank"]]
                r = rows[-1]
                print(f"{scene} {mode}: {r['efficiency']:.3f} (job {r['job_efficiency']:.3f}) identical={same}",
                      file=sys.stderr)
    print(f"| scene | mode | 1 rank ms | {a.ranks} ranks ms | efficiency | vs 1 rank tiled | job efficiency "
          f"| busy ms per rank | idle ms per rank | tiles per rank | bytes | messages | bit-identical |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['scene']} | {r['mode']} | {r['t1_ms']:.0f} | {r['tn_ms']:.0f} | **{r['efficiency']:.3f}** | "
              f"{r['efficiency_vs_tiled']:.3f} | "
              f"{r['job_efficiency']:.3f} | {', '.join(f'{b:.0f}' for b in r['busy_ms'])} | "
              f"{', '.join(f'{b:.0f}' for b in r['idle_ms'])} | {', '.join(str(b) for b in r['bands'])} | "
              f"{r['bytes']} | {r['messages']} | {'yes' if r['bit_identical'] else 'NO'} |")
    bd = [r for r in rows if "bands_data" in r]
    if bd:
        print()
        print("| scene | band | own rays | left band (rays) | left band (shadow) | passed on | received "
              "| bytes per own ray | pieces held | structure KiB | peak MiB |")
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        for r in bd:
            per = r["bands_data"]
            own_all = sum(b["own_rays"] + b["own_shadow_rays"] for b in per)
            for k, b in enumerate(per):
                own, sh = b["own_rays"], b["own_shadow_rays"]
                print(f"| {r['scene']} | {k} | {own + sh} | {100.0 * b['left_rays'] / max(own, 1):.1f}% | "
                      f"{100.0 * b['left_shadow_rays'] / max(sh, 1):.1f}% | {b['forwarded']} | {b['received']} | "
                      f"{r['bytes'] / max(own_all, 1):.1f} | {b['local_pieces']} of {b['total_pieces']} | "
                      f"{b['structure_bytes'] / 1024:.0f} | {r['peak_rss_mib'][k]:.0f} |")
    if a.output:
        with open(a.output, "w") as f:
            json.dump(rows, f, indent=2)
    if not all(r["bit_identical"] for r in rows):
        sys.exit("mpi_efficiency: an image differs from the single-process render")


if __name__ == "__main__":
    main()
