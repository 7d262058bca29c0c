// BVH traversal of N coherent rays at once (Wald, Slusallek, Benthin & Wagner
// 2001, "Interactive rendering with coherent ray tracing"), for moving scenes
// (a static scene's packets walk the wide BVH, simd/bvh_wide_packet.h; the
// primitive tests and the packet loop below serve both): the packet walks
// the binary BVH of kernels/types.h with one shared stack and a mask of the
// lanes that entered each node. A node is visited when any of its lanes'
// slab tests passes; a leaf's primitives are tested for those lanes at once
// (SIMD across rays); a lane leaves the packet when its box tests fail, or,
// for occlusion, when it has found an occluder. The nearer child goes first
// by a majority vote of the lanes that enter both.
//
// Per lane this is BVH_Trace of kernels/bvh.h: the same slab test against
// the lane's current hit distance, the same intersection arithmetic, and
// Hit_Closer, so every lane's closest hit is the scalar backend's.
// Statistics count per lane: a node visit counts once for every lane that
// entered it, a primitive test once for every lane it was run for.
#pragma once

#include <type_traits>

#include "simd/kernel_common.h"

namespace cr::simd::CR_SIMD_NS {

// Box_Intersect of one node against every lane.
template <int N, bool kFast>
CR_SIMD_INLINE vbool<N> PacketBox_Intersect(const BVHNode& node, const RayPacket<N>& P, vfloat<N> tmax,
                                            vfloat<N>& tEnter)
{
  if (P.sameSigns) {
    const float* f = reinterpret_cast<const float*>(&node);
    vfloat<N> n[3], fa[3];
    for (int a = 0; a < 3; ++a) {
      n[a] = (vfloat<N>(f[P.nearOff[a]]) - P.org[a]) * P.inv[a];
      fa[a] = (vfloat<N>(f[P.farOff[a]]) - P.org[a]) * P.inv[a];
    }
    return Box_Finish<kFast, N>(n, fa, P.tmin, tmax, tEnter);
  }
  return Box_IntersectRays<kFast, N>(node.bmin, node.bmax, P.org, P.inv, P.invNeg, P.tmin, tmax, tEnter);
}

// Primitive g, known to be of type T, against the lanes of m; keeps each
// lane's closer hit (Hit_Closer). Returns the lanes whose hit changed.
// kMotion (a moving scene): a moving g meets the packet shifted into its
// rest frame (simd/motion.h), its ties too, as Prim_Intersect does.
template <int N, class T, bool kFast, bool kMotion = false>
CR_SIMD_INLINE vbool<N> PacketPrim_IntersectAs(const KernelScene& sc, std::uint32_t g, const RayPacket<N>& P,
                                               HitPacket<N>& H, vbool<N> m)
{
  if constexpr (kMotion) {
    float mv[3];
    if (Motion_Of(sc, g, mv)) {
      RayPacket<N> q;
      RayPacket_Shift<N>(P, mv, q);
      return PacketPrim_IntersectAs<N, T, kFast>(sc, g, q, H, m);
    }
  }
  vfloat<N> t, u(0.0f), v(0.0f);
  const PrimRanges& c = sc.ranges;
  const vbool<N> ok = SimdTest<T>::template Packet<N, kFast>(sc, g, P, m, H.t, t, u, v);
  const vint<N> gv(static_cast<int>(g));
  const vbool<N> found = m & ok;
  vbool<N> closer = found & (t < H.t);
  // An exact tie in t with the hit so far is rare: resolved off the hot path,
  // by the lower id (Hit_Closer) or, between two spheres, by double-float
  // distance (Hit_CloserOn), lane by lane.
  const vbool<N> tied = found & (t == H.t);
  if (Any(tied)) [[unlikely]] {
    closer = closer | (tied & LessUnsigned(gv, H.g));
    if constexpr (std::is_same_v<T, Sphere> && !kFast) {
      const vbool<N> tie = tied & LessUnsigned(H.g, vint<N>(static_cast<int>(Prim_End(&c, CR_PRIM_SPHERE)))) & !(gv == H.g);
      unsigned bits = closer.Bits();
      for (unsigned rest = tie.Bits(); rest; rest &= rest - 1u) {
        const int l = LowestBit(rest);
        const float org[3] = {P.org[0][l], P.org[1][l], P.org[2][l]};
        const float dir[3] = {P.dir[0][l], P.dir[1][l], P.dir[2][l]};
        const int order = Sphere_TieOrder(org, dir, P.tmin[l], &ScenePrims<Sphere>(sc)[g], &ScenePrims<Sphere>(sc)[H.g[l]]);
        if (order != 0) bits = order < 0 ? bits | (1u << l) : bits & ~(1u << l);
      }
      closer = vbool<N>::FromBits(bits);
    }
  }
  if (None(closer)) return closer;
  H.t = Select(closer, t, H.t);
  H.u = Select(closer, u, H.u);
  H.v = Select(closer, v, H.v);
  H.g = Select(closer, gv, H.g);
  return closer;
}

// Primitive g of any type in kTypes against the lanes of m (as above): its
// type is found among kTypes only, so a scene of one type never branches.
template <int N, unsigned kTypes, bool kFast>
CR_SIMD_INLINE vbool<N> PacketPrim_Intersect(const KernelScene& sc, std::uint32_t g, const RayPacket<N>& P,
                                             HitPacket<N>& H, vbool<N> m)
{
#define CR_SIMD_PACKET_TYPE_(T, U, a)                                                 \
  if constexpr ((kTypes >> CR_PRIM_##U) & 1u) {                                       \
    if (IsLastType<kTypes>(CR_PRIM_##U) || g < Prim_End(&sc.ranges, CR_PRIM_##U))     \
      return PacketPrim_IntersectAs<N, T, kFast, kHasMotion<kTypes>>(sc, g, P, H, m); \
  }
  CR_PRIM_TYPES(CR_SIMD_PACKET_TYPE_)
#undef CR_SIMD_PACKET_TYPE_
  __builtin_unreachable();
}

// Closest hit (anyHit = 0) or any hit of the lanes in `active`.
template <int N, unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void BVHPacket_Trace(const KernelScene& sc, const RayPacket<N>& P, HitPacket<N>& H, vbool<N> active,
                                    int anyHit, TraceStatsSum& st)
{
  struct Entry {
    vfloat<N> t;  // each lane's entry distance
    std::uint32_t node;
    unsigned bits;  // lanes that entered the node
  };
  Entry stack[kBVHStack];
  int sp = 0;
  const BVHNode* nodes = sc.bvhNodes;
  const std::uint32_t* refs = sc.bvhRefs;
  unsigned done = 0;  // occlusion: lanes with an occluder
  vfloat<N> tEnter;
  vbool<N> m = active & PacketBox_Intersect<N, kFast>(nodes[0], P, CullDistance<kFast, N>(H.t), tEnter);
  unsigned bits = m.Bits();
  if (!bits) return;
  const unsigned activeBits = active.Bits();
  std::uint32_t ni = 0;
  for (;;) {
    const BVHNode& n = nodes[ni];
    if constexpr (kStats) st.nTS += PopCount(bits);
    if (n.count > 0) {
      if constexpr (kStats) st.nLeaves += PopCount(bits);
      const std::uint32_t end = n.first + n.count;
      for (std::uint32_t i = n.first; i < end; ++i) {
        if constexpr (kStats) st.nIT += PopCount(m.Bits());
        const vbool<N> changed = PacketPrim_Intersect<N, kTypes, kFast>(sc, refs[i], P, H, m);
        if (anyHit) {
          const unsigned cb = changed.Bits();
          if (cb) {
            done |= cb;
            if ((done & activeBits) == activeBits) return;
            m = AndNot(m, changed);
            if (None(m)) break;
          }
        }
      }
    } else {
      const std::uint32_t c0 = n.first, c1 = n.first + 1;
      vfloat<N> t0, t1;
      const vfloat<N> cull = CullDistance<kFast, N>(H.t);
      const vbool<N> h0 = m & PacketBox_Intersect<N, kFast>(nodes[c0], P, cull, t0);
      const vbool<N> h1 = m & PacketBox_Intersect<N, kFast>(nodes[c1], P, cull, t1);
      const unsigned b0 = h0.Bits(), b1 = h1.Bits();
      if (b0 && b1) {
        const unsigned both = b0 & b1;
        const unsigned nearer1 = (t1 < t0).Bits() & both;
        if (2 * PopCount(nearer1) > PopCount(both)) {
          stack[sp].t = t0;
          stack[sp].node = c0;
          stack[sp].bits = b0;
          ni = c1;
          bits = b1;
          m = h1;
        } else {
          stack[sp].t = t1;
          stack[sp].node = c1;
          stack[sp].bits = b1;
          ni = c0;
          bits = b0;
          m = h0;
        }
        ++sp;
        continue;
      }
      if (b0 | b1) {
        ni = b0 ? c0 : c1;
        bits = b0 | b1;
        m = b0 ? h0 : h1;
        continue;
      }
    }
    // Pop the next pending node with a lane that can still find a closer hit.
    for (;;) {
      if (sp == 0) return;
      --sp;
      bits = stack[sp].bits & ~done & (stack[sp].t <= CullDistance<kFast, N>(H.t)).Bits();
      if (bits) {
        ni = stack[sp].node;
        m = vbool<N>::FromBits(bits);
        break;
      }
    }
  }
}

// The rays at positions [p, p + N) of the job, in job order (the last group
// padded with its first ray); returns how many are real.
template <int N>
CR_SIMD_INLINE int Job_Rays(const KernelJob& job, std::size_t p, const RayRecord* recs[N], std::uint32_t idx[N])
{
  const int count = static_cast<int>(job.end - p < std::size_t(N) ? job.end - p : std::size_t(N));
  for (int l = 0; l < count; ++l) {
    idx[l] = RayIndex(job, p + std::size_t(l));
    recs[l] = &job.rays[idx[l]];
  }
  for (int l = count; l < N; ++l) recs[l] = recs[0];
  return count;
}

// The packet of positions p .. p + count - 1 (image tiles when the job says
// so), tiles of (N/2) x 2 pixels or consecutive
// positions, see KernelJob.
template <int N>
CR_SIMD_INLINE int Packet_Rays(const KernelJob& job, std::size_t p, const RayRecord* recs[N], std::uint32_t idx[N])
{
  if (!job.imageWidth || job.order) return Job_Rays<N>(job, p, recs, idx);
  const int count = static_cast<int>(job.end - p < std::size_t(N) ? job.end - p : std::size_t(N));
  constexpr std::size_t tw = N / 2;
  const std::size_t w = job.imageWidth, tilesPerRow = w / tw, tile = p / N;
  const std::size_t base = (tile / tilesPerRow) * 2 * w + (tile % tilesPerRow) * tw;
  for (int l = 0; l < count; ++l) idx[l] = static_cast<std::uint32_t>(base + std::size_t(l / tw) * w + l % tw);
  for (int l = 0; l < count; ++l) recs[l] = &job.rays[idx[l]];
  for (int l = count; l < N; ++l) recs[l] = recs[0];
  return count;
}

// A packet's hits lane by lane, and back.
template <int N>
struct HitLanes {
  alignas(32) float t[N], u[N], v[N];
  alignas(32) std::uint32_t g[N];
  explicit HitLanes(const HitPacket<N>& H)
  {
    H.t.Store(t);
    H.u.Store(u);
    H.v.Store(v);
    H.g.Store(g);
  }
  void To(HitPacket<N>& H) const
  {
    H.t = vfloat<N>::Load(t);
    H.u = vfloat<N>::Load(u);
    H.v = vfloat<N>::Load(v);
    H.g = vint<N>::Load(g);
  }
  Hit Get(int l) const
  {
    Hit h;
    h.t = t[l];
    h.u = u[l];
    h.v = v[l];
    h.g = g[l];
    return h;
  }
  void Set(int l, const Hit& h)
  {
    t[l] = h.t;
    u[l] = h.u;
    v[l] = h.v;
    g[l] = h.g;
  }
};

// Lane l of a packet's hits, and a hit into lane l.
template <int N>
CR_SIMD_INLINE Hit HitPacket_Lane(const HitPacket<N>& H, int l)
{
  Hit h;
  h.t = H.t[l];
  h.u = H.u[l];
  h.v = H.v[l];
  h.g = H.g[l];
  return h;
}
template <int N>
CR_SIMD_INLINE void HitPacket_SetLane(HitPacket<N>& H, int l, const Hit& h)
{
  const vbool<N> lane = vbool<N>::FromBits(1u << l);
  H.t = Select(lane, vfloat<N>(h.t), H.t);
  H.u = Select(lane, vfloat<N>(h.u), H.u);
  H.v = Select(lane, vfloat<N>(h.v), H.v);
  H.g = Select(lane, vint<N>(static_cast<int>(h.g)), H.g);
}

// Writes the hits of the first `count` lanes.
template <int N>
CR_SIMD_INLINE void Packet_StoreHits(const KernelScene& sc, const PrimView& pv, const KernelJob& job,
                                     const HitPacket<N>& H, const std::uint32_t idx[N], int count)
{
  const HitLanes<N> L(H);
  for (int l = 0; l < count; ++l) {
    const Hit h = L.Get(l);
    job.hits[idx[l]] = Hit_ToRecord(&h, &pv, sc.primIds, job.occlusion, sc.unifiedHits);
  }
}

// The loop of every packet TraceRange: positions [job.begin, job.end) in
// packets of N (image tiles when the job is an image), each traced by
// trace(P, H, lanes, anyHit, st), hits stored. kMotion (a moving scene):
// the packets carry their rays' times (TimedRayPacket).
template <int N, bool kStats, bool kMotion, class TraceFn>
CR_SIMD_INLINE void Packet_TraceRangeWith(const KernelScene& sc, const KernelJob& job, TraceFn&& trace)
{
  const PrimView pv = MakePrimView(sc);
  TraceStatsSum st;
  for (std::size_t p = job.begin; p < job.end; p += N) {
    const RayRecord* recs[N];
    std::uint32_t idx[N];
    const int count = Packet_Rays<N>(job, p, recs, idx);
    RayPacketOf<N, kMotion> P;
    HitPacket<N> H;
    RayPacket_Init<N>(P, H, recs);
    P.anyHit = job.occlusion != 0;
    if constexpr (kMotion) P.time = Job_Times<N>(job, idx, count);
    trace(P, H, vbool<N>::FromBits((1u << count) - 1u), job.occlusion, st);
    Packet_StoreHits<N>(sc, pv, job, H, idx, count);
  }
  if constexpr (kStats) AddJobStats(job.stats, st, job.end - job.begin);
}

// Traces positions [job.begin, job.end) in packets of N.
template <int N, unsigned kTypes, bool kFast, bool kStats>
void BVHPacket_TraceRange(const KernelScene& sc, const KernelJob& job)
{
  Packet_TraceRangeWith<N, kStats, kHasMotion<kTypes>>(
      sc, job, [&](RayPacket<N>& P, HitPacket<N>& H, vbool<N> lanes, int anyHit, TraceStatsSum& st) {
        BVHPacket_Trace<N, kTypes, kFast, kStats>(sc, P, H, lanes, anyHit, st);
      });
}

}  // namespace cr::simd::CR_SIMD_NS
