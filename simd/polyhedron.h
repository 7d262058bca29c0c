// The convex polyhedron in the SIMD kernels. Its planes vary in number from
// one polyhedron to the next (up to 32, 528 bytes a record), so its pack
// holds the primitives' indices only and each lane runs the scalar kernels'
// test (kernels/polyhedron.h: Polyhedron_IntersectR in fast mode,
// Polyhedron_IntersectRobust in robust mode) on the scene's record: every lane
// gets the scalar kernel's bits. Not vectorised across lanes: a first form,
// measured in docs/BENCHMARKS.md.
#pragma once

#include <cstdint>

#include "simd/simd_kernels.h"

namespace cr::simd {

template <int K>
struct PolyhedronPack {  // 4 K bytes
  std::uint32_t g[K];
};

template <>
struct SimdPrim<Polyhedron> {
  using Data = Polyhedron;
  template <int K>
  using Pack = PolyhedronPack<K>;
  static constexpr bool kDistanceTies = false;
  template <int K>
  CR_SIMD_HOST_INLINE static void Fill(Pack<K>&, int, const Data&)
  {
  }
};

}  // namespace cr::simd

#ifdef CR_SIMD_NS
namespace cr::simd::CR_SIMD_NS {

// The scalar test of one lane: ray l of org/dir against polyhedron p.
template <bool kFast, int N>
CR_SIMD_INLINE bool Polyhedron_Lane(const vfloat<N> org[3], const vfloat<N> dir[3], const vfloat<N>& tmin,
                                    const vfloat<N>& tmax, int l, const Polyhedron& p, float* th)
{
  float o[3], d[3];
  Lane3<N>(org, l, o);
  Lane3<N>(dir, l, d);
  if constexpr (kFast)
    return Polyhedron_IntersectR(o, d, &p, tmin[l], tmax[l], th) != 0;
  else
    return Polyhedron_IntersectRobust(o, d, &p, tmin[l], tmax[l], th) != 0;
}

// Runs test(l, &t) for the lanes of `bits`; the lanes that hit, with t.
template <int N, class Test>
CR_SIMD_INLINE vbool<N> Polyhedron_Lanes(unsigned bits, Test test, vfloat<N>& tHit)
{
  alignas(32) float t[N] = {};
  unsigned ok = 0u;
  for (; bits; bits &= bits - 1) {
    const int l = LowestBit(bits);
    if (test(l, &t[l])) ok |= 1u << l;
  }
  tHit = vfloat<N>::Load(t);
  return vbool<N>::FromBits(ok);
}

template <>
struct SimdTest<Polyhedron> {
  template <int N, bool kFast>
  CR_SIMD_INLINE static vbool<N> Packet(const KernelScene& sc, std::uint32_t g, const RayPacket<N>& P, vbool<N> lanes,
                                        vfloat<N> tmax, vfloat<N>& t, vfloat<N>&, vfloat<N>&)
  {
    const Polyhedron& p = PrimData<Polyhedron>(sc)[Prim_Local(&sc.ranges, CR_PRIM_POLYHEDRON, g)];
    return Polyhedron_Lanes<N>(
        lanes.Bits(), [&](int l, float* th) { return Polyhedron_Lane<kFast, N>(P.org, P.dir, P.tmin, tmax, l, p, th); },
        t);
  }
  template <int K, bool kFast>
  CR_SIMD_INLINE static vbool<K> Pack(const KernelScene& sc, const PolyhedronPack<K>& pk, vbool<K> valid,
                                      const PackRay<K>& pr, vfloat<K> tmax, vfloat<K>& t, vfloat<K>&, vfloat<K>&)
  {
    return Polyhedron_Lanes<K>(
        valid.Bits(),
        [&](int l, float* th) {
          const Polyhedron& p = PrimData<Polyhedron>(sc)[Prim_Local(&sc.ranges, CR_PRIM_POLYHEDRON, pk.g[l])];
          return Polyhedron_Lane<kFast, K>(pr.org, pr.dir, pr.tmin, tmax, l, p, th);
        },
        t);
  }
  template <bool kFast>
  CR_SIMD_INLINE static vbool<4> Gather(const KernelScene& sc, const std::uint32_t g[4], const PackRay<4>& pr,
                                        vfloat<4> tmax, vfloat<4>& t, vfloat<4>&, vfloat<4>&)
  {
    return Polyhedron_Lanes<4>(
        0xFu,
        [&](int l, float* th) {
          const Polyhedron& p = PrimData<Polyhedron>(sc)[Prim_Local(&sc.ranges, CR_PRIM_POLYHEDRON, g[l])];
          return Polyhedron_Lane<kFast, 4>(pr.org, pr.dir, pr.tmin, tmax, l, p, th);
        },
        t);
  }
};

}  // namespace cr::simd::CR_SIMD_NS
#endif
