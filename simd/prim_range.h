// A range of references refs[begin, end) (a cell, a leaf) tested
// type by type. References are unified indices sorted ascending, so the
// types come in runs (in CR_PRIM_TYPES order, kernels/types.h):
// each run is found once and tested with a loop of one type, and only the
// types in kTypes are compiled. No per-primitive type test.
//
// Two forms, both lane by lane the scalar intersectors of kernels/intersect.h
// and, per lane, the scalar loop's answer:
//  - PacketRefs_Intersect: N rays, one primitive at a time (packets);
//  - RayRefs_Intersect: one ray, K = 4 primitives at a time, gathered from
//    the types' rows (SimdPrim<T>::Data, rows of 16 bytes) by
//    4x4 transposes, so the cell walks need no structure-of-arrays
//    copy of the geometry (the BVH's single-ray path keeps packs instead,
//    docs/SIMD.md compares the memory).
// The K hits of a group are reduced in Hit_Closer order (nearer t, then the
// lower lane, which is the lower g), so testing K at once against the same
// current hit gives the sequential loop's closest hit; an occlusion query
// takes the group's first occluder in reference order, the scalar loop's.
#pragma once

#include "simd/bvh_packet.h"
#include "simd/bvh_single.h"
#include "simd/kernel_common.h"

