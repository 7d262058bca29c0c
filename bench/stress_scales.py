#!/usr/bin/env python3
"""Random mixed-scale scenes against the fp64 reference: every backend x structure x precision
(robust and fp64 asserted; Embree's robust mode reported), primary, shadow, diffuse and random rays.

  bench/stress_scales.py [--all-types] BIN FIRST_SEED COUNT [OUT_DIR]

Each seed writes OUT_DIR/sSEED.nff: a feature scale S of 1e-4..1e4, the whole scene offset by up to
1e7 S, often a ground sphere of radius 1e3..1e7 S or a ground quad, and 3-25 spheres, triangles,
cones and shared-edge quads of 1e-3..2 S; --all-types adds boxes, polyhedra and quadrics (ellipsoids,
cylinders; only where the offset lets double coefficients hold them) to the mix (other scenes per seed). Prints one line per wrong (backend, structure, precision,
ray kind) and "FAILS n" at the end; exit 1 when n > 0. Found the robust triangle fault of
docs/TOLERANCE.md ("Known fault", seed 3). Not run by ctest (minutes per seed with PoCL compiling)."""
import json, os, random, subprocess, sys

ALL_TYPES = "--all-types" in sys.argv
argv = [a for a in sys.argv[1:] if a != "--all-types"]
if len(argv) < 3:
    sys.exit(__doc__)
BIN = argv[0]; seed0 = int(argv[1]); n = int(argv[2])
OUT = argv[3] if len(argv) > 3 else "stress-out"
os.makedirs(OUT, exist_ok=True)

