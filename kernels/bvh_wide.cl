/* The BVH's wide walk for CPU devices (--variant wide, CR_BVH_WIDE; OpenCL
 * only): one work-item per ray through the SIMD backend's 8-wide layout
 * (simd/bvh_wide.h: nodes whose 8 child boxes lie structure-of-arrays,
 * leaves of triangle packs of 8), with OpenCL's float8 where the SIMD backend
 * has its vfloat<8> (Wald, Benthin & Boulos 2008; Dammertz et al. 2008). A CPU
 * device such as PoCL does not vectorise the per-ray kernels across
 * work-items (their loops differ per ray), so the per-ray walk's scalar code
 * runs one lane wide; here the child boxes and a pack's edge functions run 8
 * wide in each work-item.
 *
 * Same answers as BVH_Trace: each child's slab test is Box_Slabs lane by lane
 * (the same float operations, no contraction: prelude.h), and a triangle,
 * sphere or cone pack runs its type's test in float8, lane by lane the same
 * float operations as Triangle_Intersect, Sphere_Intersect or
 * Cone_Intersect, up to where that test would refine (double-float edges,
 * planes, discriminants or roots): those lanes take the scalar test itself
 * (Wide_RefineLane), the others are decided in float8; every hit goes
 * through Prim_Intersect's bookkeeping (Wide_Keep, in lane order). The other
 * types' pieces take Prim_Intersect itself; hits are kept in Hit_Closer's
 * order, so the closest hit does not depend on the visiting order. fp64 and moving scenes walk
 * the same layout with the children tested one at a time (double) and no
 * filter (a moving piece meets a shifted ray).
 *
 * Layout, uploaded by host/cl/cl_tracer.cpp (WideUpload): `nodes` are
 * WideNode<8> (64 words: lower[3][8], upper[3][8], child[8], meta[8]);
 * `refs` starts with CR_NUM_PRIM_TYPES + 1 words: where each type's packs
 * start (triangles: TrianglePack<8> of simd/triangle.h, 88 words; spheres:
 * SpherePack<8> of simd/sphere.h, 40 words; every other type: the 8 unified
 * ids of each pack), then where the mixed leaves
 * start (2 words per type each: first pack, packs). A child slot is a node
 * index or CR_WIDE_LEAF | p with its meta word (simd/bvh_wide.h). */
#ifndef CELLRAY_KERNELS_BVH_WIDE_CL
#define CELLRAY_KERNELS_BVH_WIDE_CL
/* Included by bvh.h under CR_BVH_WIDE (the include below is then empty);
 * compiled on its own (the kernel header check), it brings bvh.h in. */
#ifndef CR_BVH_WIDE
#define CR_BVH_WIDE
#endif
#include "bvh.h"

#define CR_WIDE_LEAF 0x80000000u
#define CR_WIDE_MIXED 0xffff0000u
#define CR_WIDE_NODE_WORDS 64
#define CR_WIDE_TRI_WORDS 88
#define CR_WIDE_SPHERE_WORDS 40
#define CR_WIDE_CONE_WORDS 80
/* A triangle pack's flag bits above Triangle.flags' own: the shortest edge
 * (Triangle_PlaneNormal's k: 1 or 2; neither: 0), simd/triangle.h's
 * kPackShortEdge1 and kPackShortEdge2. */
#define CR_WIDE_TRI_SHORT1 0x100u
#define CR_WIDE_TRI_SHORT2 0x200u
/* Each wide level pushes at most 7 entries (simd/bvh_single.h). */
#ifndef CR_WIDE_STACK
#define CR_WIDE_STACK (7 * CR_BVH_STACK + 1)
#endif

#if !defined(CR_FP64) && !CR_HAS_MOTION
#define CR_WIDE_VECTOR 1
#else
#define CR_WIDE_VECTOR 0
#endif

/* The lanes of a float8 comparison as bits. */
CR_FUNC uint Wide_Bits(int8 m)
{
  const int8 w = m & (int8)(1, 2, 4, 8, 16, 32, 64, 128);
  return (uint)(w.s0 | w.s1 | w.s2 | w.s3 | w.s4 | w.s5 | w.s6 | w.s7);
}
CR_FUNC int Wide_Lowest(uint bits) { return 31 - (int)clz(bits & (0u - bits)); }

#ifdef CR_STATS
#define CR_WIDE_COUNT_TESTS(st, n) ((st)->nIT += (n))
#else
#define CR_WIDE_COUNT_TESTS(st, n) ((void)0)
#endif

/* Prim_Intersect's bookkeeping for a test run here on piece g: its hit
 * (t, u, v) kept where Hit_CloserOn says it is closer. */
CR_FUNC int Wide_Keep(const PrimView* pv, const Ray* ray, int found, real t, real u, real v, uint g, Hit* hit)
{
  if (!found || !Hit_CloserOn(pv, ray, t, g, hit)) return 0;
  hit->t = t;
  hit->u = u;
  hit->v = v;
  hit->g = g;
  return 1;
}
/* The lanes of `bits` of a pack's ids `g` by Prim_Intersect (the scene's
 * rows). Returns 1 to stop (an occlusion query has its occluder). */
CR_FUNC int Wide_ByScene(const PrimView* pv, CR_GLOBAL const uint* g, uint bits, const Ray* ray, Hit* hit, int anyHit)
{
  for (; bits; bits &= bits - 1u)
    if (Prim_Intersect(pv, g[Wide_Lowest(bits)], ray, hit) && anyHit) return 1;
  return 0;
}

/* The lanes of a pack whose ids `g` name a piece, counted as tests. */
CR_FUNC uint Wide_PackLanes(CR_GLOBAL const uint* g, TraceStats* st)
{
  const uint bits = Wide_Bits(vload8(0, g) != (uint8)(CR_NO_HIT));
  CR_WIDE_COUNT_TESTS(st, (uint)popcount(bits));
  (void)st;
  return bits;
}