namespace cr::simd::CR_SIMD_NS {

// End of the run of type k that starts at refs[i] (i <= end).
template <unsigned kTypes, unsigned k>
CR_SIMD_INLINE std::uint32_t Refs_RunEnd(const std::uint32_t* refs, std::uint32_t i, std::uint32_t end,
                                         const PrimRanges& c)
{
  if constexpr (IsLastType<kTypes>(k)) return end;
  const std::uint32_t bound = Prim_End(&c, k);
  while (i < end && refs[i] < bound) ++i;
  return i;
}

// The primitives of refs[i, e), all of type T, against the lanes of m.
// Occlusion (anyHit): a lane leaves m at its first hit and joins `done`.
// kMotion: a moving scene's (PacketPrim_IntersectAs).
template <int N, class T, bool kFast, bool kStats, bool kMotion>
CR_SIMD_INLINE void PacketRun_Intersect(const KernelScene& sc, const std::uint32_t* refs, std::uint32_t i,
                                        std::uint32_t e, const RayPacket<N>& P, HitPacket<N>& H, vbool<N>& m,
                                        int anyHit, unsigned& done, TraceStatsSum& st)
{
  for (; i < e; ++i) {
    if constexpr (kStats) st.nIT += PopCount(m.Bits());
    const vbool<N> changed = PacketPrim_IntersectAs<N, T, kFast, kMotion>(sc, refs[i], P, H, m);
    if (anyHit) {
      const unsigned cb = changed.Bits();
      if (cb) {
        done |= cb;
        m = AndNot(m, changed);
        if (None(m)) return;
      }
    }
  }
}

// refs[begin, end) against the lanes of m (see PacketRun_Intersect), run by
// run.
template <int N, unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void PacketRefs_Intersect(const KernelScene& sc, const std::uint32_t* refs, std::uint32_t begin,
                                         std::uint32_t end, const RayPacket<N>& P, HitPacket<N>& H, vbool<N> m,
                                         int anyHit, unsigned& done, TraceStatsSum& st)
{
  std::uint32_t i = begin;
#define CR_SIMD_PACKET_RUN_(T, U, a)                                                                           \
  if constexpr ((kTypes >> CR_PRIM_##U) & 1u) {                                                                \
    const std::uint32_t e = Refs_RunEnd<kTypes, CR_PRIM_##U>(refs, i, end, sc.ranges);                         \
    if (i < e && Any(m))                                                                                       \
      PacketRun_Intersect<N, T, kFast, kStats, kHasMotion<kTypes>>(sc, refs, i, e, P, H, m, anyHit, done, st); \
    i = e;                                                                                                     \
  }
  CR_PRIM_TYPES(CR_SIMD_PACKET_RUN_)
#undef CR_SIMD_PACKET_RUN_
}

// One ray against the primitives of refs[i, e), all of type T, 4 at a time
// (SimdTest<T>::Gather). Returns true when the hit changed (occlusion: at
// the first change). kMotion (a moving scene): each lane's piece meets the
// ray shifted into its rest frame (PackRay_Shift).
template <class T, bool kFast, bool kStats, bool kMotion>
CR_SIMD_INLINE bool RayRun_Intersect(const KernelScene& sc, const std::uint32_t* refs, std::uint32_t i,
                                     std::uint32_t e, const PackRay<4>& pr, Hit& hit, int anyHit, TraceStatsSum& st)
{
  constexpr int K = 4;
  constexpr bool kTies = SimdPrim<T>::kDistanceTies && !kFast;
  bool changed = false;
  for (; i < e; i += K) {
    const std::uint32_t count = e - i < std::uint32_t(K) ? e - i : std::uint32_t(K);
    // Tests counted as the scalar loop counts them: an occlusion query
    // stops at its first occluder (counted below), else all of the group.
    if constexpr (kStats)
      if (!anyHit) st.nIT += count;
    alignas(16) std::uint32_t g[K];
    for (int l = 0; l < K; ++l) g[l] = refs[i + (std::uint32_t(l) < count ? std::uint32_t(l) : count - 1)];
    const vbool<K> valid = vbool<K>::FromBits((1u << count) - 1u);
    vfloat<K> t, u(0.0f), v(0.0f);
    if constexpr (kMotion) {
      // The lanes' pieces meet the ray in their rest frames; the rest as below.
      PackRay<K> shifted;
      const PackRay<K>& ray = PackRay_Shift<K>(sc, g, vbool<K>(true), pr, shifted) ? shifted : pr;
      const vbool<K> ok = SimdTest<T>::template Gather<kFast>(sc, g, ray, vfloat<K>(hit.t), t, u, v);
      if (anyHit) {
        const unsigned bits = (valid & ok).Bits();
        if constexpr (kStats) st.nIT += bits ? std::uint32_t(LowestBit(bits) + 1) : count;
        if (!bits) continue;
        const int lane = LowestBit(bits);
        const float tl = t[lane];
        if (!Hit_Closer(tl, g[lane], &hit)) continue;
        hit.t = tl;
        hit.u = u[lane];
        hit.v = v[lane];
        hit.g = g[lane];
        return true;
      }
      if (Pack_Reduce<K, true>(valid & ok, t, u, v, g, hit, kTies ? &sc : nullptr, &ray)) changed = true;
      continue;
    }
    const vbool<K> ok = SimdTest<T>::template Gather<kFast>(sc, g, pr, vfloat<K>(hit.t), t, u, v);
    if (anyHit) {
      // The first occluder in reference order, as the scalar loop finds it
      // (the hit is still the ray's tmax: nothing was found before).
      const unsigned bits = (valid & ok).Bits();
      if constexpr (kStats) st.nIT += bits ? std::uint32_t(LowestBit(bits) + 1) : count;
      if (!bits) continue;
      const int lane = LowestBit(bits);
      const float tl = t[lane];
      if (!Hit_Closer(tl, g[lane], &hit)) continue;
      hit.t = tl;
      hit.u = u[lane];
      hit.v = v[lane];
      hit.g = g[lane];
      return true;
    }
    if (Pack_Reduce<K>(valid & ok, t, u, v, g, hit, kTies ? &sc : nullptr, &pr)) changed = true;
  }
  return changed;
}

// One ray against refs[begin, end), run by run. Returns true when the hit
// changed (occlusion: as soon as it does).
template <unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE bool RayRefs_Intersect(const KernelScene& sc, const std::uint32_t* refs, std::uint32_t begin,
                                      std::uint32_t end, const PackRay<4>& pr, Hit& hit, int anyHit, TraceStatsSum& st)
{
  bool changed = false;
  std::uint32_t i = begin;
#define CR_SIMD_RAY_RUN_(T, U, a)                                                                      \
  if constexpr ((kTypes >> CR_PRIM_##U) & 1u) {                                                        \
    const std::uint32_t e = Refs_RunEnd<kTypes, CR_PRIM_##U>(refs, i, end, sc.ranges);                 \
    if (RayRun_Intersect<T, kFast, kStats, kHasMotion<kTypes>>(sc, refs, i, e, pr, hit, anyHit, st)) { \
      if (anyHit) return true;                                                                         \
      changed = true;                                                                                  \
    }                                                                                                  \
    i = e;                                                                                             \
  }
  CR_PRIM_TYPES(CR_SIMD_RAY_RUN_)
#undef CR_SIMD_RAY_RUN_
  return changed;
}

// Lane l of a packet as the single-ray form's 4-wide ray (PackRay_Init's
// values, from the packet's own).
template <int N, bool kMotion>
CR_SIMD_INLINE PackRayOf<4, kMotion> PackRay_OfLane(const RayPacket<N>& P, int l, int anyHit)
{
  PackRayOf<4, kMotion> pr;
  for (int a = 0; a < 3; ++a) {
    pr.org[a] = vfloat<4>(P.org[a][l]);
    pr.dir[a] = vfloat<4>(P.dir[a][l]);
    pr.orgK[a] = vfloat<4>(P.orgK[a][l]);
    pr.s[a] = vfloat<4>(P.s[a][l]);
    pr.k[a] = static_cast<int>(P.k[a][l]);
  }
  pr.tmin = vfloat<4>(P.tmin[l]);
  pr.dd = vfloat<4>(P.dd[l]);
  pr.anyHit = anyHit != 0;
  if constexpr (kMotion) pr.time = RayPacket_Time<N>(P)[l];
  return pr;
}

// refs[begin, end) against the lanes of m one lane at a time, each with the
// single-ray form (RayRefs_Intersect, 4 primitives at once): for a cell that
// few lanes of a packet stand in, this keeps the vector lanes busy where a
// packet pass would run an N-wide test per primitive for one or two rays.
// Per lane the answer is the packet pass's (and the scalar loop's).
template <int N, unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void LaneRefs_Intersect(const KernelScene& sc, const std::uint32_t* refs, std::uint32_t begin,
                                       std::uint32_t end, const RayPacket<N>& P, HitPacket<N>& H, vbool<N> m,
                                       int anyHit, unsigned& done, TraceStatsSum& st)
{
  for (unsigned bits = m.Bits(); bits; bits &= bits - 1u) {
    const int l = LowestBit(bits);
    const PackRayOf<4, kHasMotion<kTypes>> pr = PackRay_OfLane<N, kHasMotion<kTypes>>(P, l, anyHit);
    Hit hit = HitPacket_Lane<N>(H, l);
    if (RayRefs_Intersect<kTypes, kFast, kStats>(sc, refs, begin, end, pr, hit, anyHit, st)) {
      HitPacket_SetLane<N>(H, l, hit);
      if (anyHit) done |= 1u << l;
    }
  }
}

// The references of a cell or leaf of a cell walk against the lanes of m that
// stand in it: lane by lane (LaneRefs_Intersect) when only one or two lanes
// do and there are four references or more, else one packet pass
// (PacketRefs_Intersect). Measured on gears (grid) 4-7% faster than packet
// passes alone. Not where the scene has spheres: their packet test is cheap
// enough that lane passes lost (balls 2-7% slower); with every type compiled
// in (kAllTypes) that is asked of the scene.
template <int N, unsigned kTypes>
CR_SIMD_INLINE bool CellRefs_ByLane(const KernelScene& sc, std::uint32_t begin, std::uint32_t end, vbool<N> m)
{
  const bool lanePasses = !(kTypes & kSphereBit) || Prim_Count(&sc.ranges, CR_PRIM_SPHERE) == 0;
  return lanePasses && PopCount(m.Bits()) <= 2 && end - begin >= 4;
}
template <int N, unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void CellRefs_Intersect(const KernelScene& sc, const std::uint32_t* refs, std::uint32_t begin,
                                       std::uint32_t end, const RayPacket<N>& P, HitPacket<N>& H, vbool<N> m,
                                       int anyHit, unsigned& done, TraceStatsSum& st)
{
  if (CellRefs_ByLane<N, kTypes>(sc, begin, end, m))
    LaneRefs_Intersect<N, kTypes, kFast, kStats>(sc, refs, begin, end, P, H, m, anyHit, done, st);
  else
    PacketRefs_Intersect<N, kTypes, kFast, kStats>(sc, refs, begin, end, P, H, m, anyHit, done, st);
}

// The references refs[begin, end) of a cell or leaf that are not in the
// ray's mailbox (a direct-mapped table of kSlots entries, slot k at
// mailbox[k * stride], updated here; kernels/hgrid.h, kernels/octree.h), in
// order, a chunk at a time, then tested 4 at a time: the scalar loop's
// tests. True when an any-hit query is answered.
template <int kSlots, unsigned kTypes, bool kFast, bool kStats, class PR>
CR_SIMD_INLINE bool MailboxRefs_Intersect(const KernelScene& sc, const std::uint32_t* refs, std::uint32_t begin,
                                          std::uint32_t end, std::uint32_t* mailbox, int stride, const PR& pr,
                                          Hit& hit, int anyHit, TraceStatsSum& st)
{
  constexpr std::uint32_t kChunk = 32;
  alignas(16) std::uint32_t fresh[kChunk];
  std::uint32_t i = begin;
  while (i < end) {
    std::uint32_t n = 0;
    for (; i < end && n < kChunk; ++i) {
      const std::uint32_t prim = refs[i];
      std::uint32_t& slot = mailbox[(prim & std::uint32_t(kSlots - 1)) * std::uint32_t(stride)];
      if (slot == prim) continue;
      slot = prim;
      fresh[n++] = prim;
    }
    if (n && RayRefs_Intersect<kTypes, kFast, kStats>(sc, fresh, 0, n, pr, hit, anyHit, st) && anyHit) return true;
  }
  return false;
}

// The same for the lanes of m of a packet, each with its own mailbox (slot
// k of lane l at mailbox[k][l]): one packet pass, each primitive against
// the lanes that do not have it in their mailboxes (one vector compare per
// primitive); lane by lane (MailboxRefs_Intersect on laneRay(l), the lane's
// 4-wide ray) where CellRefs_ByLane prefers it. Occlusion: a lane with an
// occluder joins `done`. Per lane the scalar loop's tests and answer.
template <int N, int kSlots, unsigned kTypes, bool kFast, bool kStats, class LaneRay>
CR_SIMD_INLINE void MailboxPacketRefs_Intersect(const KernelScene& sc, const std::uint32_t* refs,
                                                std::uint32_t begin, std::uint32_t end, std::uint32_t (*mailbox)[N],
                                                const RayPacket<N>& P, HitPacket<N>& H, vbool<N> m, int anyHit,
                                                unsigned& done, TraceStatsSum& st, LaneRay&& laneRay)
{
  if (CellRefs_ByLane<N, kTypes>(sc, begin, end, m)) {
    for (unsigned r = m.Bits(); r; r &= r - 1u) {
      const int l = LowestBit(r);
      Hit hit = HitPacket_Lane<N>(H, l);
      const bool answered = MailboxRefs_Intersect<kSlots, kTypes, kFast, kStats>(sc, refs, begin, end, &mailbox[0][l],
                                                                                 N, laneRay(l), hit, anyHit, st);
      HitPacket_SetLane<N>(H, l, hit);
      if (answered) done |= 1u << l;
    }
    return;
  }
  for (std::uint32_t i = begin; i < end; ++i) {
    const std::uint32_t prim = refs[i];
    std::uint32_t* row = mailbox[prim & std::uint32_t(kSlots - 1)];
    const vint<N> slot = vint<N>::Load(row);
    const vint<N> pv(static_cast<int>(prim));
    const vbool<N> fresh = AndNot(m, slot == pv);
    Select(m, pv, slot).Store(row);
    if (None(fresh)) continue;
    if constexpr (kStats) st.nIT += PopCount(fresh.Bits());
    const vbool<N> changed = PacketPrim_Intersect<N, kTypes, kFast>(sc, prim, P, H, fresh);
    if (anyHit && Any(changed)) {
      done |= changed.Bits();
      m = AndNot(m, changed);
      if (None(m)) break;
    }
  }
}

}  // namespace cr::simd::CR_SIMD_NS
