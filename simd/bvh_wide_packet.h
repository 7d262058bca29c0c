// N coherent rays at once through the N-wide BVH of the single-ray path
// (simd/bvh_wide.h), with a switch to single rays when few lanes are left
// (Embree's "hybrid" packet traversal: Benthin, Wald, Woop, Ernst & Áfra
// 2012, "Combining single and packet-ray tracing for arbitrary ray
// distributions on the Intel MIC architecture"). At a wide node, a frustum
// test of the packet against all N child boxes at once picks the children
// some lane may enter (when the lanes share direction signs), then each of
// those is tested against every lane that entered the node; the children
// that some lane enters are visited nearest first by the smallest entry
// distance of their lanes (occlusion: in slot order), the others wait on the
// stack with their lanes and per-lane entry distances. A leaf's primitives
// are tested for the entering lanes at once (SIMD across rays), each
// primitive as the binary packet path tests it. When at most
// kWidePacketSingleLanes lanes enter a node, each of them finishes that
// subtree alone (BVHSingle_TraceFrom) and the packet goes on with its stack.
//
// The answers are those of every other path: each lane's box tests are the
// scalar slab test against its current hit distance with the cull margin,
// each primitive test is the scalar arithmetic, and hits are kept in
// Hit_Closer order, so a lane's closest hit does not depend on the order.
// Statistics count per lane, as the binary packet path does: a wide node or
// leaf visit once for every lane that entered it, a primitive test once for
// every lane it was run for.
#pragma once

#include "simd/bvh_packet.h"
#include "simd/bvh_single.h"