/* A triangle, sphere or cone pack's lanes after its float8 test (type k):
 * `found` hit at (t8, u8, v8), lane by lane; `refine` take Triangle_Intersect
 * or Sphere_Intersect itself on the pack's own copy of their piece (its line
 * is in the cache; the scene's row may not be), or Cone_Intersect on the
 * scene's row. Both in lane order with
 * Prim_Intersect's bookkeeping (Wide_Keep), as a loop of those tests would
 * give: the float8 range test used the hit at the pack's start, and
 * Hit_CloserOn refuses what a nearer lane has since beaten (what the float8
 * path decides does not depend on the range's far end otherwise). Returns 1
 * to stop (an occlusion query has its occluder). */
CR_COLD CR_FUNC int Wide_RefineLane(const PrimView* pv, uint k, CR_GLOBAL const uint* pk, int l, uint g,
                                    const Ray* ray, const Hit* hit, real* t, real* u, real* w)
{
  CR_GLOBAL const float* v = (CR_GLOBAL const float*)pk; /* [vertex][axis][lane]; spheres: [axis][lane], radii */
  if (k == CR_PRIM_CONE) {
    /* The pack holds the cone's derived terms: the scene's row. */
    const Cone cn = pv->cones[Prim_Local(&pv->ranges, CR_PRIM_CONE, g)];
    return Cone_Intersect(ray, &cn, ray->tmin, hit->t, t);
  }
  if (k == CR_PRIM_TRIANGLE) {
    Triangle tri;
    CR_UNROLL for (int a = 0; a < 3; ++a) {
      tri.v0[a] = v[a * 8 + l];
      tri.v1[a] = v[(3 + a) * 8 + l];
      tri.v2[a] = v[(6 + a) * 8 + l];
    }
    tri.flags = pk[80 + l] & CR_TRI_LONG_EDGES;
    tri.pad1 = 0u;
    tri.pad2 = 0u;
    return Triangle_Intersect(ray, &tri, ray->tmin, hit->t, t, u, w);
  }
  Sphere sph;
  CR_UNROLL for (int a = 0; a < 3; ++a) sph.center[a] = v[a * 8 + l];
  sph.radius = v[24 + l];
  return Sphere_Intersect(ray, &sph, ray->tmin, hit->t, t);
}
/* Inlined into each pack test (PoCL would not inline it into three; its
 * call passes three float8 on the stack). */
__attribute__((always_inline)) CR_FUNC int Wide_KeepLanes(const PrimView* pv, const Ray* ray, uint k, uint found, uint refine, CR_GLOBAL const uint* pk,
                           float8 t8, float8 u8, float8 v8, CR_GLOBAL const uint* g, Hit* hit, int anyHit)
{
  uint bits = found | refine;
  if (!bits) return 0;
  float tt[8], uu[8], vv[8];
  vstore8(t8, 0, tt);
  vstore8(u8, 0, uu);
  vstore8(v8, 0, vv);
  for (; bits; bits &= bits - 1u) {
    const int l = Wide_Lowest(bits);
    real t = tt[l], u = uu[l], w = vv[l];
    const int ok = ((refine >> l) & 1u) ? Wide_RefineLane(pv, k, pk, l, g[l], ray, hit, &t, &u, &w) : 1;
    if (Wide_Keep(pv, ray, ok, t, u, w, g[l], hit) && anyHit) return 1;
  }
  return 0;
}

#if CR_WIDE_VECTOR && !defined(CR_FAST)
/* Triangle_Norm1 of each vertex of a pack translated to the ray origin, in
 * the ray's axis order (the scale of its sheared coordinates' rounding):
 * v the pack's [vertex][axis][lane] floats, Az..Cz the translated kz
 * components. */
CR_FUNC void Wide_TriangleNorms(CR_GLOBAL const float* v, int kx, int ky, float8 ox, float8 oy, float8 Az, float8 Bz,
                                float8 Cz, float8* nA, float8* nB, float8* nC)
{
  *nA = (fabs(vload8(0, v + kx * 8) - ox) + fabs(vload8(0, v + ky * 8) - oy)) + fabs(Az);
  *nB = (fabs(vload8(0, v + (3 + kx) * 8) - ox) + fabs(vload8(0, v + (3 + ky) * 8) - oy)) + fabs(Bz);
  *nC = (fabs(vload8(0, v + (6 + kx) * 8) - ox) + fabs(vload8(0, v + (6 + ky) * 8) - oy)) + fabs(Cz);
}
#endif

/* A triangle pack: the lanes that may hit take Prim_Intersect. Returns 1 to
 * stop (an occlusion query has its occluder). */
CR_FUNC int Wide_TrianglePack(const PrimView* pv, CR_GLOBAL const uint* pk, const Ray* ray, Hit* hit, int anyHit,
                              TraceStats* st)
{
  CR_GLOBAL const uint* g = pk + 72;
  uint bits = Wide_PackLanes(g, st);
#if CR_WIDE_VECTOR
  CR_GLOBAL const float* v = (CR_GLOBAL const float*)pk; /* v[vertex][axis][lane] */
#ifdef CR_FAST
  /* Triangle_Intersect's Moller-Trumbore up to its u and v tests. */
  float8 e1[3], e2[3], tv[3], pv3[3], qv[3];
  CR_UNROLL for (int i = 0; i < 3; ++i) {
    const float8 v0 = vload8(0, v + i * 8);
    e1[i] = vload8(0, v + (3 + i) * 8) - v0;
    e2[i] = vload8(0, v + (6 + i) * 8) - v0;
    tv[i] = (float8)(ray->org[i]) - v0;
  }
  const float8 d0 = (float8)(ray->dir[0]), d1 = (float8)(ray->dir[1]), d2 = (float8)(ray->dir[2]);
  pv3[0] = d1 * e2[2] - d2 * e2[1];
  pv3[1] = d2 * e2[0] - d0 * e2[2];
  pv3[2] = d0 * e2[1] - d1 * e2[0];
  const float8 det = e1[0] * pv3[0] + e1[1] * pv3[1] + e1[2] * pv3[2];
  const float8 invDet = (float8)(1.0f) / det;
  const float8 u = (tv[0] * pv3[0] + tv[1] * pv3[1] + tv[2] * pv3[2]) * invDet;
  qv[0] = tv[1] * e1[2] - tv[2] * e1[1];
  qv[1] = tv[2] * e1[0] - tv[0] * e1[2];
  qv[2] = tv[0] * e1[1] - tv[1] * e1[0];
  const float8 vv = (d0 * qv[0] + d1 * qv[1] + d2 * qv[2]) * invDet;
  const int8 miss = (fabs(det) < (float8)(1e-9f)) | (u < (float8)(0.0f)) | (u > (float8)(1.0f)) |
                    (vv < (float8)(0.0f)) | (u + vv > (float8)(1.0f));
  bits &= ~Wide_Bits(miss);
  if (!bits) return 0;
  /* Its t and range test (a NaN t passes there, as here; Hit_CloserOn refuses it). */
  const float8 t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) * invDet;
  const uint found = bits & ~Wide_Bits((t < (float8)(ray->tmin)) | (t > (float8)(hit->t)));
  return Wide_KeepLanes(pv, ray, CR_PRIM_TRIANGLE, found, 0u, pk, t, u, vv, g, hit, anyHit);
