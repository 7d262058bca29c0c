// The sphere in the SIMD kernels: its pack (the scene's Sphere rows are
// read as they are), the lane-wise Sphere_Intersect of kernels/sphere.h and
// its three forms (SimdTest<Sphere>, simd/prims.h).
#pragma once

#include <cstdint>

#include "simd/simd_kernels.h"

namespace cr::simd {

template <int K>
struct SpherePack {  // 20 K bytes
  float center[3][K];
  float radius[K];
  std::uint32_t g[K];
};

template <>
struct SimdPrim<Sphere> {
  using Data = Sphere;
  template <int K>
  using Pack = SpherePack<K>;
  static constexpr bool kDistanceTies = true;  // Hit_CloserOn (kernels/intersect.h)
  template <int K>
  CR_SIMD_HOST_INLINE static void Fill(Pack<K>& p, int l, const Data& s)
  {
    for (int a = 0; a < 3; ++a) p.center[a][l] = s.center[a];
    p.radius[l] = s.radius;
  }
};

}  // namespace cr::simd

#ifdef CR_SIMD_NS
namespace cr::simd::CR_SIMD_NS {

// Sphere_NeedsDf of kernels/sphere.h, lane by lane, for the lanes not in
// `miss` (the scalar test returns before it on a miss; here a missing lane,
// disc < 0, would pass the cancellation rule and cost the windows of the
// whole vector).
template <int N>
CR_SIMD_INLINE vbool<N> Sphere_NeedsDfN(vfloat<N> c, vfloat<N> cScale, vfloat<N> bh, vfloat<N> disc,
                                        vfloat<N> dScale, vfloat<N> q, vfloat<N> a, vfloat<N> ff, vfloat<N> cc,
                                        vfloat<N> t0, vfloat<N> t1, vfloat<N> tmin, vfloat<N> tmax, vbool<N> miss,
                                        bool anyHit)
{
  const vfloat<N> dd = disc * (bh * bh + disc);
  const vfloat<N> ds2 = dScale * dScale;
  const vbool<N> inaccurate =
      AndNot((cScale > vfloat<N>(8.0f) * Abs(c)) | (ds2 > vfloat<N>(64.0f) * dd), miss);
  if (None(inaccurate)) return inaccurate;
  const vbool<N> always = (ds2 > vfloat<N>(0x1.0p36f) * dd) | !(disc > vfloat<N>(0.0f));
  const vfloat<N> af = a * ff;
  const vfloat<N> eq = vfloat<N>(0x1.0p-20f) * ((Sqrt(af * cc) + dScale) / Sqrt(disc) + Sqrt(af));
  const vfloat<N> rel = eq / Abs(q) + vfloat<N>(0x1.0p-20f);
  const vfloat<N> e = vfloat<N>(0x1.0p-20f) * cScale / Abs(q);
  const vfloat<N> m = Select(vfloat<N>(16.0f) * q * q >= a * cScale, vfloat<N>(0.0f), FMax(Abs(t0), Abs(t1)));
  const vfloat<N> s0 = rel * FMax(Abs(t0), m) + e, s1 = rel * FMax(Abs(t1), m) + e;
  vbool<N> window = ((t0 + s0 >= tmin) & (t0 - s0 <= tmax)) | ((t1 + s1 >= tmin) & (t1 - s1 <= tmax));
  if (anyHit)
    window = AndNot(window, ((t0 - s0 > tmin) & (t0 + s0 < tmax)) | ((t1 - s1 > tmin) & (t1 + s1 < tmax)));
  return inaccurate & (always | window);
}

// Sphere_Intersect: nearest root in [tmin, tmax]; f = org - cen; a = d.d
// (Dot3N(dir, dir), computed once per ray by the caller). Where the float
// discriminant is within its error bound (Sphere_DiscUndecided) or the roots
// may be off (Sphere_NeedsDf), the lane takes the scalar kernels' cold
// tests (Sphere_IntersectUndecided, Sphere_IntersectDf). Only the lanes in
// `lanes` (those the traversal asks) take them.
template <bool kFast, int N>
CR_SIMD_INLINE vbool<N> Sphere_IntersectN(const vfloat<N> org[3], const vfloat<N> cen[3], const vfloat<N> dir[3],
                                          vfloat<N> a, vfloat<N> rad, vfloat<N> tmin, vfloat<N> tmax, vfloat<N>& tHit,
                                          bool anyHit, vbool<N> lanes)
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
    if (None(AndNot(lanes, disc < vfloat<N>(-0x1.0p15f) * Q))) {
      tHit = vfloat<N>(0.0f);
      return vbool<N>(false);
    }
    // Undecided lanes (Sphere_DiscUndecided) and lanes whose roots may be
    // off (Sphere_NeedsDf) take the double-float test.
    const vbool<N> undecided = lanes & (disc * disc <= Q * (cc + vfloat<N>(0x1.0p-9f) * Q));
    miss = (disc < vfloat<N>(0.0f)) | !lanes;
    if (All(AndNot(miss, undecided))) {
      tHit = vfloat<N>(0.0f);
      return vbool<N>(false);
    }
    vfloat<N> q;
    Quadratic_RootsN<N>(a, bh, c, ff + rad * rad, disc, t0, t1, q);
    const vbool<N> refine =
        undecided | Sphere_NeedsDfN<N>(c, ff + rad * rad, bh, disc, ar2 + cc, q, a, ff, cc, t0, t1, tmin, tmax, miss, anyHit);
    if (Any(refine)) {
      const vbool<N> in0 = (t0 >= tmin) & (t0 <= tmax);
      const vbool<N> in1 = (t1 >= tmin) & (t1 <= tmax);
      tHit = Select(in0, t0, t1);
      vbool<N> ok = AndNot(in0 | in1, miss);
      const unsigned undecidedBits = undecided.Bits();
      const RefinedLanes<N> r = RefineLanesN<N>(refine.Bits(), [=](int l, float* th) {
        float o[3], d[3];
        Lane3<N>(org, l, o);
        Lane3<N>(dir, l, d);
        Sphere sp;
        Lane3<N>(cen, l, sp.center);
        sp.radius = rad[l];
        if (undecidedBits >> l & 1u)
          return Sphere_IntersectUndecided(o, d, &sp, tmin[l], tmax[l], ar2[l], Q[l], th) != 0;
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


template <>
struct SimdTest<Sphere> {
  // Sphere g (unified index; spheres come first, so it is also the local
  // index) against the rays of the packet.
  template <int N, bool kFast>
  CR_SIMD_INLINE static vbool<N> Packet(const KernelScene& sc, std::uint32_t g, const RayPacket<N>& P, vbool<N> m,
                                        vfloat<N> tmax,
                                        vfloat<N>& t, vfloat<N>&, vfloat<N>&)
  {
    const Sphere& sp = PrimData<Sphere>(sc)[g];
    const vfloat<N> cen[3] = {vfloat<N>(sp.center[0]), vfloat<N>(sp.center[1]), vfloat<N>(sp.center[2])};
    return Sphere_IntersectN<kFast, N>(P.org, cen, P.dir, P.dd, vfloat<N>(sp.radius), P.tmin, tmax, t, P.anyHit, m);
  }
  // The K spheres of a pack against one ray.
  template <int K, bool kFast>
  CR_SIMD_INLINE static vbool<K> Pack(const KernelScene&, const SpherePack<K>& pk, vbool<K> valid, const PackRay<K>& pr,
                                      vfloat<K> tmax, vfloat<K>& t, vfloat<K>&, vfloat<K>&)
  {
    vfloat<K> cen[3];
    for (int i = 0; i < 3; ++i) cen[i] = vfloat<K>::Load(pk.center[i]);
    return Sphere_IntersectN<kFast, K>(pr.org, cen, pr.dir, pr.dd, vfloat<K>::Load(pk.radius), pr.tmin, tmax, t,
                                       pr.anyHit, valid);
  }
  // Spheres g[0..4) gathered from the scene's rows by a 4x4 transpose.
  template <bool kFast>
  CR_SIMD_INLINE static vbool<4> Gather(const KernelScene& sc, const std::uint32_t g[4], const PackRay<4>& pr,
                                        vfloat<4> tmax, vfloat<4>& t, vfloat<4>&, vfloat<4>&)
  {
    const float* rows[4];
    for (int l = 0; l < 4; ++l) rows[l] = PrimData<Sphere>(sc)[g[l]].center;
    vfloat<4> s[4];
    LoadTransposed4(rows, s);
    return Sphere_IntersectN<kFast, 4>(pr.org, s, pr.dir, pr.dd, s[3], pr.tmin, tmax, t, pr.anyHit,
                                       vbool<4>(true));
  }
};

}  // namespace cr::simd::CR_SIMD_NS
#endif
