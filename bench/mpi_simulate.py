#!/usr/bin/env python3
"""Plans MPI rendering past this machine (issue 21): predicted parallel
efficiency of `--distribute tiles`, `bands` and `bands-data` from 2 to 1024
ranks, driven by costs measured here, with the measured 2-rank points on the
curves, and the memory a bands-data rank needs against a replicated scene.

Measured here (one process, one thread, `render --tile-costs`):
  - each image row's cost c_y (tiles of 8 rows, their time spread over their rows),
  - the fixed cost of a tile tau (the time of the same image in 4-row tiles less
    in 32-row tiles, per extra tile: small batches trace less efficiently),
  - each rank's start-up (scene load + structure build) and the frame's bytes.
Assumed (flags): the latency of a tile request over the network (--latency-us,
default 20), the bandwidth into rank 0 (--gbps, default 1 GB/s).

Model. tiles: the rows in tiles of R = clamp(H / (8 P), 1, 32) rows; each rank
takes the next tile when it is free (list scheduling, as the shared counter
does), paying tau + latency per tile; the frame's rows then go to rank 0.
bands: rank r renders rows [r H / P, (r + 1) H / P) plus one tau; the slowest
band sets the time.
bands-data: the counts of `render --band-plan 2,4,...,1024` (one process: for
each P, the rays each band's wedge would trace, pass on and answer, and the
pieces it would hold). Rank r's time = its rows' shading (their row cost less
the single process's share of tracing) + the rays it traces x the cost of a
ray visit (measured: --visit-us, default: the per-visit time of the measured
2-rank bands-data runs, routing included) + the bytes it sends (80 per ray
passed on, 20 per answer) over the bandwidth + one latency per round and
hop. The slowest rank sets the time. This is the scheme with asynchronous
passing; our implementation's collective rounds (host/mpi/band_tracer.h) sit
below it (the measured points). Memory: the largest share of the pieces any
rank holds (1 for tiles and bands, which replicate the scene). Efficiency = T1 / (P T_P), T1 the one-rank render time
(what `mpi_efficiency.py` measures); start-up is reported apart (it does not
shrink with P: every rank loads and builds the whole scene, which is also the
memory each rank needs: where that exceeds a node's memory only a data-parallel
scheme such as the paper's bands-data can run at all).

  python3 bench/mpi_simulate.py [--scenes balls,gears,mount,tree,path/to/mesh.obj]
        [--measured results.json of mpi_efficiency.py ...] [--plot out.png] [-o model.json]
"""
import argparse
import heapq
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def scene_path(scene):
    return scene if os.path.exists(os.path.join(ROOT, scene)) or os.path.isabs(scene) else f"scenes/spd/{scene}.nff"


def render(binary, scene, rows, size):
    path = scene_path(scene)
    cmd = [binary, "render", path] + (["--spd"] if path.endswith(".nff") else []) + [
        "--size", size, "--backend", "simd", "--threads", "1", "--tile-costs", "--tile-rows", str(rows),
        "--no-progress", "-o", os.path.join("/tmp", f"cellray_sim_{os.getpid()}.exr")]
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"mpi_simulate: {' '.join(cmd)} failed:\n{p.stderr}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def measure(binary, scene, size):
    fine = render(binary, scene, 8, size)
    h = fine["height"]
    row = [0.0] * h
    for y0, y1, ms in fine["mpi"]["tiles"]:
        for y in range(int(y0), int(y1)):
            row[y] = ms / (y1 - y0)
    t4 = render(binary, scene, 4, size)["mpi"]["wall_ms"]
    t32 = render(binary, scene, 32, size)["mpi"]["wall_ms"]
    tau = max(0.0, (t4 - t32) / (h / 4 - h / 32))
    return {"rows": row, "tau_ms": tau, "t1_ms": t32, "startup_ms": fine["load_ms"] + fine["build_ms"],
            "frame_bytes": fine["width"] * h * 12, "height": h,
            "trace_share": fine["stats"]["trace_ms"] / max(fine["stats"]["total_ms"], 1e-9)}


def band_plan(binary, scene, size, ranks):
    cmd = [binary, "render", scene_path(scene), "--size", size, "--backend", "simd", "--threads", "1",
           "--band-plan", ",".join(str(P) for P in ranks), "--no-progress",
           "-o", os.path.join("/tmp", f"cellray_plan_{os.getpid()}.exr")] + (["--spd"] if scene_path(scene).endswith(".nff") else [])
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"mpi_simulate: {' '.join(cmd)} failed:\n{p.stderr}")
    j = json.loads(p.stdout.strip().splitlines()[-1])
    st = j["stats"]
    rays = st["eye_rays"] + st["reflection_rays"] + st["refraction_rays"] + st["shadow_rays"]
    return {P["ranks"]: P for P in j["band_plan"]}, rays