#else
  /* Triangle_Intersect's watertight edge functions. */
  const int kx = ray->kx, ky = ray->ky, kz = ray->kz;
  const float8 ox = (float8)(ray->org[kx]), oy = (float8)(ray->org[ky]), oz = (float8)(ray->org[kz]);
  const float8 sx = (float8)(ray->sx), sy = (float8)(ray->sy);
  const float8 Az = vload8(0, v + kz * 8) - oz, Bz = vload8(0, v + (3 + kz) * 8) - oz,
               Cz = vload8(0, v + (6 + kz) * 8) - oz;
  const float8 Ax = (vload8(0, v + kx * 8) - ox) - sx * Az, Ay = (vload8(0, v + ky * 8) - oy) - sy * Az;
  const float8 Bx = (vload8(0, v + (3 + kx) * 8) - ox) - sx * Bz, By = (vload8(0, v + (3 + ky) * 8) - oy) - sy * Bz;
  const float8 Cx = (vload8(0, v + (6 + kx) * 8) - ox) - sx * Cz, Cy = (vload8(0, v + (6 + ky) * 8) - oy) - sy * Cz;
  const float8 U = Cx * By - Cy * Bx, V = Ax * Cy - Ay * Cx, W = Bx * Ay - By * Ax;
  const float8 zero = (float8)(0.0f);
  const int8 miss = (((U < zero) | (V < zero) | (W < zero)) & ((U > zero) | (V > zero) | (W > zero))) |
                    ((U + V + W) == zero);
  /* Triangles with long edges: Triangle_Intersect refines a flagged edge
   * whose float value lies within its rounding bound
   * (Triangle_LongEdgeUndecided, the same float operations here); a lane
   * with no such edge is decided by the float edges above, as there. */
  uint keep = ~Wide_Bits(miss), refine = 0u;
  const uint8 flags = vload8(0, pk + 80);
  const uint8 none = (uint8)(0u);
  if (Wide_Bits((flags & (uint8)(CR_TRI_LONG_EDGES)) != none) & bits & ~keep) {
    float8 nA, nB, nC;
    Wide_TriangleNorms(v, kx, ky, ox, oy, Az, Bz, Cz, &nA, &nB, &nC);
    const float8 k = (float8)(0x1.0p-18f);
    const int8 undecided = (((flags & (uint8)(CR_TRI_LONG_U)) != none) & (fabs(U) <= k * (nB * nC))) |
                           (((flags & (uint8)(CR_TRI_LONG_V)) != none) & (fabs(V) <= k * (nC * nA))) |
                           (((flags & (uint8)(CR_TRI_LONG_W)) != none) & (fabs(W) <= k * (nA * nB)));
    refine = Wide_Bits(undecided);
    keep |= refine;
  }
  bits &= keep;
  if (!bits) return 0;
  /* The rest of Triangle_Intersect for the lanes left, float8 (its
   * operations lane by lane, as simd/triangle.h's Triangle_PlaneKN): t from
   * the plane of the shortest edge and its successor (the pack's flag bits,
   * PackShortEdge) through the vertex they share. Lanes that refine there
   * take Triangle_Intersect itself: a long edge within its rounding (above),
   * the plane inexact with t possibly in range (Triangle_PlaneNeedsDf), or
   * all three edges within their rounding (Triangle_EdgesUndecided). */
  const int8 k1 = (flags & (uint8)(CR_WIDE_TRI_SHORT1)) != none, k2 = (flags & (uint8)(CR_WIDE_TRI_SHORT2)) != none;
  float8 n[3], p[3];
  {
    float8 ea[3], eb[3];
    CR_UNROLL for (int i = 0; i < 3; ++i) {
      const float8 v0 = vload8(0, v + i * 8), v1 = vload8(0, v + (3 + i) * 8), v2 = vload8(0, v + (6 + i) * 8);
      const float8 e0 = v1 - v0, e1 = v2 - v1, e2 = v0 - v2, o = (float8)(ray->org[i]);
      /* k 0: e0, e1, v1; k 1: e1, e2, v2; k 2: e2, e0, v0. */
      ea[i] = select(select(e0, e1, k1), e2, k2);
      eb[i] = select(select(e1, e2, k1), e0, k2);
      p[i] = select(select(v1 - o, v2 - o, k1), v0 - o, k2);
    }
    n[0] = ea[1] * eb[2] - ea[2] * eb[1];
    n[1] = ea[2] * eb[0] - ea[0] * eb[2];
    n[2] = ea[0] * eb[1] - ea[1] * eb[0];
  }
  const float8 nd = n[0] * (float8)(ray->dir[0]) + n[1] * (float8)(ray->dir[1]) + n[2] * (float8)(ray->dir[2]);
  const float8 np0 = n[0] * p[0], np1 = n[1] * p[1], np2 = n[2] * p[2];
  const float8 np = (np0 + np1) + np2, sum = (fabs(np0) + fabs(np1)) + fabs(np2);
  const float8 t = np / nd;
  const float8 tmin = (float8)(ray->tmin), tmax = (float8)(hit->t);
  const float8 an = fabs(nd), tn = t * an, slack = (float8)(0.25f) * fabs(tn) + (float8)(0x1.0p-20f) * sum;
  const int8 nearPlane = (sum > (float8)(16.0f) * fabs(np)) & (tn + slack >= tmin * an) & (tn - slack <= tmax * an);
  float8 nA, nB, nC;
  Wide_TriangleNorms(v, kx, ky, ox, oy, Az, Bz, Cz, &nA, &nB, &nC);
  const float8 k19 = (float8)(0x1.0p-19f);
  const int8 degenerate = (fabs(U) <= k19 * (nB * nC)) & (fabs(V) <= k19 * (nC * nA)) & (fabs(W) <= k19 * (nA * nB));
  const int8 inRange = (t >= tmin) & (t <= tmax) & (nd != zero);
  refine = (refine | Wide_Bits((nearPlane & (nd != zero)) | degenerate)) & bits;
  const float8 invDet = (float8)(1.0f) / (U + V + W);
  return Wide_KeepLanes(pv, ray, CR_PRIM_TRIANGLE, bits & ~refine & Wide_Bits(inRange), refine, pk, t, V * invDet, W * invDet, g, hit,
                        anyHit);
