// Ray-primitive and ray-box tests on N lanes, lane by lane the arithmetic of
// kernels/intersect.h: the same operations in the same order, separate
// multiplies and adds (no FMA), IEEE division and square root, and the C
// semantics of fmin/fmax, copysign and of comparisons with NaN. The lanes are
// either N rays against one primitive (packets: the primitive broadcast) or
// one ray against N primitives (single-ray packs: the ray broadcast); the
// functions do not care which. kFast selects the CR_FAST algorithms.
// Included by simd/kernel_common.h, after the ISA namespace is set (simd/vec.h).
#pragma once

#include "simd/vec.h"

namespace cr::simd::CR_SIMD_NS {

template <int N>
using V3 = vfloat<N>[3];

template <int N>
CR_SIMD_INLINE vfloat<N> Dot3N(const vfloat<N> a[3], const vfloat<N> b[3])
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// Cull_Distance of kernels/intersect.h: boxes are entered up to 8 ulps
// beyond the closest hit so far, so the answer does not depend on the order
// boxes are visited in (the scalar backend walks the binary BVH, the
// single-ray path a BVH4/8).
template <bool kFast>
CR_SIMD_INLINE float CullDistance(float t)
{
  if constexpr (kFast) return t;
  return t * (1.0f + 0x1.0p-20f);
}
template <bool kFast, int N>
CR_SIMD_INLINE vfloat<N> CullDistance(vfloat<N> t)
{
  if constexpr (kFast) return t;
  return t * vfloat<N>(1.0f + 0x1.0p-20f);
}

// Box_Intersect after the per-axis plane distances: n[a], f[a] are the near
// and far distances of axis a (already chosen by the sign of inv). The
// accumulation starts at -inf / +inf and drops NaN (0 * inf on a
// plane-parallel ray) as fmax/fmin do; the far distance gets Ize's factor
// 1 + 2 gamma(3) unless kFast. Writes the entry distance.
template <bool kFast, int N>
CR_SIMD_INLINE vbool<N> Box_Finish(const vfloat<N> n[3], const vfloat<N> f[3], vfloat<N> tmin, vfloat<N> tmax,
                                   vfloat<N>& tEnter)
{
  vfloat<N> boxNear(-__builtin_inff()), boxFar(__builtin_inff());
  for (int a = 0; a < 3; ++a) {
    boxNear = Max(n[a], boxNear);  // NaN n keeps boxNear, as fmax(boxNear, n)
    boxFar = Min(f[a], boxFar);
  }
  if constexpr (!kFast) boxFar = boxFar * vfloat<N>(1.0000004f);
  const vfloat<N> tn = Max(boxNear, tmin);
  const vfloat<N> tf = Min(boxFar, tmax);
  tEnter = tn;
  return tn <= tf;
}

// Packet form: one box, a ray per lane (near/far chosen per lane by the sign
// of inv, as Box_Intersect does).
template <bool kFast, int N>
CR_SIMD_INLINE vbool<N> Box_IntersectRays(const float* bmin, const float* bmax, const vfloat<N> org[3],
                                          const vfloat<N> inv[3], const vbool<N> invNeg[3], vfloat<N> tmin,
                                          vfloat<N> tmax, vfloat<N>& tEnter)
{
  vfloat<N> n[3], f[3];
  for (int a = 0; a < 3; ++a) {
    const vfloat<N> lo = (vfloat<N>(bmin[a]) - org[a]) * inv[a];
    const vfloat<N> hi = (vfloat<N>(bmax[a]) - org[a]) * inv[a];
    n[a] = Select(invNeg[a], hi, lo);
    f[a] = Select(invNeg[a], lo, hi);
  }
  return Box_Finish<kFast, N>(n, f, tmin, tmax, tEnter);
}

// Single-ray form: N boxes structure-of-arrays (nearPlane[a] is bmax[a] when
// the ray's inv[a] < 0, else bmin[a]; farPlane the other), one ray broadcast.
template <bool kFast, int N>
CR_SIMD_INLINE vbool<N> Box_IntersectBoxes(const float* const nearPlane[3], const float* const farPlane[3],
                                           const vfloat<N> org[3], const vfloat<N> inv[3], vfloat<N> tmin,
                                           vfloat<N> tmax, vfloat<N>& tEnter)
{
  vfloat<N> n[3], f[3];
  for (int a = 0; a < 3; ++a) {
    n[a] = (vfloat<N>::Load(nearPlane[a]) - org[a]) * inv[a];
    f[a] = (vfloat<N>::Load(farPlane[a]) - org[a]) * inv[a];
  }
  return Box_Finish<kFast, N>(n, f, tmin, tmax, tEnter);
}

// Quadratic_Roots: roots of a t^2 + 2 bh t + c given disc >= 0, smaller
// first; the Vieta root c/q gives way to the direct root (sq - bh)/a when q is
// so small that c's own rounding (about eps * cScale) dominates.
template <int N>
CR_SIMD_INLINE void Quadratic_RootsN(vfloat<N> a, vfloat<N> bh, vfloat<N> c, vfloat<N> cScale, vfloat<N> disc,
                                     vfloat<N>& t0, vfloat<N>& t1, vfloat<N>& q)
{
  const vfloat<N> sq = CopySign(Sqrt(disc), bh);
  q = -(bh + sq);
  const vfloat<N> r0 = q / a;
  const vfloat<N> r1 = Select(vfloat<N>(16.0f) * q * q >= a * cScale, c / q, (sq - bh) / a);
  t0 = FMin(r0, r1);
  t1 = FMax(r0, r1);
}

// Sphere_NeedsDf of kernels/intersect.h, lane by lane.
template <int N>
CR_SIMD_INLINE vbool<N> Sphere_NeedsDfN(vfloat<N> c, vfloat<N> cScale, vfloat<N> bh, vfloat<N> disc,
                                        vfloat<N> dScale, vfloat<N> q, vfloat<N> a, vfloat<N> ff, vfloat<N> cc,
                                        vfloat<N> t0, vfloat<N> t1, vfloat<N> tmin, vfloat<N> tmax)
{
  const vfloat<N> dd = disc * (bh * bh + disc);
  const vfloat<N> ds2 = dScale * dScale;
  const vbool<N> inaccurate = (cScale > vfloat<N>(8.0f) * Abs(c)) | (ds2 > vfloat<N>(64.0f) * dd);
  if (None(inaccurate)) return inaccurate;
  const vbool<N> always = (ds2 > vfloat<N>(0x1.0p36f) * dd) | !(disc > vfloat<N>(0.0f));
  const vfloat<N> af = a * ff;
  const vfloat<N> eq = vfloat<N>(0x1.0p-20f) * ((Sqrt(af * cc) + dScale) / Sqrt(disc) + Sqrt(af));
  const vfloat<N> rel = eq / Abs(q) + vfloat<N>(0x1.0p-20f);
  const vfloat<N> e = vfloat<N>(0x1.0p-18f) * cScale / Abs(q);
  const vfloat<N> m = Select(vfloat<N>(16.0f) * q * q >= a * cScale, vfloat<N>(0.0f), FMax(Abs(t0), Abs(t1)));
  const vfloat<N> s0 = rel * FMax(Abs(t0), m) + e, s1 = rel * FMax(Abs(t1), m) + e;
  const vbool<N> window = ((t0 + s0 >= tmin) & (t0 - s0 <= tmax)) | ((t1 + s1 >= tmin) & (t1 - s1 <= tmax));
  return inaccurate & (always | window);
}

// Cone_NeedsDf of kernels/intersect.h, lane by lane.
template <int N>
CR_SIMD_INLINE vbool<N> Cone_NeedsDfN(vfloat<N> C, vfloat<N> cScale, vfloat<N> Bh, vfloat<N> disc, vfloat<N> ee,
                                      vfloat<N> xx, vfloat<N> q, vfloat<N> dl2, vfloat<N> oo, vfloat<N> k,
                                      vfloat<N> ds, vfloat<N> rb, vfloat<N> dRdR, vfloat<N> dd, vfloat<N> A,
                                      vfloat<N> t0, vfloat<N> t1, vfloat<N> tmin, vfloat<N> tmax)
{
  const vfloat<N> dScale = ee + xx;
  const vfloat<N> d2 = disc * (Bh * Bh + disc);
  const vfloat<N> ds2 = dScale * dScale;
  const vbool<N> inaccurate =
      (cScale > vfloat<N>(8.0f) * Abs(C)) | (ds2 > vfloat<N>(64.0f) * d2) | (dl2 > vfloat<N>(64.0f) * oo);
  if (None(inaccurate)) return inaccurate;
  const vfloat<N> ndl = Sqrt(dl2), ndR = Sqrt(dRdR), nd = Sqrt(dd), noR = Sqrt(oo), kds = Abs(k * ds);
  const vfloat<N> Ee =
      vfloat<N>(0x1.0p-20f) * ((Abs(k) * ndl + Abs(rb)) * ndR + Abs(rb) * nd + kds * ndl);
  const vfloat<N> Ex = vfloat<N>(0x1.0p-19f) * (ndl * ndR + noR * nd);
  const vfloat<N> eDisc = vfloat<N>(2.0f) * (Sqrt(ee) * Ee + Sqrt(xx) * Ex) + vfloat<N>(0x1.0p-21f) * dScale;
  const vfloat<N> eB = vfloat<N>(0x1.0p-20f) * (ndl * (ndR + Abs(k) * kds) + noR * nd + kds * Abs(rb));
  const vfloat<N> eA = vfloat<N>(0x1.0p-19f) * (ndR * nd + kds * kds + Abs(k) * kds * nd);
  const vfloat<N> eq = eDisc / (vfloat<N>(2.0f) * Sqrt(disc)) + eB;
  const vfloat<N> rel = eq / Abs(q) + eA / Abs(A) + vfloat<N>(0x1.0p-20f);
  const vbool<N> always = (ds2 > vfloat<N>(0x1.0p36f) * d2) | (dl2 > vfloat<N>(0x1.0p36f) * oo) |
                          !(disc > vfloat<N>(0.0f)) |
                          !((eDisc < vfloat<N>(0.25f) * disc) & (rel < vfloat<N>(0.0625f)));
  const vfloat<N> e = vfloat<N>(0x1.0p-18f) * (cScale + ndl * (noR + Abs(k * rb))) / Abs(q);
  const vfloat<N> m = Select(vfloat<N>(16.0f) * q * q >= A * cScale, vfloat<N>(0.0f), FMax(Abs(t0), Abs(t1)));
  const vfloat<N> s0 = rel * FMax(Abs(t0), m) + e, s1 = rel * FMax(Abs(t1), m) + e;
  const vbool<N> window = ((t0 + s0 >= tmin) & (t0 - s0 <= tmax)) | ((t1 + s1 >= tmin) & (t1 - s1 <= tmax));
  return inaccurate & (always | window);
}

// The lanes of `bits` take a scalar kernel's double-float test (the cold
// paths of kernels/intersect.h, compiled in this namespace: the same bits as
// the scalar and OpenCL backends). test(l, &t) returns whether lane l hits,
// and its t. Rare, so out of line.
template <int N>
struct RefinedLanes {
  vfloat<N> t;
  vbool<N> ok;
};
// Everything goes in and out by value, and the tests capture by value: a
// vector whose address reached this out-of-line function would live in
// memory in the hot caller too (a triangle test 20% slower on tetra).
template <int N, class Test>
__attribute__((noinline, cold)) RefinedLanes<N> RefineLanesN(unsigned bits, Test test, vfloat<N> tHit, vbool<N> ok)
{
  alignas(32) float t[N];
  tHit.Store(t);
  unsigned okBits = ok.Bits();
  for (; bits; bits &= bits - 1) {
    const int l = LowestBit(bits);
    float th = 0.0f;
    if (test(l, &th)) {
      t[l] = th;
      okBits |= 1u << l;
    } else {
      okBits &= ~(1u << l);
    }
  }
  return {vfloat<N>::Load(t), vbool<N>::FromBits(okBits)};
}

// Lane l of a vector array as a float[3].
template <int N>
CR_SIMD_INLINE void Lane3(const vfloat<N> v[3], int l, float out[3])
{
  for (int i = 0; i < 3; ++i) out[i] = v[i][l];
}

// Sphere_Intersect: nearest root in [tmin, tmax]; f = org - cen; a = d.d
// (Dot3N(dir, dir), computed once per ray by the caller). Where the float
// discriminant is within its error bound (Sphere_DiscUndecided) or the roots
// may be off (Sphere_NeedsDf), the lane takes the scalar kernels'
// double-float test (Sphere_IntersectDf).
template <bool kFast, int N>
CR_SIMD_INLINE vbool<N> Sphere_IntersectN(const vfloat<N> org[3], const vfloat<N> cen[3], const vfloat<N> dir[3],
                                          vfloat<N> a, vfloat<N> rad, vfloat<N> tmin, vfloat<N> tmax, vfloat<N>& tHit)
{
  vfloat<N> f[3];
  for (int i = 0; i < 3; ++i) f[i] = org[i] - cen[i];
  const vfloat<N> bh = Dot3N<N>(f, dir);
  const vfloat<N> ff = Dot3N<N>(f, f);
  const vfloat<N> c = ff - rad * rad;
  vfloat<N> t0, t1;
  vbool<N> miss;
  if constexpr (kFast) {
    const vfloat<N> b = vfloat<N>(2.0f) * bh;
    const vfloat<N> disc4 = b * b - vfloat<N>(4.0f) * a * c;
    miss = disc4 < vfloat<N>(0.0f);
    const vfloat<N> sq = Sqrt(disc4);
    t0 = (-b - sq) / (vfloat<N>(2.0f) * a);
    t1 = (-b + sq) / (vfloat<N>(2.0f) * a);
  } else {
    const vfloat<N> cx = f[1] * dir[2] - f[2] * dir[1];
    const vfloat<N> cy = f[2] * dir[0] - f[0] * dir[2];
    const vfloat<N> cz = f[0] * dir[1] - f[1] * dir[0];
    const vfloat<N> ar2 = a * rad * rad;
    const vfloat<N> cc = cx * cx + cy * cy + cz * cz;
    vfloat<N> disc = ar2 - cc;
    const vfloat<N> Q = vfloat<N>(0x1.0p-29f) * (ff * a);
    // Most tests miss for certain (Sphere_Intersect's -2^15 Q): skip the
    // bound, the square root and the divisions when all do.
    if (All(disc < vfloat<N>(-0x1.0p15f) * Q)) {
      tHit = vfloat<N>(0.0f);
      return vbool<N>(false);
    }
    // Undecided lanes (Sphere_DiscUndecided) and lanes whose roots may be
    // off (Sphere_NeedsDf) take the double-float test.
    const vbool<N> undecided = disc * disc <= Q * (cc + vfloat<N>(0x1.0p-9f) * Q);
    miss = disc < vfloat<N>(0.0f);
    if (All(AndNot(miss, undecided))) {
      tHit = vfloat<N>(0.0f);
      return vbool<N>(false);
    }
    vfloat<N> q;
    Quadratic_RootsN<N>(a, bh, c, ff + rad * rad, disc, t0, t1, q);
    const vbool<N> refine =
        undecided | AndNot(Sphere_NeedsDfN<N>(c, ff + rad * rad, bh, disc, ar2 + cc, q, a, ff, cc, t0, t1, tmin, tmax), miss);
    if (Any(refine)) {
      const vbool<N> in0 = (t0 >= tmin) & (t0 <= tmax);
      const vbool<N> in1 = (t1 >= tmin) & (t1 <= tmax);
      tHit = Select(in0, t0, t1);
      vbool<N> ok = AndNot(in0 | in1, miss);
      const RefinedLanes<N> r = RefineLanesN<N>(refine.Bits(), [=](int l, float* th) {
        float o[3], d[3];
        Lane3<N>(org, l, o);
        Lane3<N>(dir, l, d);
        Sphere sp;
        Lane3<N>(cen, l, sp.center);
        sp.radius = rad[l];
        return Sphere_IntersectDf(o, d, &sp, tmin[l], tmax[l], th) != 0;
      }, tHit, ok);
      tHit = r.t;
      return r.ok;
    }
  }
  const vbool<N> in0 = (t0 >= tmin) & (t0 <= tmax);
  const vbool<N> in1 = (t1 >= tmin) & (t1 <= tmax);
  tHit = Select(in0, t0, t1);
  return AndNot(in0 | in1, miss);
}

// n . p / nd with the products summed in Dot3's order; `inexact`: the lanes
// where n . p cancels by more than 16 (Triangle_Intersect's cold-path rule).
template <int N>
CR_SIMD_INLINE vfloat<N> Triangle_PlaneDivN(const vfloat<N> n[3], const vfloat<N> p[3], vfloat<N> nd,
                                            vbool<N>& inexact, vfloat<N>& sumOverNd)
{
  const vfloat<N> np0 = n[0] * p[0], np1 = n[1] * p[1], np2 = n[2] * p[2];
  const vfloat<N> np = (np0 + np1) + np2;
  const vfloat<N> sum = (Abs(np0) + Abs(np1)) + Abs(np2);
  inexact = sum > vfloat<N>(16.0f) * Abs(np);
  // Read only where inexact: no division in the common case.
  sumOverNd = Any(inexact) ? vfloat<N>(0x1.0p-20f) * sum / Abs(nd) : vfloat<N>(0.0f);
  return np / nd;
}

// The distance along the ray to the triangle's plane, kernels/intersect.h's
// Triangle_Intersect step for step: the normal from the shortest edge and its
// successor (edges from the stored vertices), the shared vertex relative to
// the origin; a plane-parallel ray (n.d == 0) sets `miss`. v0..v2, org, dir
// in world axis order.
template <int N>
CR_SIMD_INLINE vfloat<N> Triangle_PlaneTN(const vfloat<N> v0[3], const vfloat<N> v1[3], const vfloat<N> v2[3],
                                          const vfloat<N> org[3], const vfloat<N> dir[3], vbool<N>& miss,
                                          vbool<N>& inexact, vfloat<N>& sumOverNd)
{
  vfloat<N> e0[3], e1[3], e2[3];
  for (int i = 0; i < 3; ++i) {
    e0[i] = v1[i] - v0[i];
    e1[i] = v2[i] - v1[i];
    e2[i] = v0[i] - v2[i];
  }
  const vfloat<N> l0 = Dot3N<N>(e0, e0), l1 = Dot3N<N>(e1, e1), l2 = Dot3N<N>(e2, e2);
  // k = (l0 <= l1) ? ((l0 <= l2) ? 0 : 2) : ((l1 <= l2) ? 1 : 2)
  const vbool<N> k0 = (l0 <= l1) & (l0 <= l2);
  const vbool<N> k1 = AndNot(l1 <= l2, l0 <= l1);
  // k == 2 otherwise. Edge k, its successor, and the vertex they share:
  // k 0: e0, e1, v1; k 1: e1, e2, v2; k 2: e2, e0, v0.
  vfloat<N> ea[3], eb[3], p[3];
  for (int i = 0; i < 3; ++i) {
    ea[i] = Select(k0, e0[i], Select(k1, e1[i], e2[i]));
    eb[i] = Select(k0, e1[i], Select(k1, e2[i], e0[i]));
    p[i] = Select(k0, v1[i] - org[i], Select(k1, v2[i] - org[i], v0[i] - org[i]));
  }
  vfloat<N> n[3];
  n[0] = ea[1] * eb[2] - ea[2] * eb[1];
  n[1] = ea[2] * eb[0] - ea[0] * eb[2];
  n[2] = ea[0] * eb[1] - ea[1] * eb[0];
  const vfloat<N> nd = Dot3N<N>(n, dir);
  miss = miss | (nd == vfloat<N>(0.0f));
  return Triangle_PlaneDivN<N>(n, p, nd, inexact, sumOverNd);
}

// Triangle_PlaneTN for one triangle against N rays (packets): the normal
// depends on the triangle only, so it comes once from the scalar kernels'
// Triangle_PlaneNormal (the same float operations, no contraction:
// simd/CMakeLists.txt), which gives every lane Triangle_PlaneTN's bits.
template <int N>
CR_SIMD_INLINE vfloat<N> Triangle_PlaneT1N(const Triangle& tri, const vfloat<N> org[3], const vfloat<N> dir[3],
                                           vbool<N>& miss, vbool<N>& inexact, vfloat<N>& sumOverNd)
{
  float nf[3];
  const int shared = Triangle_PlaneNormal(&tri, nf);
  const float* vk = shared == 0 ? tri.v0 : (shared == 1 ? tri.v1 : tri.v2);
  const vfloat<N> n[3] = {vfloat<N>(nf[0]), vfloat<N>(nf[1]), vfloat<N>(nf[2])};
  vfloat<N> p[3];
  for (int i = 0; i < 3; ++i) p[i] = vfloat<N>(vk[i]) - org[i];
  const vfloat<N> nd = Dot3N<N>(n, dir);
  miss = miss | (nd == vfloat<N>(0.0f));
  return Triangle_PlaneDivN<N>(n, p, nd, inexact, sumOverNd);
}

// Plane sources for Triangle_WatertightN: T(org, dir, miss, inexact) gives
// the distance to the triangle's plane, Tri(l) lane l's triangle (for the
// double-float cold path). Vertices already in registers (a transposed
// group), a TrianglePack's [vertex][axis][lane] floats, or one triangle for
// every lane (packets).
template <int N>
struct VecPlane {
  const vfloat<N> (&vtx)[3][4];
  vfloat<N> T(const vfloat<N>* org, const vfloat<N>* dir, vbool<N>& miss, vbool<N>& inexact, vfloat<N>& son) const
  {
    return Triangle_PlaneTN<N>(vtx[0], vtx[1], vtx[2], org, dir, miss, inexact, son);
  }
  // Lanes whose triangle has long edges (the flags word rides in v0's
  // fourth float).
  unsigned LongEdgeLanes() const { return MaskedLanes(vtx[0][3], CR_TRI_LONG_EDGES); }
  unsigned FlagLanes(std::uint32_t bit) const { return MaskedLanes(vtx[0][3], bit); }
  Triangle Tri(int l) const
  {
    Triangle t{};
    for (int i = 0; i < 3; ++i) {
      t.v0[i] = vtx[0][i][l];
      t.v1[i] = vtx[1][i][l];
      t.v2[i] = vtx[2][i][l];
    }
    t.flags = __builtin_bit_cast(std::uint32_t, vtx[0][3][l]);
    return t;
  }
};
template <int N>
struct PackPlane {
  const float (&pv)[3][3][N];
  const std::uint32_t (&flags)[N];
  vfloat<N> T(const vfloat<N>* org, const vfloat<N>* dir, vbool<N>& miss, vbool<N>& inexact, vfloat<N>& son) const
  {
    vfloat<N> v0[3], v1[3], v2[3];
    for (int i = 0; i < 3; ++i) {
      v0[i] = vfloat<N>::Load(pv[0][i]);
      v1[i] = vfloat<N>::Load(pv[1][i]);
      v2[i] = vfloat<N>::Load(pv[2][i]);
    }
    return Triangle_PlaneTN<N>(v0, v1, v2, org, dir, miss, inexact, son);
  }
  unsigned LongEdgeLanes() const { return MaskedLanes(vint<N>::Load(flags), CR_TRI_LONG_EDGES); }
  unsigned FlagLanes(std::uint32_t bit) const { return MaskedLanes(vint<N>::Load(flags), bit); }
  Triangle Tri(int l) const
  {
    Triangle t{};
    for (int i = 0; i < 3; ++i) {
      t.v0[i] = pv[0][i][l];
      t.v1[i] = pv[1][i][l];
      t.v2[i] = pv[2][i][l];
    }
    t.flags = flags[l];
    return t;
  }
};
template <int N>
struct OnePlane {
  const Triangle& tri;
  vfloat<N> T(const vfloat<N>* org, const vfloat<N>* dir, vbool<N>& miss, vbool<N>& inexact, vfloat<N>& son) const
  {
    return Triangle_PlaneT1N<N>(tri, org, dir, miss, inexact, son);
  }
  unsigned LongEdgeLanes() const { return tri.flags & CR_TRI_LONG_EDGES ? (1u << N) - 1u : 0u; }
  unsigned FlagLanes(std::uint32_t bit) const { return tri.flags & bit ? (1u << N) - 1u : 0u; }
  Triangle Tri(int) const { return tri; }
};

// The lanes of `bits` run a scalar kernel edge routine on their edge
// functions: refine(ray, tri, l, &U, &V, &W) with the lane's ray prepared as
// the scalar kernels prepare it (Ray_Init) and its triangle from the plane
// source (Triangle_RefineEdges, Triangle_EdgesDf of kernels/intersect.h).
template <int N>
struct EdgeFunctions {
  vfloat<N> U, V, W;
};
template <int N, class PlaneFn, class Refine>
__attribute__((noinline, cold)) EdgeFunctions<N> Triangle_EdgeLanesN(unsigned bits, PlaneFn plane,
                                                                     const vfloat<N> org[3], const vfloat<N> dir[3],
                                                                     vfloat<N> U, vfloat<N> V, vfloat<N> W,
                                                                     Refine refine)
{
  alignas(32) float u[N], v[N], w[N];
  U.Store(u);
  V.Store(v);
  W.Store(w);
  for (; bits; bits &= bits - 1) {
    const int l = LowestBit(bits);
    RayRecord rec{};
    Lane3<N>(org, l, rec.org);
    Lane3<N>(dir, l, rec.dir);
    rec.tmax = __builtin_inff();
    Ray ray;
    Ray_Init(&ray, &rec);
    const Triangle tri = plane.Tri(l);
    refine(ray, tri, l, &u[l], &v[l], &w[l]);
  }
  return {vfloat<N>::Load(u), vfloat<N>::Load(v), vfloat<N>::Load(w)};
}

// Robust Triangle_Intersect (Woop, Benthin & Wald 2013) after the
// translation: A[j], B[j], C[j] are the vertices minus the ray origin in the
// ray's permuted axes (j = 0, 1, 2 for kx, ky, kz); s[] = sx, sy, sz.
// plane.T(org, dir, miss, inexact) gives the distance to the triangle's plane
// (Triangle_PlaneTN; the plane sources above); it runs only when some lane
// passes the edge tests (most tests miss before), so the world-order
// vertices are not loaded or kept in registers for the others.
template <int N, class PlaneFn>
CR_SIMD_INLINE vbool<N> Triangle_WatertightN(const vfloat<N> A[3], const vfloat<N> B[3], const vfloat<N> C[3],
                                             const vfloat<N> s[3], PlaneFn&& plane, const vfloat<N> org[3],
                                             const vfloat<N> dir[3], vfloat<N> tmin, vfloat<N> tmax, vfloat<N>& tHit,
                                             vfloat<N>& uHit, vfloat<N>& vHit)
{
  const vfloat<N> Ax = A[0] - s[0] * A[2], Ay = A[1] - s[1] * A[2];
  const vfloat<N> Bx = B[0] - s[0] * B[2], By = B[1] - s[1] * B[2];
  const vfloat<N> Cx = C[0] - s[0] * C[2], Cy = C[1] - s[1] * C[2];
  vfloat<N> U = Cx * By - Cy * Bx;
  vfloat<N> V = Ax * Cy - Ay * Cx;
  vfloat<N> W = Bx * Ay - By * Ax;
  // Triangles with long edges: a flagged edge within its rounding bound
  // (Triangle_LongEdgeUndecided) takes the scalar kernels'
  // Triangle_RefineEdges, lane by lane.
  if (plane.LongEdgeLanes()) {
    const vfloat<N> nA = (Abs(A[0]) + Abs(A[1])) + Abs(A[2]);
    const vfloat<N> nB = (Abs(B[0]) + Abs(B[1])) + Abs(B[2]);
    const vfloat<N> nC = (Abs(C[0]) + Abs(C[1])) + Abs(C[2]);
    const vfloat<N> k(0x1.0p-18f);
    const unsigned undecided = (plane.FlagLanes(CR_TRI_LONG_U) & (Abs(U) <= k * (nB * nC)).Bits()) |
                               (plane.FlagLanes(CR_TRI_LONG_V) & (Abs(V) <= k * (nC * nA)).Bits()) |
                               (plane.FlagLanes(CR_TRI_LONG_W) & (Abs(W) <= k * (nA * nB)).Bits());
    if (undecided) {
      const EdgeFunctions<N> e = Triangle_EdgeLanesN<N>(
          undecided, plane, org, dir, U, V, W,
          [=](const Ray& ray, const Triangle& tri, int l, float* u, float* v, float* w) {
            Triangle_RefineEdges(&ray, &tri, nA[l], nB[l], nC[l], u, v, w);
          });
      U = e.U;
      V = e.V;
      W = e.W;
    }
  }
  const vfloat<N> zero(0.0f);
  vbool<N> miss = ((U < zero) | (V < zero) | (W < zero)) & ((U > zero) | (V > zero) | (W > zero));
  vfloat<N> det = U + V + W;
  miss = miss | (det == zero);
  // Most tests miss here: skip the division when all do.
  if (All(miss)) {
    tHit = uHit = vHit = zero;
    return vbool<N>(false);
  }
  // t from the triangle's plane, as kernels/intersect.h computes it (in world
  // axis order, which the sums' rounding depends on). Where n . p cancels
  // (the origin near the plane: Triangle_PlaneInexact), as there: float hits
  // whose three edge functions all lie within their rounding
  // (Triangle_EdgesUndecided) take the scalar kernels' Triangle_EdgesDf, and
  // lanes whose t may lie in [tmin, tmax] Triangle_PlaneTDf, lane by lane.
  vbool<N> inexact;
  vfloat<N> sumOverNd;
  vfloat<N> t = plane.T(org, dir, miss, inexact, sumOverNd);
  const vbool<N> nearPlane = AndNot(inexact, miss);
  if (Any(nearPlane)) {
    const vfloat<N> nA = (Abs(A[0]) + Abs(A[1])) + Abs(A[2]);
    const vfloat<N> nB = (Abs(B[0]) + Abs(B[1])) + Abs(B[2]);
    const vfloat<N> nC = (Abs(C[0]) + Abs(C[1])) + Abs(C[2]);
    const vfloat<N> k(0x1.0p-19f);
    const vbool<N> undecided =
        nearPlane & (Abs(U) <= k * (nB * nC)) & (Abs(V) <= k * (nC * nA)) & (Abs(W) <= k * (nA * nB));
    if (Any(undecided)) {
      const EdgeFunctions<N> e = Triangle_EdgeLanesN<N>(
          undecided.Bits(), plane, org, dir, U, V, W,
          [](const Ray& ray, const Triangle& tri, int, float* u, float* v, float* w) {
            Triangle_EdgesDf(&ray, &tri, u, v, w);
          });
      U = e.U;
      V = e.V;
      W = e.W;
      miss = miss | (((U < zero) | (V < zero) | (W < zero)) & ((U > zero) | (V > zero) | (W > zero)));
      det = U + V + W;
      miss = miss | (det == zero);
      if (All(miss)) {
        tHit = uHit = vHit = zero;
        return vbool<N>(false);
      }
    }
    const vfloat<N> slack = vfloat<N>(0.25f) * Abs(t) + sumOverNd;
    const vbool<N> refine = AndNot(inexact & (t + slack >= tmin) & (t - slack <= tmax), miss);
    if (Any(refine)) {
      t = RefineLanesN<N>(refine.Bits(), [=](int l, float* th) {
        float o[3], d[3];
        Lane3<N>(org, l, o);
        Lane3<N>(dir, l, d);
        const Triangle tri = plane.Tri(l);
        *th = Triangle_PlaneTDf(o, d, &tri);
        return true;
      }, t, vbool<N>(true)).t;
    }
  }
  const vfloat<N> invDet = vfloat<N>(1.0f) / det;
  tHit = t;
  uHit = V * invDet;
  vHit = W * invDet;
  return AndNot((t >= tmin) & (t <= tmax), miss);
}

// Fast Triangle_Intersect (Moller & Trumbore 1997, |det| >= 1e-9).
// Comparisons keep the scalar code's NaN behaviour; a NaN t passes its range
// test there and is then refused by Hit_Closer, so it is refused here.
template <int N>
CR_SIMD_INLINE vbool<N> Triangle_MollerTrumboreN(const vfloat<N> v0[3], const vfloat<N> v1[3], const vfloat<N> v2[3],
                                                 const vfloat<N> org[3], const vfloat<N> dir[3], vfloat<N> tmin,
                                                 vfloat<N> tmax, vfloat<N>& tHit, vfloat<N>& uHit, vfloat<N>& vHit)
{
  vfloat<N> e1[3], e2[3], tv[3], pv[3], qv[3];
  for (int i = 0; i < 3; ++i) {
    e1[i] = v1[i] - v0[i];
    e2[i] = v2[i] - v0[i];
    tv[i] = org[i] - v0[i];
  }
  pv[0] = dir[1] * e2[2] - dir[2] * e2[1];
  pv[1] = dir[2] * e2[0] - dir[0] * e2[2];
  pv[2] = dir[0] * e2[1] - dir[1] * e2[0];
  const vfloat<N> det = Dot3N<N>(e1, pv);
  const vfloat<N> zero(0.0f), one(1.0f);
  vbool<N> miss = Abs(det) < vfloat<N>(1e-9f);
  const vfloat<N> invDet = one / det;
  const vfloat<N> u = Dot3N<N>(tv, pv) * invDet;
  miss = miss | (u < zero) | (u > one);
  qv[0] = tv[1] * e1[2] - tv[2] * e1[1];
  qv[1] = tv[2] * e1[0] - tv[0] * e1[2];
  qv[2] = tv[0] * e1[1] - tv[1] * e1[0];
  const vfloat<N> v = Dot3N<N>(dir, qv) * invDet;
  miss = miss | (v < zero) | (u + v > one);
  const vfloat<N> t = Dot3N<N>(e2, qv) * invDet;
  miss = miss | (t < tmin) | (t > tmax) | IsNaN(t);
  tHit = t;
  uHit = u;
  vHit = v;
  return !miss;
}

// Cone_Intersect with the per-cone terms of ConeData (w unit axis, H, r0, k).
// dl = org - base. coneOf(l) is lane l's cone as the scene holds it (nullptr
// for a lane that holds none), for the double-float cold path
// (Cone_IntersectDf), which must start from the stored apex and base.
template <bool kFast, int N, class ConeOf>
CR_SIMD_INLINE vbool<N> Cone_IntersectN(const vfloat<N> org[3], const vfloat<N> dl[3], const vfloat<N> dir[3],
                                        const vfloat<N> w[3], vfloat<N> H, vfloat<N> r0, vfloat<N> k, vfloat<N> tmin,
                                        vfloat<N> tmax, vfloat<N>& tHit, ConeOf&& coneOf)
{
  const vfloat<N> zero(0.0f);
  vbool<N> miss = !(H > zero);
  const vfloat<N> ds = Dot3N<N>(dir, w);
  const vfloat<N> os = Dot3N<N>(dl, w);
  vfloat<N> dR[3], oR[3];
  for (int i = 0; i < 3; ++i) {
    dR[i] = dir[i] - ds * w[i];
    oR[i] = dl[i] - os * w[i];
  }
  const vfloat<N> rb = r0 + k * os;
  const vfloat<N> A = Dot3N<N>(dR, dR) - k * k * ds * ds;
  const vfloat<N> Bh = Dot3N<N>(oR, dR) - k * ds * rb;
  const vfloat<N> oo = Dot3N<N>(oR, oR);
  const vfloat<N> C = oo - rb * rb;
  // A == 0: the linear case.
  const vbool<N> linear = A == zero;
  const vfloat<N> tLin = -C / (vfloat<N>(2.0f) * Bh);
  vfloat<N> t0, t1;
  vbool<N> quadMiss, refine(false);
  if constexpr (kFast) {
    const vfloat<N> disc4 = vfloat<N>(4.0f) * Bh * Bh - vfloat<N>(4.0f) * A * C;
    quadMiss = disc4 < zero;
    const vfloat<N> sq = Sqrt(disc4);
    const vfloat<N> ta = (vfloat<N>(-2.0f) * Bh - sq) / (vfloat<N>(2.0f) * A);
    const vfloat<N> tb = (vfloat<N>(-2.0f) * Bh + sq) / (vfloat<N>(2.0f) * A);
    t0 = FMin(ta, tb);
    t1 = FMax(ta, tb);
  } else {
    vfloat<N> e[3], x[3];
    for (int i = 0; i < 3; ++i) e[i] = rb * dR[i] - k * ds * oR[i];
    x[0] = oR[1] * dR[2] - oR[2] * dR[1];
    x[1] = oR[2] * dR[0] - oR[0] * dR[2];
    x[2] = oR[0] * dR[1] - oR[1] * dR[0];
    const vfloat<N> ee = Dot3N<N>(e, e), xx = Dot3N<N>(x, x);
    const vfloat<N> disc = ee - xx;
    quadMiss = disc < zero;
    // A discriminant within its rounding of 0: decided in double-float.
    const vbool<N> undecided = AndNot(quadMiss & (-disc <= vfloat<N>(0x1.0p-20f) * (ee + xx)), miss | linear);
    // Skip the square root and divisions when every lane misses already.
    if (None(undecided) && All(miss | (linear & (Bh == zero)) | AndNot(quadMiss, linear))) {
      tHit = zero;
      return vbool<N>(false);
    }
    vfloat<N> q;
    Quadratic_RootsN<N>(A, Bh, C, oo + rb * rb, disc, t0, t1, q);
    refine = AndNot(Cone_NeedsDfN<N>(C, oo + rb * rb, Bh, disc, ee, xx, q, Dot3N<N>(dl, dl), oo, k, ds, rb,
                                    Dot3N<N>(dR, dR), Dot3N<N>(dir, dir), A, t0, t1, tmin, tmax),
                    miss | linear | quadMiss) |
             undecided;
  }
  t0 = Select(linear, tLin, t0);
  t1 = Select(linear, tLin, t1);
  miss = miss | (linear & (Bh == zero)) | AndNot(quadMiss, linear);
  const vfloat<N> s0 = os + t0 * ds;
  const vfloat<N> s1 = os + t1 * ds;
  const vbool<N> ok0 = (t0 >= tmin) & (t0 <= tmax) & (s0 >= zero) & (s0 <= H);
  const vbool<N> ok1 = (t1 >= tmin) & (t1 <= tmax) & (s1 >= zero) & (s1 <= H);
  tHit = Select(ok0, t0, t1);
  vbool<N> ok = AndNot(ok0 | ok1, miss);
  if constexpr (!kFast) {
    if (Any(refine)) {
      const RefinedLanes<N> r = RefineLanesN<N>(refine.Bits(), [=](int l, float* th) {
        const Cone* cn = coneOf(l);
        if (!cn) return false;
        float o[3], d[3];
        Lane3<N>(org, l, o);
        Lane3<N>(dir, l, d);
        return Cone_IntersectDf(o, d, cn, tmin[l], tmax[l], th) != 0;
      }, tHit, ok);
      tHit = r.t;
      ok = r.ok;
    }
  }
  return ok;
}

}  // namespace cr::simd::CR_SIMD_NS
