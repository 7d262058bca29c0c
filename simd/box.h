// The axis-aligned box in the SIMD kernels: its pack (the scene's Box rows
// are read as they are), the lane-wise Box_Hit of kernels/box.h and its
// three forms (SimdTest<Box>, simd/prims.h).
#pragma once

#include <cstdint>

#include "simd/simd_kernels.h"

namespace cr::simd {

template <int K>
struct BoxPack {  // 28 K bytes
  float lo[3][K];
  float hi[3][K];
  std::uint32_t g[K];
};

template <>
struct SimdPrim<Box> {
  using Data = Box;
  template <int K>
  using Pack = BoxPack<K>;
  static constexpr bool kDistanceTies = false;
  template <int K>
  CR_SIMD_HOST_INLINE static void Fill(Pack<K>& p, int l, const Data& b)
  {
    for (int a = 0; a < 3; ++a) {
      p.lo[a][l] = b.lo[a];
      p.hi[a][l] = b.hi[a];
    }
  }
};

}  // namespace cr::simd

#ifdef CR_SIMD_NS
namespace cr::simd::CR_SIMD_NS {

// Box_Hit of kernels/box.h, lane by lane: the slab parameters (divided in
// robust mode, multiplied by the reciprocal 1 / dir in fast mode, as
// Ray_Init rounds it), fmin/fmax passing over NaN, the entry or, from
// inside, the exit.
template <bool kFast, int N>
CR_SIMD_INLINE vbool<N> Box_HitN(const vfloat<N> org[3], const vfloat<N> dir[3], const vfloat<N> lo[3],
                                 const vfloat<N> hi[3], vfloat<N> tmin, vfloat<N> tmax, vfloat<N>& tHit)
{
  vfloat<N> tn(-__builtin_inff()), tf(__builtin_inff());
  for (int a = 0; a < 3; ++a) {
    vfloat<N> t0, t1;
    if constexpr (kFast) {
      const vfloat<N> inv = vfloat<N>(1.0f) / dir[a];
      t0 = (lo[a] - org[a]) * inv;
      t1 = (hi[a] - org[a]) * inv;
    } else {
      t0 = (lo[a] - org[a]) / dir[a];
      t1 = (hi[a] - org[a]) / dir[a];
    }
    tn = FMax(tn, FMin(t0, t1));
    tf = FMin(tf, FMax(t0, t1));
  }
  const vfloat<N> t = Select(tn >= tmin, tn, tf);
  tHit = t;
  return (tn <= tf) & (t >= tmin) & (t <= tmax);
}

template <>
struct SimdTest<Box> {
  template <int N, bool kFast>
  CR_SIMD_INLINE static vbool<N> Packet(const KernelScene& sc, std::uint32_t g, const RayPacket<N>& P, vbool<N>,
                                        vfloat<N> tmax,
                                        vfloat<N>& t, vfloat<N>&, vfloat<N>&)
  {
    const Box& b = PrimData<Box>(sc)[Prim_Local(&sc.ranges, CR_PRIM_BOX, g)];
    vfloat<N> lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = vfloat<N>(b.lo[a]);
      hi[a] = vfloat<N>(b.hi[a]);
    }
    return Box_HitN<kFast, N>(P.org, P.dir, lo, hi, P.tmin, tmax, t);
  }
  template <int K, bool kFast>
  CR_SIMD_INLINE static vbool<K> Pack(const KernelScene&, const BoxPack<K>& pk, vbool<K>, const PackRay<K>& pr,
                                      vfloat<K> tmax, vfloat<K>& t, vfloat<K>&, vfloat<K>&)
  {
    vfloat<K> lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = vfloat<K>::Load(pk.lo[a]);
      hi[a] = vfloat<K>::Load(pk.hi[a]);
    }
    return Box_HitN<kFast, K>(pr.org, pr.dir, lo, hi, pr.tmin, tmax, t);
  }
  // Box rows: (lo, pad), (hi, pad).
  template <bool kFast>
  CR_SIMD_INLINE static vbool<4> Gather(const KernelScene& sc, const std::uint32_t g[4], const PackRay<4>& pr,
                                        vfloat<4> tmax, vfloat<4>& t, vfloat<4>&, vfloat<4>&)
  {
    const Box* b[4];
    for (int l = 0; l < 4; ++l) b[l] = &PrimData<Box>(sc)[Prim_Local(&sc.ranges, CR_PRIM_BOX, g[l])];
    const float* rows[4];
    vfloat<4> lo[4], hi[4];
    for (int l = 0; l < 4; ++l) rows[l] = b[l]->lo;
    LoadTransposed4(rows, lo);
    for (int l = 0; l < 4; ++l) rows[l] = b[l]->hi;
    LoadTransposed4(rows, hi);
    return Box_HitN<kFast, 4>(pr.org, pr.dir, lo, hi, pr.tmin, tmax, t);
  }
};

}  // namespace cr::simd::CR_SIMD_NS
#endif