#endif
#else
  return Wide_ByScene(pv, g, bits, ray, hit, anyHit);
#endif
}

/* A sphere pack (centres, radii, ids): the lanes that may hit take
 * Prim_Intersect. Sphere_Intersect's own misses are dropped, from the same
 * float operations: robust, a discriminant below its undecided band or
 * below 0 and decided; fast, the textbook discriminant below 0. */
CR_FUNC int Wide_SpherePack(const PrimView* pv, CR_GLOBAL const uint* pk, const Ray* ray, Hit* hit, int anyHit,
                            TraceStats* st)
{
  CR_GLOBAL const uint* g = pk + 32;
  uint bits = Wide_PackLanes(g, st);
#if CR_WIDE_VECTOR
  CR_GLOBAL const float* c = (CR_GLOBAL const float*)pk; /* center[axis][lane], radius[lane] */
  const float8 f0 = (float8)(ray->org[0]) - vload8(0, c), f1 = (float8)(ray->org[1]) - vload8(0, c + 8),
               f2 = (float8)(ray->org[2]) - vload8(0, c + 16);
  const float8 rad = vload8(0, c + 24);
  const float d0 = ray->dir[0], d1 = ray->dir[1], d2 = ray->dir[2];
  const float a = d0 * d0 + d1 * d1 + d2 * d2;
  const float8 ff = f0 * f0 + f1 * f1 + f2 * f2;
#ifdef CR_FAST
  const float8 bh = f0 * d0 + f1 * d1 + f2 * d2;
  const float8 cq = ff - rad * rad;
  const float8 b = (float8)(2.0f) * bh;
  const float8 disc4 = b * b - (float8)(4.0f * a) * cq;
  bits &= ~Wide_Bits(disc4 < (float8)(0.0f));
  if (!bits) return 0;
  /* The rest of Sphere_Intersect, float8: the roots, then the nearer in range. */
  const float8 sq = sqrt(disc4), a2 = (float8)(2.0f * a);
  const float8 t0 = (-b - sq) / a2, t1 = (-b + sq) / a2;
  const float8 tmin = (float8)(ray->tmin), tmax = (float8)(hit->t);
  const int8 in0 = (t0 >= tmin) & (t0 <= tmax), in1 = (t1 >= tmin) & (t1 <= tmax);
  const uint found = bits & Wide_Bits(in0 | in1);
  const float8 zero = (float8)(0.0f);
  return Wide_KeepLanes(pv, ray, CR_PRIM_SPHERE, found, 0u, pk, select(t1, t0, in0), zero, zero, g, hit, anyHit);
#else
  const float8 cx = f1 * d2 - f2 * d1, cy = f2 * d0 - f0 * d2, cz = f0 * d1 - f1 * d0;
  const float8 ar2 = (a * rad) * rad;
  const float8 cc = cx * cx + cy * cy + cz * cz;
  const float8 disc = ar2 - cc;
  const float8 Q = (float8)(0x1.0p-29f) * (ff * a);
  const int8 undecided = disc * disc <= Q * (cc + (float8)(0x1.0p-9f) * Q);
  const int8 miss = (disc < (float8)(-0x1.0p15f) * Q) | (~undecided & (disc < (float8)(0.0f)));
  bits &= ~Wide_Bits(miss);
  if (!bits) return 0;
  /* The rest of Sphere_Intersect, float8 (its operations lane by lane): the
   * stable roots (Quadratic_Roots), then the nearer in range. Lanes whose
   * answer float may not decide take Sphere_Intersect itself: an undecided
   * discriminant (Sphere_DiscUndecided) or one not >= 0, and every lane where
   * Sphere_NeedsDf looks further (c or the discriminant cancelling: its
   * first test), so what is decided here does not depend on [tmin, tmax]
   * beyond the range test. */
  const float8 bh = f0 * d0 + f1 * d1 + f2 * d2;
  const float8 r2 = rad * rad, cq = ff - r2, cScale = ff + r2;
  const float8 dScale = ar2 + cc, dd = disc * (bh * bh + disc);
  const int8 looks = (cScale > (float8)(8.0f) * fabs(cq)) | (dScale * dScale > (float8)(64.0f) * dd);
  const uint refine = bits & Wide_Bits(undecided | ~(disc >= (float8)(0.0f)) | looks);
  const float8 zero = (float8)(0.0f);
  uint found = 0u;
  float8 t = zero;
  /* Not when only such lanes are left (a ray leaving a sphere's surface
   * meets that sphere so). One call of Wide_KeepLanes below, which PoCL
   * then inlines. */
  if (bits != refine) {
    const float8 sq = copysign(sqrt(disc), bh), q = -(bh + sq);
    const float8 va = (float8)(a);
    const float8 r0 = q / va;
    const int8 stable = (float8)(16.0f) * q * q >= va * cScale;
    const float8 r1 = select(sq - bh, cq, stable) / select(va, q, stable);
    const float8 t0 = fmin(r0, r1), t1 = fmax(r0, r1);
    const float8 tmin = (float8)(ray->tmin), tmax = (float8)(hit->t);
    const int8 in0 = (t0 >= tmin) & (t0 <= tmax), in1 = (t1 >= tmin) & (t1 <= tmax);
    found = bits & ~refine & Wide_Bits(in0 | in1);
    t = select(t1, t0, in0);
  }
  return Wide_KeepLanes(pv, ray, CR_PRIM_SPHERE, found, refine, pk, t, zero, zero, g, hit, anyHit);
#endif
#else
  return Wide_ByScene(pv, g, bits, ray, hit, anyHit);
#endif
}

