#!/usr/bin/env python3
"""Plans MPI rendering past this machine (issue 21): predicted parallel
efficiency of `--distribute tiles` and `bands` from 2 to 1024 ranks, driven by
costs measured here, with the measured 2-rank points on the curves.

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
band sets the time. Efficiency = T1 / (P T_P), T1 the one-rank render time
(what `mpi_efficiency.py` measures); start-up is reported apart (it does not
shrink with P: every rank loads and builds the whole scene, which is also the
memory each rank needs: where that exceeds a node's memory only a data-parallel
scheme such as the paper's bands-data can run at all).

  python3 bench/mpi_simulate.py [--scenes balls,gears,mount,tree]
        [--measured results.json of mpi_efficiency.py] [--plot out.png] [-o model.json]
"""
import argparse
import heapq
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def render(binary, scene, rows, size):
    cmd = [binary, "render", f"scenes/spd/{scene}.nff", "--spd", "--size", size, "--backend", "simd", "--threads",
           "1", "--tile-costs", "--tile-rows", str(rows), "--no-progress", "-o", "/dev/null.exr"]
    cmd[-1] = os.path.join("/tmp", f"cellray_sim_{os.getpid()}.exr")
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
            "frame_bytes": fine["width"] * h * 12, "height": h}


def simulate(m, P, mode, latency_ms, gbps):
    rows, tau, h = m["rows"], m["tau_ms"], m["height"]
    gather = m["frame_bytes"] / (gbps * 1e9) * 1e3
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
    ap.add_argument("--measured", help="mpi_efficiency.py's JSON: its 2-rank points are drawn on the curves")
    ap.add_argument("--plot")
    ap.add_argument("-o", "--output")
    a = ap.parse_args()
    ranks = [1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024]
    model = {}
    for scene in a.scenes.split(","):
        m = measure(a.binary, scene, a.size)
        t1 = sum(m["rows"])
        curves = {}
        for mode in ("tiles", "bands"):
            curves[mode] = [t1 / (P * simulate(m, P, mode, a.latency_us * 1e-3, a.gbps)) for P in ranks[1:]]
        model[scene] = {"tau_ms": m["tau_ms"], "t1_ms": t1, "startup_ms": m["startup_ms"], "curves": curves}
        print(f"{scene}: tau {m['tau_ms']:.3f} ms/tile, T1 {t1:.0f} ms, start-up {m['startup_ms']:.0f} ms", file=sys.stderr)
    print("| scene | mode | " + " | ".join(str(P) for P in ranks[1:]) + " |")
    print("|---|---|" + "---|" * (len(ranks) - 1))
    for scene, v in model.items():
        for mode, c in v["curves"].items():
            print(f"| {scene} | {mode} | " + " | ".join(f"{e:.2f}" for e in c) + " |")
    measured = []
    if a.measured:
        measured = json.load(open(a.measured))
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
        for ax, mode in zip(axes, ("tiles", "bands")):
            for i, (scene, v) in enumerate(model.items()):
                line, = ax.plot(ranks[1:], v["curves"][mode], marker=".", label=scene)
                pts = [r for r in measured if r["scene"] == scene and r["mode"] == mode]
                for r in pts:
                    ax.plot([r["ranks"]], [r["efficiency"]], marker="o", markersize=9, markerfacecolor="none",
                            color=line.get_color())
            ax.set_xscale("log", base=2)
            ax.set_title(f"--distribute {mode} (model; circles: measured)")
            ax.set_xlabel("ranks")
            ax.grid(True, alpha=0.3)
        axes[0].set_ylabel("parallel efficiency (render)")
        axes[0].legend()
        fig.tight_layout()
        fig.savefig(a.plot, dpi=110)
    if a.output:
        json.dump(model, open(a.output, "w"), indent=1)


if __name__ == "__main__":
    main()