def simulate(m, P, mode, latency_ms, gbps, plan=None, visit_ms=0.0):
    rows, tau, h = m["rows"], m["tau_ms"], m["height"]
    gather = m["frame_bytes"] / (gbps * 1e9) * 1e3
    if mode == "bands-data":
        bp = plan[P]
        shade = 1.0 - m["trace_share"]
        hops = bp["trace_calls"] * (bp["max_hops"] + 1)
        span = 0.0
        for r in range(P):
            own = sum(rows[h * r // P:h * (r + 1) // P]) * shade
            sent = 80 * bp["passed"][r] + 20 * bp["returned"][r]
            span = max(span, own + bp["visits"][r] * visit_ms + sent / (gbps * 1e9) * 1e3 + hops * latency_ms)
        return span + gather
    if mode == "bands":
        span = max(sum(rows[h * r // P:h * (r + 1) // P]) + (tau if h * (r + 1) // P > h * r // P else 0.0)
                   for r in range(P))
        return span + gather
    R = max(1, min(32, h // (8 * P)))
    free = [0.0] * P
    heapq.heapify(free)
    for y0 in range(0, h, R):
        t = heapq.heappop(free)
        heapq.heappush(free, t + sum(rows[y0:y0 + R]) + tau + latency_ms)
    return max(free) + gather


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", default=os.path.join(ROOT, "build", "release", "bin", "cellray"))
    ap.add_argument("--scenes", default="balls,gears,mount,tree")
    ap.add_argument("--size", default="512x512")
    ap.add_argument("--latency-us", type=float, default=20.0)
    ap.add_argument("--gbps", type=float, default=1.0)
    ap.add_argument("--measured", action="append", default=[],
                    help="mpi_efficiency.py's JSON (repeatable): its points are drawn on the curves")
    ap.add_argument("--visit-us", type=float, default=0.0,
                    help="bands-data: cost of tracing one ray at one rank, routing included (default: from --measured)")
    ap.add_argument("--plot")
    ap.add_argument("-o", "--output")
    a = ap.parse_args()
    ranks = [1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024]
    measured = []
    for f in a.measured:
        measured += json.load(open(f))
    # The cost of a ray visit in bands-data: the measured ranks' local trace
    # time (tracing and routing) over the rays they traced.
    visit_ms = a.visit_us * 1e-3
    if not visit_ms:
        ms = vis = 0.0
        for r in measured:
            for b in r.get("bands_data", []):
                ms += b["trace_ms"]
                vis += b["own_rays"] + b["own_shadow_rays"] + b["received"]
        visit_ms = ms / vis if vis else 1e-4
    print(f"bands-data: {visit_ms * 1e6:.0f} ns per ray visit", file=sys.stderr)
    model = {}
    modes = ("tiles", "bands", "bands-data")
    for scene in a.scenes.split(","):
        name = os.path.splitext(os.path.basename(scene))[0]
        m = measure(a.binary, scene, a.size)
        plan, _ = band_plan(a.binary, scene, a.size, ranks)  # 1 rank: every piece
        t1 = sum(m["rows"])
        curves = {}
        for mode in modes:
            curves[mode] = [t1 / (P * simulate(m, P, mode, a.latency_us * 1e-3, a.gbps, plan, visit_ms))
                            for P in ranks[1:]]
        pieces = [max(plan[P]["pieces"]) for P in ranks[1:]]
        model[name] = {"tau_ms": m["tau_ms"], "t1_ms": t1, "startup_ms": m["startup_ms"], "curves": curves,
                       "max_pieces_per_rank": pieces, "total_pieces": plan[1]["pieces"][0],
                       "left_share": [sum(plan[P]["passed"]) / max(1, plan[P]["rays"] + plan[P]["shadow_rays"])
                                      for P in ranks[1:]]}
        print(f"{name}: tau {m['tau_ms']:.3f} ms/tile, T1 {t1:.0f} ms, start-up {m['startup_ms']:.0f} ms", file=sys.stderr)
    print("| scene | mode | " + " | ".join(str(P) for P in ranks[1:]) + " |")
    print("|---|---|" + "---|" * (len(ranks) - 1))
    for scene, v in model.items():
        for mode, c in v["curves"].items():
            print(f"| {scene} | {mode} | " + " | ".join(f"{e:.2f}" for e in c) + " |")
        print(f"| {scene} | rays passed on per ray | " + " | ".join(f"{e:.2f}" for e in v["left_share"]) + " |")
        print(f"| {scene} | most pieces on a rank | " + " | ".join(str(e) for e in v["max_pieces_per_rank"]) + " |")
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(1, 4, figsize=(19, 4))
        for ax, mode in zip(axes, modes):
            for i, (scene, v) in enumerate(model.items()):
                line, = ax.plot(ranks[1:], v["curves"][mode], marker=".", label=scene)
                pts = [r for r in measured if os.path.splitext(os.path.basename(r["scene"]))[0] == scene
                       and r["mode"] == mode and r["ranks"] == 2]
                for r in pts:
                    ax.plot([r["ranks"]], [r["efficiency"]], marker="o", markersize=9, markerfacecolor="none",
                            color=line.get_color())
            ax.set_xscale("log", base=2)
            ax.set_ylim(0, 1.4)
            ax.set_title(f"--distribute {mode} (model; circles: measured)", fontsize=9)
            ax.set_xlabel("ranks")
            ax.grid(True, alpha=0.3)
        axes[0].set_ylabel("parallel efficiency (render)")
        axes[0].legend(fontsize=8)
        ax = axes[3]
        for scene, v in model.items():
            ax.plot(ranks[1:], [p / v["total_pieces"] for p in v["max_pieces_per_rank"]], marker=".", label=scene)
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_title("bands-data: largest share of the scene on one rank", fontsize=9)
        ax.set_xlabel("ranks")
        ax.grid(True, alpha=0.3)
        fig.tight_layout()
        fig.savefig(a.plot, dpi=110)
    if a.output:
        json.dump(model, open(a.output, "w"), indent=1)


if __name__ == "__main__":
    main()
