#!/usr/bin/env python3
"""Plots of a `cellray bench` run, read from DIR/results.json, written as PNG
and SVG to DIR/plots/ (or --out):

  speed_vs_error  per configuration: speed (x, geometric mean of the median
                  Mrays/s over every scene and ray kind) against error (y:
                  wrong-answer rate, mean relative t error), the Pareto front
                  marked; with the hard-case suite's wrong counts when
                  `cellray bench --hard` has run (docs/HARD_CASES.md)
  images          samples per pixel against image error (PSNR against a
                  high-spp fp64 reference render), and render speed against
                  error with its Pareto front
  speed_bars      Mrays/s per scene, grouped bars per structure x backend
                  (robust) beside Embree, one panel per ray kind
  scaling         build time, memory and time per ray against scene size
                  (`cellray bench --scaling`), the stadium case marked

usage: python3 bench/plot.py DIR [--out PLOTDIR]
"""
import argparse
import json
import math
import os
import sys
from collections import OrderedDict, defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

KINDS = ["primary", "shadow", "diffuse", "random"]


def save(fig, out, name):
    os.makedirs(out, exist_ok=True)
    for ext in ("png", "svg"):
        fig.savefig(os.path.join(out, f"{name}.{ext}"), dpi=110, bbox_inches="tight")
    plt.close(fig)
    print(f"plot.py: {os.path.join(out, name)}.png/.svg", file=sys.stderr)


def mrays(row):
    m = row.get("mrays_per_s")
    return m["median"] if isinstance(m, dict) else None


def is_ours_robust(row):
    return row["backend"] not in ("embree", "reference") and row["precision"] == "robust"


def pareto(points):
    """Indices of the points no other point beats on both speed (higher) and
    error (lower)."""
    front = []
    for i, (x, y) in enumerate(points):
        if not any((x2 >= x and y2 <= y) and (x2 > x or y2 < y) for j, (x2, y2) in enumerate(points) if j != i):
            front.append(i)
    return sorted(front, key=lambda i: points[i][0])


def per_config(rows):
    acc = OrderedDict()
    for r in rows:
        m = mrays(r)
        if m is None or m <= 0 or not isinstance(r.get("error"), dict):
            continue
        a = acc.setdefault(r["label"], {"logs": [], "wrong": 0, "rays": 0, "relw": 0.0, "w": 0.0, "row": r})
        a["logs"].append(math.log(m))
        a["wrong"] += r["error"]["wrong"]
        a["rays"] += r["rays"]
        a["relw"] += r["error"]["mean_rel_t_err"] * r["error"]["agree"]
        a["w"] += r["error"]["agree"]
    out = []
    for label, a in acc.items():
        out.append({
            "label": label,
            "speed": math.exp(sum(a["logs"]) / len(a["logs"])),
            "wrong_rate": a["wrong"] / a["rays"] if a["rays"] else 0.0,
            "rel": a["relw"] / a["w"] if a["w"] else 0.0,
            "backend": a["row"]["backend"],
            "accel": a["row"]["accel"],
            "precision": a["row"]["precision"],
        })
    return out


COLORS = {"simd": "tab:blue", "scalar": "tab:green", "opencl": "tab:orange", "embree": "tab:red",
          "reference": "tab:gray"}
MARKERS = {"robust": "o", "fast": "v", "fp64": "s", "embree": "D"}


def label_points(ax, xs, ys, labels):
    """Annotates points with slanted labels, stacking the labels of points
    that nearly coincide (within 15% in x, 5% in y) instead of overprinting."""
    placed = []
    for x, y, text in sorted(zip(xs, ys, labels), key=lambda t: (t[1], t[0])):
        k = sum(1 for (px, py) in placed
                if abs(math.log10(x / px)) < 0.06 and abs(math.log10(y / py)) < 0.02)
        placed.append((x, y))
        ax.annotate(text, (x, y), fontsize=6, xytext=(3, 3 + 7 * k), textcoords="offset points", rotation=35,
                    rotation_mode="anchor")


def scatter_front(ax, pts, key, ylabel, floor, title):
    xs = [p["speed"] for p in pts]
    ys = [max(p[key], floor) for p in pts]
    for p, x, y in zip(pts, xs, ys):
        ax.scatter(x, y, color=COLORS.get(p["backend"], "k"), marker=MARKERS.get(p["precision"], "o"), s=36,
                   zorder=3)
    label_points(ax, xs, ys, [p["label"] for p in pts])
    front = pareto(list(zip(xs, ys)))
    if front:
        fx = [xs[i] for i in front]
        fy = [ys[i] for i in front]
        ax.step(fx, fy, where="post", color="k", lw=1, ls="--", zorder=2, label="Pareto front")
        ax.scatter(fx, fy, facecolors="none", edgecolors="k", s=110, zorder=4)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("speed: Mrays/s (geometric mean over scenes and ray kinds)")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")


