// Primitive types whose SIMD form runs the scalar kernels' test lane by lane
// (the convex polyhedron, the SDF block, the CSG solid): their records vary in size or in
// work per ray (planes, march steps) and do not fit a vector pack, so the
// pack holds the primitives' indices and each lane calls the scalar test on
// the scene's record: every lane gets the scalar kernel's bits. A type
// derives SimdPrim<T> from LanewisePrim<T> and SimdTest<T> from
// LanewiseTest<T, CR_PRIM_..., Scalar>, Scalar::Run<kFast>(o, d, p, tmin,
// tmax, &t, &u, &v) being its scalar test.
#pragma once

#include <cstdint>

#include "simd/simd_kernels.h"

namespace cr::simd {

template <int K>
struct IndexPack {  // 4 K bytes
  std::uint32_t g[K];
};

template <class T>
struct LanewisePrim {
  using Data = T;
  template <int K>
  using Pack = IndexPack<K>;
  static constexpr bool kDistanceTies = false;
  template <int K>
  CR_SIMD_HOST_INLINE static void Fill(Pack<K>&, int, const Data&)
  {
  }
};

}  // namespace cr::simd

#ifdef CR_SIMD_NS
namespace cr::simd::CR_SIMD_NS {

// Runs test(l, &t, &u, &v) for the lanes of `bits`; the lanes that hit,
// with t, u and v.
template <int N, class Test>
CR_SIMD_INLINE vbool<N> LanewiseRun(unsigned bits, Test test, vfloat<N>& tHit, vfloat<N>& uHit, vfloat<N>& vHit)
{
  alignas(32) float t[N] = {};
  alignas(32) float u[N] = {};
  alignas(32) float v[N] = {};
  unsigned ok = 0u;
  for (; bits; bits &= bits - 1) {
    const int l = LowestBit(bits);
    if (test(l, &t[l], &u[l], &v[l])) ok |= 1u << l;
  }
  tHit = vfloat<N>::Load(t);
  uHit = vfloat<N>::Load(u);
  vHit = vfloat<N>::Load(v);
  return vbool<N>::FromBits(ok);
}

template <class T, std::uint32_t kType, class Scalar>
struct LanewiseTest {
  // The scalar test of one lane: ray l of org/dir against primitive p.
  template <bool kFast, int N>
  CR_SIMD_INLINE static bool Lane(const vfloat<N> org[3], const vfloat<N> dir[3], const vfloat<N>& tmin,
                                  const vfloat<N>& tmax, int l, const T& p, float* th, float* tu, float* tv)
  {
    float o[3], d[3];
    Lane3<N>(org, l, o);
    Lane3<N>(dir, l, d);
    return Scalar::template Run<kFast>(o, d, p, tmin[l], tmax[l], th, tu, tv);
  }
  CR_SIMD_INLINE static const T& Record(const KernelScene& sc, std::uint32_t g)
  {
    return PrimData<T>(sc)[Prim_Local(&sc.ranges, kType, g)];
  }
  template <int N, bool kFast>
  CR_SIMD_INLINE static vbool<N> Packet(const KernelScene& sc, std::uint32_t g, const RayPacket<N>& P, vbool<N> lanes,
                                        vfloat<N> tmax, vfloat<N>& t, vfloat<N>& u, vfloat<N>& v)
  {
    const T& p = Record(sc, g);
    return LanewiseRun<N>(
        lanes.Bits(),
        [&](int l, float* th, float* tu, float* tv) { return Lane<kFast, N>(P.org, P.dir, P.tmin, tmax, l, p, th, tu, tv); },
        t, u, v);
  }
  template <int K, bool kFast>
  CR_SIMD_INLINE static vbool<K> Pack(const KernelScene& sc, const IndexPack<K>& pk, vbool<K> valid,
                                      const PackRay<K>& pr, vfloat<K> tmax, vfloat<K>& t, vfloat<K>& u, vfloat<K>& v)
  {
    return LanewiseRun<K>(
        valid.Bits(),
        [&](int l, float* th, float* tu, float* tv) {
          return Lane<kFast, K>(pr.org, pr.dir, pr.tmin, tmax, l, Record(sc, pk.g[l]), th, tu, tv);
        },
        t, u, v);
  }
  template <bool kFast>
  CR_SIMD_INLINE static vbool<4> Gather(const KernelScene& sc, const std::uint32_t g[4], const PackRay<4>& pr,
                                        vfloat<4> tmax, vfloat<4>& t, vfloat<4>& u, vfloat<4>& v)
  {
    return LanewiseRun<4>(
        0xFu,
        [&](int l, float* th, float* tu, float* tv) {
          return Lane<kFast, 4>(pr.org, pr.dir, pr.tmin, tmax, l, Record(sc, g[l]), th, tu, tv);
        },
        t, u, v);
  }
};

}  // namespace cr::simd::CR_SIMD_NS
#endif