/* A cone pack (ConePack<8>: base, unit axis w, height H, base radius r0,
 * slope k, ids, each [lane]: Cone_Intersect's ray-independent terms, computed
 * by the host with its float operations): the lanes that may hit take
 * Prim_Intersect. Cone_Intersect's own misses are dropped, from the same
 * float operations: a cone of no height; or a quadratic case (A != 0) whose
 * discriminant is below 0 and, robust, not within its rounding of 0 (the
 * double-float case). */
CR_FUNC int Wide_ConePack(const PrimView* pv, CR_GLOBAL const uint* pk, const Ray* ray, Hit* hit, int anyHit,
                          TraceStats* st)
{
  CR_GLOBAL const uint* g = pk + 72;
  uint bits = Wide_PackLanes(g, st);
#if CR_WIDE_VECTOR
  CR_GLOBAL const float* c = (CR_GLOBAL const float*)pk;
  float8 dl[3], w[3], d[3];
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    dl[a] = (float8)(ray->org[a]) - vload8(0, c + a * 8);
    w[a] = vload8(0, c + 24 + a * 8);
    d[a] = (float8)(ray->dir[a]);
  }
  const float8 H = vload8(0, c + 48), r0 = vload8(0, c + 56), k = vload8(0, c + 64);
  const float8 ds = d[0] * w[0] + d[1] * w[1] + d[2] * w[2];
  const float8 os = dl[0] * w[0] + dl[1] * w[1] + dl[2] * w[2];
  float8 dR[3], oR[3];
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    dR[a] = d[a] - ds * w[a];
    oR[a] = dl[a] - os * w[a];
  }
  const float8 rb = r0 + k * os;
  const float8 A = (dR[0] * dR[0] + dR[1] * dR[1] + dR[2] * dR[2]) - k * k * ds * ds;
  const float8 zero = (float8)(0.0f);
  const float8 oo = oR[0] * oR[0] + oR[1] * oR[1] + oR[2] * oR[2];
  const float8 Bh = (oR[0] * dR[0] + oR[1] * dR[1] + oR[2] * dR[2]) - k * ds * rb;
  const float8 C = oo - rb * rb;
#ifdef CR_FAST
  const float8 disc4 = (float8)(4.0f) * Bh * Bh - (float8)(4.0f) * A * C;
  const int8 quadMiss = disc4 < zero;
#else
  float8 e[3];
  CR_UNROLL for (int a = 0; a < 3; ++a) e[a] = rb * dR[a] - k * ds * oR[a];
  const float8 x0 = oR[1] * dR[2] - oR[2] * dR[1], x1 = oR[2] * dR[0] - oR[0] * dR[2],
               x2 = oR[0] * dR[1] - oR[1] * dR[0];
  const float8 ee = e[0] * e[0] + e[1] * e[1] + e[2] * e[2], xx = x0 * x0 + x1 * x1 + x2 * x2;
  const float8 disc = ee - xx;
  const int8 quadMiss = (disc < zero) & ~(-disc <= (float8)(0x1.0p-20f) * (ee + xx));
#endif
  const int8 miss = ~(H > zero) | ((A != zero) & quadMiss);
  bits &= ~Wide_Bits(miss);
  if (!bits) return 0;
  /* The rest of Cone_Intersect, float8 (its operations lane by lane): the
   * roots, then the nearer in range whose axial position lies in [0, H].
   * Lanes that Cone_Intersect would take further take it itself: A == 0 (a
   * ray along the surface's slope), a discriminant within its rounding of 0
   * or not >= 0, and, robust, every lane where Cone_NeedsDf looks further
   * (its first test: C or the discriminant cancelling, or the origin far
   * along the axis beside its radial distance). */
#ifdef CR_FAST
  uint refine = bits & Wide_Bits((A == zero) | ~(disc4 >= zero));
#else
  const float8 cScale = oo + rb * rb, dScale = ee + xx, d2 = disc * (Bh * Bh + disc);
  const float8 dl2 = dl[0] * dl[0] + dl[1] * dl[1] + dl[2] * dl[2];
  const int8 looks = (cScale > (float8)(8.0f) * fabs(C)) | (dScale * dScale > (float8)(64.0f) * d2) |
                     (dl2 > (float8)(64.0f) * oo);
  uint refine = bits & Wide_Bits((A == zero) | ~(disc >= zero) | looks);
#endif
  uint found = 0u;
  float8 t = zero;
  if (bits != refine) {
#ifdef CR_FAST
    const float8 sq = sqrt(disc4), A2 = (float8)(2.0f) * A, mB2 = (float8)(-2.0f) * Bh;
    const float8 ta = (mB2 - sq) / A2, tb = (mB2 + sq) / A2;
    const float8 t0 = fmin(ta, tb), t1 = fmax(ta, tb);
#else
    const float8 sq = copysign(sqrt(disc), Bh), q = -(Bh + sq);
    const float8 ra = q / A;
    const int8 stable = (float8)(16.0f) * q * q >= A * cScale;
    const float8 rc = select(sq - Bh, C, stable) / select(A, q, stable);
    const float8 t0 = fmin(ra, rc), t1 = fmax(ra, rc);
#endif
    const float8 tmin = (float8)(ray->tmin), tmax = (float8)(hit->t);
    const float8 s0 = os + t0 * ds, s1 = os + t1 * ds;
    const int8 in0 = (t0 >= tmin) & (t0 <= tmax) & (s0 >= zero) & (s0 <= H);
    const int8 in1 = (t1 >= tmin) & (t1 <= tmax) & (s1 >= zero) & (s1 <= H);
    found = bits & ~refine & Wide_Bits(in0 | in1);
    t = select(t1, t0, in0);
  }
  return Wide_KeepLanes(pv, ray, CR_PRIM_CONE, found, refine, pk, t, zero, zero, g, hit, anyHit);
