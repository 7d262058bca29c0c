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

// Box_Slabs for one ray and one box (lo, hi), scalar: Box_Intersect from
// tmin up to the closest hit's Cull_Distance, its operations in its order;
// the entry parameter in tEnter. A NaN near or far distance (0 * inf on a
// plane-parallel ray from the plane) keeps the other, as fmax/fmin do.
template <bool kFast, class R>
CR_SIMD_INLINE bool Box_SlabsOne(const float* lo, const float* hi, const R& ray, float tmin, float hitT,
                                 float& tEnter)
{
  float boxNear = -__builtin_inff(), boxFar = __builtin_inff();
  for (int a = 0; a < 3; ++a) {
    const float l = (lo[a] - ray.org[a]) * ray.inv[a];
    const float h = (hi[a] - ray.org[a]) * ray.inv[a];
    const bool neg = ray.inv[a] < 0.0f;
    const float tNear = neg ? h : l, tFar = neg ? l : h;
    boxNear = tNear > boxNear ? tNear : boxNear;
    boxFar = tFar < boxFar ? tFar : boxFar;
  }
  if constexpr (!kFast) boxFar = boxFar * 1.0000004f;
  const float cull = CullDistance<kFast>(hitT);
  tEnter = boxNear > tmin ? boxNear : tmin;
  return tEnter <= (boxFar < cull ? boxFar : cull);
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
  // Select(stable, c / q, (sq - bh) / a) with one division: the lane's
  // quotient is the same either way.
  const vbool<N> stable = vfloat<N>(16.0f) * q * q >= a * cScale;
  const vfloat<N> r1 = Select(stable, c, sq - bh) / Select(stable, q, a);
  t0 = FMin(r0, r1);
  t1 = FMax(r0, r1);
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

}  // namespace cr::simd::CR_SIMD_NS
