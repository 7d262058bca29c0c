#!/usr/bin/env python3
"""Writes teapot-stadium.nff: Haines' "teapot in a stadium" taken literally.
The SPD teapot (../spd/teapot.nff: 2256 patches and its checkerboard floor,
about 8 units across, its camera and lights unchanged) stands at the centre
of a ground quad 80,000 units across, 0.05 below its floor, ringed by 64
pillars 320 units square and 3,200 high at 0.9 of the half width: a scene
10^4 times larger than its only detail, where a spatial subdivision must
refine deep around the teapot and nowhere else (docs/BENCHMARKS.md).
Written for cellray; `python3 make_teapot_stadium.py > teapot-stadium.nff`
from this folder."""
import math
import os
import sys

HALF = 40000.0  # half the ground's side
Z = -0.05  # the ground, just below the teapot's floor (z = 0)
PILLARS, PILLAR_HALF, PILLAR_HEIGHT = 64, 160.0, 3200.0


def quad(p):
    return "p 4\n" + "\n".join("%.9g %.9g %.9g" % v for v in p)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    with open(os.path.join(here, "..", "spd", "teapot.nff")) as f:
        teapot = f.read().rstrip("\n")
    out = ["# The SPD teapot in a stadium 10^4 times its size (make_teapot_stadium.py). Written for cellray.",
           teapot, "f 0.4 0.7 0.3 0.9 0 1 0 1",
           quad([(HALF, HALF, Z), (-HALF, HALF, Z), (-HALF, -HALF, Z), (HALF, -HALF, Z)]),
           "f 0.9 0.9 0.9 0.7 0.3 30 0 1"]
    faces = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    for k in range(PILLARS):
        a = 2.0 * math.pi * k / PILLARS
        cx, cy = 0.9 * HALF * math.cos(a), 0.9 * HALF * math.sin(a)
        e = PILLAR_HALF
        p = [(cx - e, cy - e, Z), (cx + e, cy - e, Z), (cx + e, cy + e, Z), (cx - e, cy + e, Z)]
        p += [(x, y, Z + PILLAR_HEIGHT) for (x, y, _) in p]
        out += [quad([p[i] for i in f]) for f in faces]
    sys.stdout.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