#else
  return Wide_ByScene(pv, g, bits, ray, hit, anyHit);
#endif
}

/* `count` packs of type k from `first`. Returns 1 to stop. */
CR_FUNC int Wide_Packs(const PrimView* pv, CR_GLOBAL const uint* refs, uint k, uint first, uint count, const Ray* ray,
                       Hit* hit, int anyHit, TraceStats* st)
{
  CR_GLOBAL const uint* base = refs + refs[k];
  if (k == CR_PRIM_TRIANGLE) {
    for (uint p = first; p < first + count; ++p)
      if (Wide_TrianglePack(pv, base + (size_t)p * CR_WIDE_TRI_WORDS, ray, hit, anyHit, st)) return 1;
    return 0;
  }
  if (k == CR_PRIM_SPHERE) {
    for (uint p = first; p < first + count; ++p)
      if (Wide_SpherePack(pv, base + (size_t)p * CR_WIDE_SPHERE_WORDS, ray, hit, anyHit, st)) return 1;
    return 0;
  }
  if (k == CR_PRIM_CONE) {
    for (uint p = first; p < first + count; ++p)
      if (Wide_ConePack(pv, base + (size_t)p * CR_WIDE_CONE_WORDS, ray, hit, anyHit, st)) return 1;
    return 0;
  }
  for (uint i = first * 8u; i < (first + count) * 8u; ++i) {
    const uint g = base[i];
    if (g == CR_NO_HIT) continue;
    CR_COUNT(st, nIT);
    if (Prim_Intersect(pv, g, ray, hit) && anyHit) return 1;
  }
  return 0;
}

/* A leaf slot: p without the leaf flag, meta its meta word. Returns 1 to stop. */
CR_FUNC int Wide_Leaf(const PrimView* pv, CR_GLOBAL const uint* refs, uint p, uint meta, const Ray* ray, Hit* hit,
                      int anyHit, TraceStats* st)
{
  if (meta != CR_WIDE_MIXED)
    return Wide_Packs(pv, refs, (meta >> 16) - 1u, p, meta & 0xffffu, ray, hit, anyHit, st);
  CR_GLOBAL const uint* leaf = refs + refs[CR_NUM_PRIM_TYPES] + (size_t)p * (2u * CR_NUM_PRIM_TYPES);
  for (uint k = 0; k < CR_NUM_PRIM_TYPES; ++k)
    if (leaf[2u * k + 1u] && Wide_Packs(pv, refs, k, leaf[2u * k], leaf[2u * k + 1u], ray, hit, anyHit, st)) return 1;
  return 0;
}

/* The child slots of a wide node whose boxes the ray enters in [tmin, tmax],
 * as bits, and their entry distances in te. */
CR_FUNC uint Wide_Children(CR_GLOBAL const float* nb, const Ray* ray, real tmin, real tmax, real te[8])
{
#if !defined(CR_FP64)
  float8 boxNear = (float8)(-CR_INF), boxFar = (float8)(CR_INF);
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    const float8 o = (float8)(ray->org[a]), inv = (float8)(ray->inv[a]);
    const float8 lo = (vload8(0, nb + a * 8) - o) * inv;
    const float8 hi = (vload8(0, nb + 24 + a * 8) - o) * inv;
    const int neg = ray->inv[a] < 0.0f;
    boxNear = fmax(boxNear, neg ? hi : lo);
    boxFar = fmin(boxFar, neg ? lo : hi);
  }
#ifndef CR_FAST
  boxFar = boxFar * 1.0000004f;
#endif
  const float8 tn = fmax((float8)(tmin), boxNear), tf = fmin((float8)(tmax), boxFar);
  vstore8(tn, 0, te);
  return Wide_Bits(tn <= tf);
#else
  uint bits = 0u;
  for (int i = 0; i < 8; ++i) {
    real lo[3], hi[3];
    CR_UNROLL for (int a = 0; a < 3; ++a) {
      lo[a] = (real)nb[a * 8 + i];
      hi[a] = (real)nb[24 + a * 8 + i];
    }
    if (Box_Slabs(lo, hi, ray, tmin, tmax, &te[i])) bits |= 1u << i;
  }
  return bits;
#endif
}

/* Closest hit (anyHit = 0) or any hit (anyHit = 1) of the ray in the
 * subtree of slot (ref, meta) (the root: 0, 0); `hit` from Hit_Init or a
 * closer hit so far. Children nearest first (any hit: in slot order), the
 * others on the stack with their entry distances (simd/bvh_single.h).
 * Returns 1 when an occlusion query found its occluder. */