namespace cr::simd::CR_SIMD_NS {

// Lanes at or below this count leave the packet for the single-ray walk.
// 3 against 2 (2026-11-27): bumpy 10^7 primary rays 8.2 against 9.2 ms (2
// threads); teapot, balls, gears, tree, bunny, sponza x primary, shadow,
// diffuse 1.008x the time (primary 1.00-1.045, diffuse 0.92-1.015).
inline constexpr int kWidePacketSingleLanes = 3;

// The packs of type T from `first` (`count` of them) against the lanes of m,
// one primitive at a time; returns the lanes whose hit changed.
template <int N, int K, class T, bool kFast, bool kStats, bool kMotion>
CR_SIMD_INLINE vbool<N> WidePacketLeaf_Type(const KernelScene& sc, std::uint32_t first, int count,
                                            const RayPacket<N>& P, HitPacket<N>& H, vbool<N> m, bool anyHit,
                                            TraceStatsSum& st)
{
  constexpr unsigned k = kPrimIndex<T>;
  using Pack = typename SimdPrim<T>::template Pack<K>;
  const Pack* packs = static_cast<const Pack*>(sc.packs[k]) + first;
  vbool<N> changed = vbool<N>::FromBits(0u);
  for (int p = 0; p < count; ++p) {
    for (int s = 0; s < K; ++s) {
      const std::uint32_t g = packs[p].g[s];
      if (g == CR_NO_HIT) continue;
      if constexpr (kStats) st.nIT += PopCount(m.Bits());
      const vbool<N> c = PacketPrim_IntersectAs<N, T, kFast, kMotion>(sc, g, P, H, m);
      changed = changed | c;
      if (anyHit && Any(c)) {
        m = AndNot(m, c);
        if (None(m)) return changed;
      }
    }
  }
  return changed;
}

// A leaf slot (p without the leaf flag, meta its meta word) against the
// lanes of m; returns the lanes whose hit changed.
template <int N, int K, unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE vbool<N> WidePacketLeaf(const KernelScene& sc, std::uint32_t p, std::uint32_t meta,
                                       const RayPacket<N>& P, HitPacket<N>& H, vbool<N> m, bool anyHit,
                                       TraceStatsSum& st)
{
  constexpr bool kMotion = kHasMotion<kTypes>;
  if (meta != kWideMixedLeaf) {
    const std::uint32_t type = (meta >> 16) - 1u;
    const int count = static_cast<int>(meta & 0xffffu);
#define CR_SIMD_WP_LEAF_RUN_(T, U, a)                                                          \
  if constexpr ((kTypes >> CR_PRIM_##U) & 1u)                                                  \
    if (type == CR_PRIM_##U)                                                                   \
      return WidePacketLeaf_Type<N, K, T, kFast, kStats, kMotion>(sc, p, count, P, H, m, anyHit, st);
    CR_PRIM_TYPES(CR_SIMD_WP_LEAF_RUN_)
#undef CR_SIMD_WP_LEAF_RUN_
    return vbool<N>::FromBits(0u);
  }
  const WideLeaf& leaf = sc.wideLeaves[p];
  vbool<N> changed = vbool<N>::FromBits(0u);
#define CR_SIMD_WP_LEAF_TYPE_(T, U, a)                                                                  \
  if constexpr ((kTypes >> CR_PRIM_##U) & 1u) {                                                         \
    changed = changed | WidePacketLeaf_Type<N, K, T, kFast, kStats, kMotion>(                           \
                            sc, leaf.first[CR_PRIM_##U], leaf.count[CR_PRIM_##U], P, H, m, anyHit, st); \
    if (anyHit) {                                                                                       \
      m = AndNot(m, changed);                                                                           \
      if (None(m)) return changed;                                                                      \
    }                                                                                                   \
  }
  CR_PRIM_TYPES(CR_SIMD_WP_LEAF_TYPE_)
#undef CR_SIMD_WP_LEAF_TYPE_
  return changed;
}

// Every lane's origin and reciprocal direction finite, the reciprocals
// nonzero: the frustum's products are then never NaN.
template <int N>
CR_SIMD_INLINE bool WidePacket_Finite(const RayPacket<N>& P)
{
  const vfloat<N> inf(__builtin_inff()), zero(0.0f);
  vbool<N> ok = vbool<N>::FromBits(vbool<N>::kAll);
  for (int a = 0; a < 3; ++a) {
    const vfloat<N> ai = Abs(P.inv[a]);
    ok = ok & (Abs(P.org[a]) < inf) & (ai < inf) & (ai > zero);
  }
  return All(ok);
}

// Closest hit (anyHit = 0) or any hit of the lanes in `active`, through the
// N-wide BVH with K-wide packs.
template <int N, int K, unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void BVHWidePacket_Trace(const KernelScene& sc, const RayPacket<N>& P, HitPacket<N>& H,
                                        vbool<N> active, int anyHit, TraceStatsSum& st)
{
  struct Entry {
    vfloat<N> t;  // each lane's entry distance
    std::uint32_t ref, meta;
    unsigned bits;  // lanes that entered the child
  };
  Entry stack[(N - 1) * kBVHStack + 1];
  int sp = 0;
  const WideNode<N>* nodes = static_cast<const WideNode<N>*>(sc.wideNodes);
  const unsigned activeBits = active.Bits();
  unsigned done = 0;  // occlusion: lanes with an occluder
  unsigned bits = activeBits;
  std::uint32_t ref = 0, meta = 0;
  // The packet's frustum in interval form, when every lane goes the same way
  // along each axis and every component is finite: the lanes' origins in
  // [oLo, oHi], reciprocals in [iLo, iHi] (one sign) per axis. Its bounds
  // on a child's slab distances are the products at the intervals' corners,
  // rounded as the lanes' own are, so they bound every lane's distance (the
  // rounding is monotone) and a child it rejects no lane enters.
  const bool frustum = P.sameSigns && WidePacket_Finite<N>(P);
  vfloat<N> oLo[3], oHi[3], iLo[3], iHi[3];
  bool axisNeg[3];
  for (int a = 0; a < 3; ++a) {
    oLo[a] = vfloat<N>(HMin(P.org[a]));
    oHi[a] = vfloat<N>(-HMin(-P.org[a]));
    iLo[a] = vfloat<N>(HMin(P.inv[a]));
    iHi[a] = vfloat<N>(-HMin(-P.inv[a]));
    axisNeg[a] = P.invNeg[a].Bits() != 0u;
  }
  const float tminLo = HMin(P.tmin);
  // Single rays of the lanes, made when the first lane leaves the packet.
  Ray rays[N];
  bool raysMade = false;
  for (;;) {
    if (PopCount(bits) <= kWidePacketSingleLanes) {
      // Few lanes: each finishes this subtree alone.
      if (!raysMade) {
        RayPacket_Extract<N>(P, H, rays);
        raysMade = true;
      }
      HitLanes<N> L(H);
      for (unsigned rest = bits; rest; rest &= rest - 1u) {
        const int l = LowestBit(rest);
        Ray& ray = rays[l];
        ray.tmax = L.t[l];
        Hit hit = L.Get(l);
        const std::uint32_t g0 = hit.g;
        const float t0 = hit.t;
        BVHSingle_TraceFrom<N, K, kTypes, kFast, kStats>(sc, ray, hit, anyHit, st, ref, meta);
        if (hit.g != g0 || hit.t != t0) {
          L.Set(l, hit);
          done |= 1u << l;
        }
      }
      L.To(H);
      if (!anyHit) done = 0;
      if (anyHit && (done & activeBits) == activeBits) return;
    } else if (!(ref & kWideLeafFlag)) {
      const WideNode<N>& n = nodes[ref];
      if constexpr (kStats) st.nTS += PopCount(bits);
      const vbool<N> m = vbool<N>::FromBits(bits);
      const vfloat<N> cull = CullDistance<kFast, N>(H.t);
      Entry kid[N];
      int nk = 0;
      float key[N];
      unsigned cand = 0;
      if (frustum) {
        vfloat<N> near[3], far[3];
        const vfloat<N> zero(0.0f);
        for (int a = 0; a < 3; ++a) {
          const vfloat<N> lower = vfloat<N>::Load(n.lower[a]), upper = vfloat<N>::Load(n.upper[a]);
          if (!axisNeg[a]) {
            const vfloat<N> dn = lower - oHi[a], df = upper - oLo[a];
            near[a] = dn * Select(dn >= zero, iLo[a], iHi[a]);
            far[a] = df * Select(df >= zero, iHi[a], iLo[a]);
          } else {
            const vfloat<N> dn = upper - oLo[a], df = lower - oHi[a];
            near[a] = dn * Select(dn >= zero, iLo[a], iHi[a]);
            far[a] = df * Select(df <= zero, iLo[a], iHi[a]);
          }
        }
        vfloat<N> unused;
        cand = Box_Finish<kFast, N>(near, far, vfloat<N>(tminLo), vfloat<N>(-HMin(-cull)), unused).Bits();
      } else {
        for (int i = 0; i < N && !(n.child[i] == kWideEmptyLeaf && n.meta[i] == kWideMixedLeaf); ++i) cand |= 1u << i;
      }
      for (; cand; cand &= cand - 1u) {
        const int i = LowestBit(cand);
        const float lo[3] = {n.lower[0][i], n.lower[1][i], n.lower[2][i]};
        const float hi[3] = {n.upper[0][i], n.upper[1][i], n.upper[2][i]};
        vfloat<N> tE;
        const vbool<N> h = m & Box_IntersectRays<kFast, N>(lo, hi, P.org, P.inv, P.invNeg, P.tmin, cull, tE);
        const unsigned hb = h.Bits();
        if (!hb) continue;
        if (anyHit) {
          // Any occluder will do: no order (sponza shadow rays 9% faster,
          // the other scenes the same).
          kid[nk++] = {tE, n.child[i], n.meta[i], hb};
          continue;
        }
        // Insertion by the nearest lane's entry, farthest first.
        const float d = HMin(Select(h, tE, vfloat<N>(__builtin_inff())));
        int j = nk++;
        while (j > 0 && key[j - 1] < d) {
          kid[j] = kid[j - 1];
          key[j] = key[j - 1];
          --j;
        }
        kid[j] = {tE, n.child[i], n.meta[i], hb};
        key[j] = d;
      }
      if (nk > 0) {
        for (int j = 0; j < nk - 1; ++j) {
          WideSlot_Prefetch<N, K, kTypes>(sc, nodes, kid[j].ref, kid[j].meta);
          stack[sp++] = kid[j];
        }
        ref = kid[nk - 1].ref;
        meta = kid[nk - 1].meta;
        bits = kid[nk - 1].bits;
        continue;
      }
    } else {
      if constexpr (kStats) {
        st.nTS += PopCount(bits);
        st.nLeaves += PopCount(bits);
      }
      const vbool<N> changed = WidePacketLeaf<N, K, kTypes, kFast, kStats>(
          sc, ref & ~kWideLeafFlag, meta, P, H, vbool<N>::FromBits(bits), anyHit != 0, st);
      if (anyHit) {
        done |= changed.Bits();
        if ((done & activeBits) == activeBits) return;
      }
    }
    // Pop the next pending child with a lane that can still find a closer hit.
    for (;;) {
      if (sp == 0) return;
      --sp;
      bits = stack[sp].bits & ~done & (stack[sp].t <= CullDistance<kFast, N>(H.t)).Bits();
      if (bits) {
        ref = stack[sp].ref;
        meta = stack[sp].meta;
        break;
      }
    }
  }
}

// Traces positions [job.begin, job.end) in packets of N through the wide BVH.
template <int N, int K, unsigned kTypes, bool kFast, bool kStats>
void BVHWidePacket_TraceRange(const KernelScene& sc, const KernelJob& job)
{
  Packet_TraceRangeWith<N, kStats, kHasMotion<kTypes>>(
      sc, job, [&](RayPacket<N>& P, HitPacket<N>& H, vbool<N> lanes, int anyHit, TraceStatsSum& st) {
        BVHWidePacket_Trace<N, K, kTypes, kFast, kStats>(sc, P, H, lanes, anyHit, st);
      });
}

}  // namespace cr::simd::CR_SIMD_NS