def scene(rng):
    S = 10 ** rng.choice([-4, -2, 0, 2, 4])      # feature scale
    O = rng.choice([0, 0, 1e2, 1e4, 1e5]) * S * rng.choice([1, 100])  # offset of the whole scene
    ox, oz = O * rng.uniform(-1, 1), O * rng.uniform(-1, 1)
    L = []
    def P(x, y, z): return f"{x + ox:.9g} {y:.9g} {z + oz:.9g}"
    cam = (ox + S * rng.uniform(-8, 8), S * rng.uniform(0.5, 6), oz + S * rng.uniform(-8, 8))
    L += ["v", f"from {cam[0]:.9g} {cam[1]:.9g} {cam[2]:.9g}", f"at {P(0, S * 0.5, 0)}", "up 0 1 0",
          f"angle {rng.choice([20, 40, 70])}", f"hither {S * 1e-3:.6g}", "resolution 64 64", "b 0.2 0.3 0.4"]
    L.append(f"l {P(S * 5, S * 9, S * 3)}")
    if rng.random() < 0.5: L.append(f"l {P(-S * 7, S * 4, S * 6)}")
    L.append("f 0.7 0.7 0.7 0.8 0.1 10 0 0")
    g = rng.random()
    if g < 0.4:   # ground sphere
        R = S * 10 ** rng.uniform(3, 7)
        L.append(f"s {P(0, -R + S * rng.uniform(-1e-3, 1e-3), 0)} {R:.9g}")
    elif g < 0.7:  # ground quad
        W = S * 10 ** rng.uniform(2, 6)
        L += ["p 4", P(-W, 0, -W), P(-W, 0, W), P(W, 0, W), P(W, 0, -W)]
    for _ in range(rng.randint(3, 25)):
        k = rng.random(); x, z = S * rng.uniform(-4, 4), S * rng.uniform(-4, 4)
        sz = S * 10 ** rng.uniform(-3, 0.3)
        y = sz * rng.uniform(-0.2, 1.5)
        if ALL_TYPES and rng.random() < 0.45:
            e = rng.random()
            if e < 0.35:
                L.append(f"box {P(x - sz, y - sz * 0.5, z - sz * rng.uniform(0.01, 1))} {P(x + sz, y + sz * 0.5, z + sz)}")
                continue
            elif e < 0.7:  # a convex polyhedron: 6..10 planes around (x, y, z), in general position
                cx, cy, cz = x + ox, y, z + oz
                planes = []
                for i in range(rng.randint(6, 10)):
                    if i < 6:
                        a = [0.0, 0.0, 0.0]; a[i // 2] = 1.0 if i % 2 == 0 else -1.0
                        a = [a[j] + rng.uniform(-0.3, 0.3) for j in range(3)]
                    else:
                        a = [rng.gauss(0, 1) for _ in range(3)]
                    ln = sum(c * c for c in a) ** 0.5; a = [c / ln for c in a]
                    h = sz * rng.uniform(0.3, 1.0)
                    planes.append(f"{a[0]:.9g} {a[1]:.9g} {a[2]:.9g} {-(a[0] * cx + a[1] * cy + a[2] * cz) - h:.17g}")
                L += [f"polyhedron {len(planes)}"] + planes
                continue
            elif max(abs(ox), abs(oz)) < 1e4 * sz:  # double coefficients hold the shape
                cx, cy, cz = x + ox, y, z + oz
                a, b, c = sz, sz * rng.uniform(0.2, 1.5), sz * rng.uniform(0.2, 1.5)
                if rng.random() < 0.5:  # ellipsoid
                    A, B, C = 1 / a ** 2, 1 / b ** 2, 1 / c ** 2
                    lo, hi = (cx - 2 * a, cy - 2 * b, cz - 2 * c), (cx + 2 * a, cy + 2 * b, cz + 2 * c)
                else:  # a cylinder along y, clipped to a height of 2 b
                    A, B, C = 1 / a ** 2, 0.0, 1 / c ** 2
                    lo, hi = (cx - 2 * a, cy - b, cz - 2 * c), (cx + 2 * a, cy + b, cz + 2 * c)
                J = A * cx * cx + B * cy * cy + C * cz * cz - 1
                L.append(f"quadric {A:.17g} {B:.17g} {C:.17g} 0 0 0 {-2 * A * cx:.17g} {-2 * B * cy:.17g} {-2 * C * cz:.17g} {J:.17g} "
                         + " ".join(f"{v:.9g}" for v in lo + hi))
                continue
        if k < 0.35:
            L.append(f"s {P(x, y, z)} {sz:.9g}")
        elif k < 0.7:
            L.append("p 3")
            for _ in range(3):
                L.append(P(x + sz * rng.uniform(-1, 1), y + sz * rng.uniform(-1, 1), z + sz * rng.uniform(-1, 1)))
        elif k < 0.85:
            L.append(f"c {P(x, y, z)} {sz * rng.uniform(0, 0.5):.9g} {P(x + sz * rng.uniform(-.5, .5), y + sz, z)} {sz * rng.uniform(0, 0.5):.9g}")
        else:  # shared-edge quad (watertightness)
            a = (x, y, z); b = (x + sz, y, z); c = (x + sz, y + sz * rng.uniform(-1, 1), z + sz); d = (x, y, z + sz)
            L += ["p 3", P(*a), P(*b), P(*c), "p 3", P(*a), P(*c), P(*d)]
    return "\n".join(L) + "\n"

def run(args):
    r = subprocess.run([BIN] + args, capture_output=True, text=True)
    return r

fails = 0
for k in range(seed0, seed0 + n):
    rng = random.Random(k)
    nff = f"{OUT}/s{k}.nff"; open(nff, "w").write(scene(rng))
    for kind in ["primary", "shadow", "diffuse", "random"]:
        rays = f"{OUT}/s{k}-{kind}.rays"
        r = run(["rays", nff, "--kind", kind, "--count", "3000", "--seed", str(k), "-o", rays])
        if r.returncode != 0:
            print("RAYS FAIL", k, kind, r.stderr[:200]); continue
        occ = kind == "shadow"
        for be in ["scalar", "simd", "opencl", "embree"]:
            for acc in (["grid", "octree", "bvh", "hgrid"] if be != "embree" else ["bvh"]):
                for prec in (["robust", "fp64"] if be not in ("simd", "embree") else ["robust"]):
                    hits = f"{OUT}/h.hits"
                    a = ["trace", nff, "--rays", rays, "--accel", acc, "--backend", be, "--precision", prec, "-o", hits]
                    if be == "embree": a += ["--variant", "single-robust"]
                    if occ: a.append("--occlusion")
                    r = run(a)
                    if r.returncode != 0:
                        print("TRACE FAIL", k, kind, be, acc, prec, r.stderr[:300]); fails += 1; continue
                    c = run(["check", nff, "--rays", rays, "--hits", hits] + (["--occlusion"] if occ else []))
                    try: j = json.loads(c.stdout)
                    except Exception:
                        print("CHECK FAIL", k, kind, be, acc, prec, c.stderr[:300]); fails += 1; continue
                    if j["wrong"] != 0 and be != "embree":
                        fails += 1
                        print(f"WRONG seed {k} {kind} {be} {acc} {prec}: {j['wrong']} of {j['rays']} first {j['first_wrong'][:3]} why {j['first_wrong_why'][:2]}", flush=True)
                    elif be == "embree" and j["wrong"]:
                        print(f"(embree robust wrong {j['wrong']} seed {k} {kind})")
    print("seed", k, "done", flush=True)
print("FAILS", fails)
sys.exit(1 if fails else 0)