def plot_speed_vs_error(res, out):
    rows = res.get("rows", [])
    pts = per_config(rows)
    if not pts:
        return
    hard = res.get("hard")
    n = 3 if hard else 2
    fig, axes = plt.subplots(1, n, figsize=(6.2 * n, 5.2))
    floor_w = 1e-7
    scatter_front(axes[0], pts, "wrong_rate", f"wrong answers / rays (0 drawn at {floor_w:g})", floor_w,
                  "speed against wrong answers (check: fp64 reference)")
    scatter_front(axes[1], pts, "rel", "mean relative t error of agreeing hits", 1e-12,
                  "speed against distance error")
    if hard:
        wrong = defaultdict(int)
        for h in hard.get("results", []):
            wrong[(h["backend"], h["accel"], h["precision"])] += h["wrong"]
        hp = []
        for p in pts:
            key = (p["backend"], p["accel"], p["precision"])
            if key in wrong:
                q = dict(p)
                q["hard"] = wrong[key]
                hp.append(q)
        if hp:
            scatter_front(axes[2], hp, "hard", "wrong rays on the hard cases (0 drawn at 0.5)", 0.5,
                          "speed against the hard cases (docs/HARD_CASES.md)")
        else:
            axes[2].axis("off")
    fig.suptitle("cellray: speed against error (markers: o robust, v fast, s fp64, D Embree; colour: backend)\n"
                 "hard-case table: docs/HARD_CASES.md, from `cellray bench --hard`", fontsize=9)
    save(fig, out, "speed_vs_error")


def plot_images(res, out):
    images = [r for r in res.get("images", []) if r.get("render_ms", 0) > 0]
    if not images:
        return
    fig, (a, same, b) = plt.subplots(1, 3, figsize=(18, 4.8))
    by = OrderedDict()
    for r in images:
        by.setdefault(r["label"], []).append(r)
    for label, rs in by.items():
        rs = sorted(rs, key=lambda r: r["spp"])
        c = COLORS.get(rs[0]["backend"], "k")
        m = MARKERS.get(rs[0]["precision"], "o")
        a.plot([r["spp"] for r in rs], [r["psnr"] for r in rs], marker=m, color=c, label=label, alpha=0.8)
    a.set_xscale("log", base=2)
    a.set_xlabel("samples per pixel")
    a.set_ylabel("PSNR (dB) against the high-spp fp64 reference render")
    a.set_title(f"{images[0]['scene']} {images[0]['width']}x{images[0]['height']}: spp against image error",
                fontsize=9)
    a.grid(True, alpha=0.3)
    a.legend(fontsize=7)
    # Arithmetic alone: against the reference's render at the same spp and
    # seed; identical images (infinite PSNR) drawn at the top.
    cap = 100.0
    for label, rs in by.items():
        rs = sorted(rs, key=lambda r: r["spp"])
        ys = [r["psnr_same_spp"] if r.get("psnr_same_spp") is not None else cap for r in rs]
        same.plot([r["spp"] for r in rs], ys, marker=MARKERS.get(rs[0]["precision"], "o"),
               color=COLORS.get(rs[0]["backend"], "k"), label=label, alpha=0.8)
    same.set_xscale("log", base=2)
    same.set_xlabel("samples per pixel")
    same.set_ylabel(f"PSNR (dB) against the fp64 render at the same spp ({cap:g}: identical)")
    same.set_title("arithmetic alone: same samples, fp64 reference", fontsize=9)
    same.grid(True, alpha=0.3)
    same.legend(fontsize=7)
    xs = [1e3 / r["render_ms"] for r in images]
    ys = [r["mean_error"] for r in images]
    for r, x, y in zip(images, xs, ys):
        b.scatter(x, y, color=COLORS.get(r["backend"], "k"), marker=MARKERS.get(r["precision"], "o"))
    label_points(b, xs, ys, [f"{r['label']} {r['spp']}spp" for r in images])
    front = pareto(list(zip(xs, ys)))
    b.scatter([xs[i] for i in front], [ys[i] for i in front], facecolors="none", edgecolors="k", s=110,
              label="Pareto front (render time, error)")
    b.set_yscale("log")
    b.set_xscale("log")
    b.set_xlabel("speed: renders per second")
    b.set_ylabel("mean absolute error against the reference render")
    b.set_title("render speed against image error", fontsize=9)
    b.grid(True, which="both", alpha=0.3)
    b.legend(fontsize=7)
    fig.subplots_adjust(wspace=0.32)
    save(fig, out, "images")


