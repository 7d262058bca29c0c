// Motion blur in the SIMD kernels (kernels/motion.h): a moving piece at ray
// time tau is its static record translated by tau * motion, so its test
// runs on the ray shifted into the piece's rest frame, origin - time *
// motion, the same direction (inverse, shear constants, dominant axes and
// direction signs unchanged). The structures hold moving pieces in their
// swept boxes, so only the primitive tests shift, lane by lane as
// Motion_Shift shifts the scalar ray: a lane keeps its origin where the
// piece does not move (all three components 0) or the ray's time is 0, and
// otherwise takes org[a] - time * m[a] (a multiply and a subtraction: the
// ISA units do not contract into FMA).
//
// Only the kernels of a moving scene call these: the type set kAllTypes |
// kMotionBit (kHasMotion), instantiated in units of their own
// (kernels_motion_*.cpp), so the static scenes' kernels and the code the
// compiler makes of them are untouched. Their rays carry times in the
// Timed* forms below; the static kernels' rays keep their layout.
#pragma once

#include <type_traits>

#include "simd/rays.h"
#include "simd/simd_kernels.h"

namespace cr::simd::CR_SIMD_NS {

// A moving scene's rays: each lane's time (Ray::time) with the ray.
template <int N>
struct TimedRayPacket : RayPacket<N> {
  vfloat<N> time;
};
template <int K>
struct TimedPackRay : PackRay<K> {
  float time;
};
// The ray forms of a kernel (kMotion: a moving scene's).
template <int N, bool kMotion>
using RayPacketOf = std::conditional_t<kMotion, TimedRayPacket<N>, RayPacket<N>>;
template <int K, bool kMotion>
using PackRayOf = std::conditional_t<kMotion, TimedPackRay<K>, PackRay<K>>;
// The times of a moving scene's rays, which are always of the Timed forms
// (RayPacketOf, PackRayOf with kMotion), whatever reference they pass by.
template <int N>
CR_SIMD_INLINE vfloat<N> RayPacket_Time(const RayPacket<N>& P)
{
  return static_cast<const TimedRayPacket<N>&>(P).time;
}
template <int K>
CR_SIMD_INLINE float PackRay_Time(const PackRay<K>& pr)
{
  return static_cast<const TimedPackRay<K>&>(pr).time;
}

// The time of ray i of the job (KernelJob::times; none: 0).
CR_SIMD_INLINE float Job_Time(const KernelJob& job, std::uint32_t i) { return job.times ? job.times[i] : 0.0f; }

// The times of a packet's rays idx[0, count); padding lanes repeat lane 0,
// as their records do (Job_Rays).
template <int N>
CR_SIMD_INLINE vfloat<N> Job_Times(const KernelJob& job, const std::uint32_t idx[N], int count)
{
  if (!job.times) return vfloat<N>(0.0f);
  alignas(32) float t[N];
  for (int l = 0; l < N; ++l) t[l] = job.times[idx[l < count ? l : 0]];
  return vfloat<N>::Load(t);
}

// Motion of piece g (KernelScene::motion), in m; false when it does not move
// (Motion_Shift's test).
CR_SIMD_INLINE bool Motion_Of(const KernelScene& sc, std::uint32_t g, float m[3])
{
  const float* p = sc.motion + 4u * g;
  m[0] = p[0];
  m[1] = p[1];
  m[2] = p[2];
  return !(m[0] == 0.0f && m[1] == 0.0f && m[2] == 0.0f);
}

// A packet (a TimedRayPacket) as one moving piece, of motion m, sees it: q
// is P with each lane's origin shifted (the lanes at time 0 keep theirs),
// and the origin's permuted components orgK picked again as RayPacket_Init
// picks them.
template <int N>
CR_SIMD_INLINE void RayPacket_Shift(const RayPacket<N>& P, const float m[3], RayPacket<N>& q)
{
  q = P;
  const vfloat<N> time = RayPacket_Time<N>(P);
  const vbool<N> still = time == vfloat<N>(0.0f);
  for (int a = 0; a < 3; ++a) q.org[a] = Select(still, P.org[a], P.org[a] - time * vfloat<N>(m[a]));
  if (P.kUniform) {
    for (int j = 0; j < 3; ++j) q.orgK[j] = q.org[P.kScalar[j]];
  } else {
    const vint<N> k0(0), k1(1);
    for (int j = 0; j < 3; ++j)
      q.orgK[j] = Select(P.k[j] == k0, q.org[0], Select(P.k[j] == k1, q.org[1], q.org[2]));
  }
}

// The motions of the K pieces g[0, K) (lane l: piece g[l]; the lanes not in
// `valid`, padding, read piece 0's), and the lanes whose piece moves.
template <int K>
CR_SIMD_INLINE vbool<K> Motion_OfK(const KernelScene& sc, const std::uint32_t* g, vbool<K> valid, vfloat<K> m[3])
{
  const unsigned validBits = valid.Bits();
  if constexpr (K == 4) {
    const float* rows[4];
    for (int l = 0; l < 4; ++l) rows[l] = sc.motion + 4u * ((validBits >> l) & 1u ? g[l] : 0u);
    vfloat<4> r[4];
    LoadTransposed4(rows, r);
    for (int a = 0; a < 3; ++a) m[a] = r[a];
  } else {
    alignas(32) float c[3][K];
    for (int l = 0; l < K; ++l) {
      const float* p = sc.motion + 4u * ((validBits >> l) & 1u ? g[l] : 0u);
      for (int a = 0; a < 3; ++a) c[a][l] = p[a];
    }
    for (int a = 0; a < 3; ++a) m[a] = vfloat<K>::Load(c[a]);
  }
  const vfloat<K> zero(0.0f);
  return AndNot(valid, (m[0] == zero) & (m[1] == zero) & (m[2] == zero));
}

// One ray (a TimedPackRay) as each of K pieces g[0, K) sees it: q is pr
// with lane l's origin shifted by piece g[l]'s motion (the lanes of static
// pieces, or not in `valid`, keep it). False, q untouched, when no lane
// shifts: the test takes pr itself.
template <int K>
CR_SIMD_INLINE bool PackRay_Shift(const KernelScene& sc, const std::uint32_t* g, vbool<K> valid, const PackRay<K>& pr,
                                  PackRay<K>& q)
{
  const float t = PackRay_Time<K>(pr);
  if (t == 0.0f) return false;
  vfloat<K> m[3];
  const vbool<K> moving = Motion_OfK<K>(sc, g, valid, m);
  if (None(moving)) return false;
  q = pr;
  const vfloat<K> time(t);
  for (int a = 0; a < 3; ++a) q.org[a] = Select(moving, pr.org[a] - time * m[a], pr.org[a]);
  for (int j = 0; j < 3; ++j) q.orgK[j] = q.org[pr.k[j]];
  return true;
}

}  // namespace cr::simd::CR_SIMD_NS