CR_FUNC int Wide_TraceFrom(CR_GLOBAL const float* wn, CR_GLOBAL const uint* refs, const PrimView* pv, const Ray* ray,
                           Hit* hit, int anyHit, TraceStats* st, uint ref, uint meta)
{
  uint stackRef[CR_WIDE_STACK], stackMeta[CR_WIDE_STACK];
  real stackT[CR_WIDE_STACK];
  int sp = 0;
  for (;;) {
    if (!(ref & CR_WIDE_LEAF)) {
      CR_GLOBAL const float* nb = wn + (size_t)ref * CR_WIDE_NODE_WORDS;
      CR_GLOBAL const uint* child = (CR_GLOBAL const uint*)(nb + 48);
      CR_GLOBAL const uint* cmeta = (CR_GLOBAL const uint*)(nb + 56);
      CR_COUNT(st, nTS);
      real te[8];
      uint bits = Wide_Children(nb, ray, ray->tmin, Cull_Distance(hit->t), te);
      if (bits) {
        const int i0 = Wide_Lowest(bits);
        bits &= bits - 1u;
        if (!bits) {
          ref = child[i0];
          meta = cmeta[i0];
          continue;
        }
        /* Two or more: push all, farthest deepest, go on with the nearest. */
        const int base = sp;
        stackRef[sp] = child[i0];
        stackMeta[sp] = cmeta[i0];
        stackT[sp] = te[i0];
        ++sp;
        do {
          const int i = Wide_Lowest(bits);
          bits &= bits - 1u;
          int j = sp++;
          while (!anyHit && j > base && stackT[j - 1] < te[i]) {
            stackRef[j] = stackRef[j - 1];
            stackMeta[j] = stackMeta[j - 1];
            stackT[j] = stackT[j - 1];
            --j;
          }
          stackRef[j] = child[i];
          stackMeta[j] = cmeta[i];
          stackT[j] = te[i];
        } while (bits);
        --sp;
        ref = stackRef[sp];
        meta = stackMeta[sp];
        continue;
      }
    } else {
      CR_COUNT(st, nTS);
      CR_COUNT(st, nLeaves);
      if (Wide_Leaf(pv, refs, ref & ~CR_WIDE_LEAF, meta, ray, hit, anyHit, st)) return 1;
    }
    /* Pop the nearest pending slot that can still hold a closer hit. */
    for (;;) {
      if (sp == 0) return 0;
      --sp;
      if (stackT[sp] <= Cull_Distance(hit->t)) {
        ref = stackRef[sp];
        meta = stackMeta[sp];
        break;
      }
    }
  }
}

CR_FUNC void BVH_Trace(CR_GLOBAL const BVHHeader* hdr, CR_GLOBAL const BVHNode* nodes, CR_GLOBAL const uint* refs,
                       const PrimView* pv, const Ray* ray, Hit* hit, int anyHit, TraceStats* st)
{
  (void)hdr;
  (void)Wide_TraceFrom((CR_GLOBAL const float*)nodes, refs, pv, ray, hit, anyHit, st, 0u, 0u);
}

#if defined(CR_BVH_WIDE_PACKET) && !defined(CR_FP64)
/* The packet form (--variant wide-packet, CR_BVH_WIDE_PACKET): a work-item
 * walks 8 rays together (Wald, Slusallek, Benthin & Wagner 2001; Embree's
 * hybrid walk, Benthin et al. 2012, as simd/bvh_wide_packet.h): at a node a
 * frustum test of the packet against the 8 child boxes at once (when the
 * lanes share direction signs) picks the children some lane may enter, and
 * each of those is tested against the lanes that entered the node, float8
 * across the rays (Box_Slabs lane by lane); children are visited nearest
 * first by their nearest lane's entry (any hit: in slot order). At a leaf
 * each entering lane tests it as the per-ray walk does (Wide_Leaf), and when
 * at most CR_WIDE_PACKET_SINGLE lanes enter a node each finishes that subtree
 * alone (Wide_TraceFrom). Each lane's answer is the per-ray walk's. */
#ifndef CR_WIDE_PACKET_SINGLE
#define CR_WIDE_PACKET_SINGLE 2
#endif

CR_FUNC float8 Wide_Lanes8(const Ray* ray, int field, int a)
{
  float v[8];
  for (int l = 0; l < 8; ++l)
    v[l] = field == 0 ? ray[l].org[a] : field == 1 ? ray[l].inv[a] : ray[l].tmin;
  return vload8(0, v);
}
CR_FUNC float8 Wide_Cull8(const Hit* hit)
{
  float v[8];
  for (int l = 0; l < 8; ++l) v[l] = Cull_Distance(hit[l].t);
  return vload8(0, v);
}
CR_FUNC float Wide_HMin(float8 v)
{
  const float4 a = fmin(v.lo, v.hi);
  const float2 b = fmin(a.lo, a.hi);
  return fmin(b.x, b.y);
}
CR_FUNC float Wide_HMax(float8 v)
{
  const float4 a = fmax(v.lo, v.hi);
  const float2 b = fmax(a.lo, a.hi);
  return fmax(b.x, b.y);
}