def plot_speed_bars(res, out):
    rows = [r for r in res.get("rows", []) if mrays(r) and (is_ours_robust(r) or r["backend"] == "embree")]
    if not rows:
        return
    labels = list(OrderedDict.fromkeys(r["label"] for r in rows))
    scenes = list(OrderedDict.fromkeys(r["scene"] for r in rows))
    kinds = [k for k in KINDS if any(r["kind"] == k for r in rows)]
    cmap = plt.get_cmap("tab20")
    fig, axes = plt.subplots(len(kinds), 1, figsize=(max(10, 1.0 * len(scenes) * len(labels) / 6), 3.2 * len(kinds)),
                             squeeze=False)
    width = 0.8 / len(labels)
    for ax, kind in zip(axes[:, 0], kinds):
        val = {(r["scene"], r["label"]): mrays(r) for r in rows if r["kind"] == kind}
        for li, label in enumerate(labels):
            xs, hs = [], []
            for si, s in enumerate(scenes):
                v = val.get((s, label))
                if v:
                    xs.append(si + (li - (len(labels) - 1) / 2) * width)
                    hs.append(v)
            hatch = "//" if label.startswith("embree") else None
            ax.bar(xs, hs, width=width, label=label, color=cmap(li % 20), hatch=hatch,
                   edgecolor="k" if hatch else None, linewidth=0.3)
        ax.set_xticks(range(len(scenes)))
        ax.set_xticklabels(scenes, fontsize=8)
        ax.set_yscale("log")
        ax.set_ylabel("Mrays/s (median)")
        ax.set_title(f"{kind} rays", fontsize=9)
        ax.grid(True, axis="y", which="both", alpha=0.3)
    axes[0, 0].legend(fontsize=7, ncol=min(6, len(labels)), loc="lower left", bbox_to_anchor=(0, 1.12))
    fig.suptitle("Mrays/s per scene: our structures x backends (robust) and Embree (hatched)", fontsize=10, y=1.0)
    save(fig, out, "speed_bars")


def plot_scaling(res, out):
    sc = res.get("scaling")
    if not sc or not sc.get("rows"):
        return
    rows = sc["rows"]
    # A scene's family: sphereflake-7 -> sphereflake, subdiv-bunny-1000000 -> subdiv-bunny.
    fam = lambda s: s.rsplit("-", 1)[0] if s.startswith("subdiv-") else s.split("-")[0]  # noqa: E731
    labels = list(OrderedDict.fromkeys(r["label"] for r in rows))
    cmap = plt.get_cmap("tab10")
    fig, axes = plt.subplots(2, 2, figsize=(12, 9))
    panels = [
        (axes[0, 0], "build time (ms)", lambda r: r.get("build_ms"), None),
        (axes[0, 1], "structure memory (MiB)", lambda r: r.get("bytes", 0) / 2**20, None),
        (axes[1, 0], "primary rays: ns per ray", lambda r: 1e3 / mrays(r) if mrays(r) else None, "primary"),
        (axes[1, 1], "diffuse rays: ns per ray", lambda r: 1e3 / mrays(r) if mrays(r) else None, "diffuse"),
    ]
    styles = {"sphereflake": "-", "bumpy": "--", "subdiv-bunny": ":", "subdiv-sponza": "-."}
    for ax, title, value, kind in panels:
        for li, label in enumerate(labels):
            for family, ls in styles.items():
                pts = {}
                for r in rows:
                    if r["label"] != label or fam(r["scene"]) != family or (kind and r["kind"] != kind):
                        continue
                    v = value(r)
                    if v:
                        pts[r["pieces"]] = v
                if pts:
                    xs = sorted(pts)
                    ax.plot(xs, [pts[x] for x in xs], ls=ls, marker="o", ms=3, color=cmap(li),
                            label=f"{label} ({family})")
            st = [r for r in rows if r["label"] == label and fam(r["scene"]) == "stadium" and
                  (not kind or r["kind"] == kind)]
            for r in st[:1]:
                v = value(r)
                if v:
                    ax.scatter([r["pieces"]], [v], marker="*", s=160, color=cmap(li), edgecolors="k", zorder=5,
                               label=f"{label} (teapot in a stadium)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("primitives")
        ax.set_title(title, fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    axes[0, 0].legend(fontsize=6, ncol=2)
    fig.suptitle("cost growth with scene size (sphereflake: solid, bumpy sphere: dashed, subdivided bunny: "
                 "dotted, subdivided sponza: dash-dot, stadium: star)", fontsize=10)
    fig.subplots_adjust(hspace=0.3)
    save(fig, out, "scaling")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dir", help="output directory of cellray bench (holds results.json)")
    ap.add_argument("--out", help="where to write the plots (default DIR/plots)")
    a = ap.parse_args()
    path = os.path.join(a.dir, "results.json")
    try:
        with open(path) as f:
            res = json.load(f)
    except (OSError, ValueError) as e:
        print(f"plot.py: cannot read {path}: {e}", file=sys.stderr)
        return 2
    out = a.out or os.path.join(a.dir, "plots")
    plot_speed_vs_error(res, out)
    plot_images(res, out)
    plot_speed_bars(res, out)
    plot_scaling(res, out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