/* The 8 rays ray[0..7] (lanes past `n` copies of ray 0, inactive). */
CR_FUNC void BVH_TracePacket8(CR_GLOBAL const BVHNode* nodes, CR_GLOBAL const uint* refs, const PrimView* pv,
                              const Ray* ray, Hit* hit, int n, int anyHit, TraceStats* st)
{
  CR_GLOBAL const float* wn = (CR_GLOBAL const float*)nodes;
  uint stackRef[CR_WIDE_STACK], stackMeta[CR_WIDE_STACK], stackBits[CR_WIDE_STACK];
  float stackT[CR_WIDE_STACK * 8];
  int sp = 0;
  const uint active = n >= 8 ? 0xffu : (1u << n) - 1u;
  uint done = 0u; /* occlusion: lanes with an occluder */
  uint bits = active;
  uint ref = 0u, meta = 0u;
  float8 org[3], inv[3];
  int8 neg[3];
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    org[a] = Wide_Lanes8(ray, 0, a);
    inv[a] = Wide_Lanes8(ray, 1, a);
    neg[a] = inv[a] < (float8)(0.0f);
  }
  const float8 tmin = Wide_Lanes8(ray, 2, 0);
  /* The packet's frustum in interval form, when every lane goes the same way
   * along each axis and every component is finite (simd/bvh_wide_packet.h):
   * bounds on every lane's slab distances from the intervals' corners. */
  int frustum = 1;
  float oLo[3], oHi[3], iLo[3], iHi[3];
  int axisNeg[3];
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    const uint nb = Wide_Bits(neg[a]) & active;
    frustum = frustum && (nb == 0u || nb == active);
    const int8 finite = (fabs(org[a]) < (float8)(CR_INF)) & (fabs(inv[a]) < (float8)(CR_INF)) &
                        (fabs(inv[a]) > (float8)(0.0f));
    frustum = frustum && (Wide_Bits(finite) & active) == active;
    oLo[a] = Wide_HMin(org[a]);
    oHi[a] = Wide_HMax(org[a]);
    iLo[a] = Wide_HMin(inv[a]);
    iHi[a] = Wide_HMax(inv[a]);
    axisNeg[a] = nb != 0u;
  }
  const float tminLo = Wide_HMin(tmin);
  float8 cull = Wide_Cull8(hit);
  for (;;) {
    if (popcount(bits) <= CR_WIDE_PACKET_SINGLE) {
      /* Few lanes: each finishes this subtree alone. */
      for (uint rest = bits; rest; rest &= rest - 1u) {
        const int l = Wide_Lowest(rest);
        if (Wide_TraceFrom(wn, refs, pv, &ray[l], &hit[l], anyHit, &st[l], ref, meta)) done |= 1u << l;
      }
      if (anyHit && (done & active) == active) return;
      cull = Wide_Cull8(hit);
    } else if (!(ref & CR_WIDE_LEAF)) {
      CR_GLOBAL const float* nb = wn + (size_t)ref * CR_WIDE_NODE_WORDS;
      CR_GLOBAL const uint* child = (CR_GLOBAL const uint*)(nb + 48);
      CR_GLOBAL const uint* cmeta = (CR_GLOBAL const uint*)(nb + 56);
      for (uint rest = bits; rest; rest &= rest - 1u) CR_COUNT(&st[Wide_Lowest(rest)], nTS);
      uint cand = 0xffu;
      if (frustum) {
        float8 boxNear = (float8)(-CR_INF), boxFar = (float8)(CR_INF);
        CR_UNROLL for (int a = 0; a < 3; ++a) {
          const float8 lower = vload8(0, nb + a * 8), upper = vload8(0, nb + 24 + a * 8);
          float8 nr, fr;
          if (!axisNeg[a]) {
            const float8 dn = lower - (float8)(oHi[a]), df = upper - (float8)(oLo[a]);
            nr = dn * select((float8)(iHi[a]), (float8)(iLo[a]), dn >= (float8)(0.0f));
            fr = df * select((float8)(iLo[a]), (float8)(iHi[a]), df >= (float8)(0.0f));
          } else {
            const float8 dn = upper - (float8)(oLo[a]), df = lower - (float8)(oHi[a]);
            nr = dn * select((float8)(iHi[a]), (float8)(iLo[a]), dn >= (float8)(0.0f));
            fr = df * select((float8)(iHi[a]), (float8)(iLo[a]), df <= (float8)(0.0f));
          }
          boxNear = fmax(boxNear, nr);
          boxFar = fmin(boxFar, fr);
        }
#ifndef CR_FAST
        boxFar = boxFar * 1.0000004f;
#endif
        const float8 tn = fmax((float8)(tminLo), boxNear), tf = fmin((float8)(Wide_HMax(cull)), boxFar);
        cand = Wide_Bits(tn <= tf);
      }
      uint kidRef[8], kidMeta[8], kidBits[8];
      float kidT[64], key[8];
      int nk = 0;
      for (; cand; cand &= cand - 1u) {
        const int i = Wide_Lowest(cand);
        if (child[i] == CR_WIDE_LEAF && cmeta[i] == CR_WIDE_MIXED) continue; /* an unused slot */
        float8 boxNear = (float8)(-CR_INF), boxFar = (float8)(CR_INF);
        CR_UNROLL for (int a = 0; a < 3; ++a) {
          const float8 lo = ((float8)(nb[a * 8 + i]) - org[a]) * inv[a];
          const float8 hi = ((float8)(nb[24 + a * 8 + i]) - org[a]) * inv[a];
          boxNear = fmax(boxNear, select(lo, hi, neg[a]));
          boxFar = fmin(boxFar, select(hi, lo, neg[a]));
        }
#ifndef CR_FAST
        boxFar = boxFar * 1.0000004f;
#endif
        const float8 tn = fmax(tmin, boxNear), tf = fmin(cull, boxFar);
        const uint hb = Wide_Bits(tn <= tf) & bits;
        if (!hb) continue;
        int j = nk++;
        if (!anyHit) {
          /* Insertion by the nearest lane's entry, farthest first. */
          const float d = Wide_HMin(select((float8)(CR_INF), tn, tn <= tf));
          while (j > 0 && key[j - 1] < d) {
            kidRef[j] = kidRef[j - 1];
            kidMeta[j] = kidMeta[j - 1];
            kidBits[j] = kidBits[j - 1];
            key[j] = key[j - 1];
            for (int l = 0; l < 8; ++l) kidT[8 * j + l] = kidT[8 * (j - 1) + l];
            --j;
          }
          key[j] = d;
        }
        kidRef[j] = child[i];
        kidMeta[j] = cmeta[i];
        kidBits[j] = hb;
        vstore8(tn, j, kidT);
      }
      if (nk > 0) {
        for (int j = 0; j < nk - 1; ++j) {
          stackRef[sp] = kidRef[j];
          stackMeta[sp] = kidMeta[j];
          stackBits[sp] = kidBits[j];
          vstore8(vload8(j, kidT), sp, stackT);
          ++sp;
        }
        ref = kidRef[nk - 1];
        meta = kidMeta[nk - 1];
        bits = kidBits[nk - 1];
        continue;
      }
    } else {
      for (uint rest = bits; rest; rest &= rest - 1u) {
        const int l = Wide_Lowest(rest);
        CR_COUNT(&st[l], nTS);
        CR_COUNT(&st[l], nLeaves);
        if (Wide_Leaf(pv, refs, ref & ~CR_WIDE_LEAF, meta, &ray[l], &hit[l], anyHit, &st[l])) done |= 1u << l;
      }
      if (anyHit && (done & active) == active) return;
      cull = Wide_Cull8(hit);
    }
    /* Pop the next pending child with a lane that can still find a closer hit. */
    for (;;) {
      if (sp == 0) return;
      --sp;
      bits = stackBits[sp] & ~done & Wide_Bits(vload8(sp, stackT) <= cull);
      if (bits) {
        ref = stackRef[sp];
        meta = stackMeta[sp];
        break;
      }
    }
  }
}
#endif /* CR_BVH_WIDE_PACKET */

#endif /* CELLRAY_KERNELS_BVH_WIDE_CL */
