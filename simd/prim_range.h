// A range of references refs[begin, end) (a grid cell, an octree leaf) tested
// type by type. References are unified indices sorted ascending, so the
// types come in runs (spheres, then triangles, then cones, kernels/types.h):
// each run is found once and tested with a loop of one type, and only the
// types in kTypes are compiled. No per-primitive type test.
//
// Two forms, both lane by lane the scalar intersectors of kernels/intersect.h
// and, per lane, the scalar loop's answer:
//  - PacketRefs_Intersect: N rays, one primitive at a time (packets);
//  - RayRefs_Intersect: one ray, K = 4 primitives at a time, gathered from
//    the scene's own arrays (Sphere, Triangle, ConeData rows of 16 bytes) by
//    4x4 transposes, so the grid and the octree need no structure-of-arrays
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

// End of the run of type kType that starts at refs[i] (i <= end).
template <unsigned kTypes, PrimType kType>
CR_SIMD_INLINE std::uint32_t Refs_RunEnd(const std::uint32_t* refs, std::uint32_t i, std::uint32_t end,
                                         const PrimRanges& c)
{
  constexpr bool hasT = kTypes & kTriangleBit, hasC = kTypes & kConeBit;
  std::uint32_t bound;
  if constexpr (kType == PrimType::Sphere) {
    if constexpr (!hasT && !hasC) return end;
    bound = Prim_End(&c, CR_PRIM_SPHERE);
  } else if constexpr (kType == PrimType::Triangle) {
    if constexpr (!hasC) return end;
    bound = Prim_End(&c, CR_PRIM_TRIANGLE);
  } else {
    return end;
  }
  while (i < end && refs[i] < bound) ++i;
  return i;
}

// The primitives of refs[i, e), all of type kType, against the lanes of m.
// Occlusion (anyHit): a lane leaves m at its first hit and joins `done`.
template <int N, PrimType kType, bool kFast, bool kStats>
CR_SIMD_INLINE void PacketRun_Intersect(const KernelScene& sc, const std::uint32_t* refs, std::uint32_t i,
                                        std::uint32_t e, const RayPacket<N>& P, HitPacket<N>& H, vbool<N>& m,
                                        int anyHit, unsigned& done, TraceStatsSum& st)
{
  for (; i < e; ++i) {
    if constexpr (kStats) st.nIT += PopCount(m.Bits());
    const vbool<N> changed = PacketPrim_IntersectAs<N, kType, kFast>(sc, refs[i], P, H, m);
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

// refs[begin, end) against the lanes of m (see PacketRun_Intersect).
template <int N, unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void PacketRefs_Intersect(const KernelScene& sc, const std::uint32_t* refs, std::uint32_t begin,
                                         std::uint32_t end, const RayPacket<N>& P, HitPacket<N>& H, vbool<N> m,
                                         int anyHit, unsigned& done, TraceStatsSum& st)
{
  std::uint32_t i = begin;
  if constexpr (kTypes & kSphereBit) {
    const std::uint32_t e = Refs_RunEnd<kTypes, PrimType::Sphere>(refs, i, end, sc.ranges);
    PacketRun_Intersect<N, PrimType::Sphere, kFast, kStats>(sc, refs, i, e, P, H, m, anyHit, done, st);
    i = e;
  }
  if constexpr (kTypes & kTriangleBit) {
    const std::uint32_t e = Refs_RunEnd<kTypes, PrimType::Triangle>(refs, i, end, sc.ranges);
    if (i < e && Any(m)) PacketRun_Intersect<N, PrimType::Triangle, kFast, kStats>(sc, refs, i, e, P, H, m, anyHit, done, st);
    i = e;
  }
  if constexpr (kTypes & kConeBit) {
    if (i < end && Any(m)) PacketRun_Intersect<N, PrimType::Cone, kFast, kStats>(sc, refs, i, end, P, H, m, anyHit, done, st);
  }
}

// One ray against the primitives of refs[i, e), all of type kType, 4 at a
// time. Returns true when the hit changed (occlusion: at the first change).
template <unsigned kTypes, PrimType kType, bool kFast, bool kStats>
CR_SIMD_INLINE bool RayRun_Intersect(const KernelScene& sc, const std::uint32_t* refs, std::uint32_t i,
                                     std::uint32_t e, const PackRay<4>& pr, Hit& hit, int anyHit, TraceStatsSum& st)
{
  constexpr int K = 4;
  const PrimRanges& c = sc.ranges;
  bool changed = false;
  for (; i < e; i += K) {
    const std::uint32_t count = e - i < std::uint32_t(K) ? e - i : std::uint32_t(K);
    if constexpr (kStats) st.nIT += count;
    alignas(16) std::uint32_t g[K];
    for (int l = 0; l < K; ++l) g[l] = refs[i + (std::uint32_t(l) < count ? std::uint32_t(l) : count - 1)];
    const vbool<K> valid = vbool<K>::FromBits((1u << count) - 1u);
    vfloat<K> t, u(0.0f), v(0.0f);
    vbool<K> ok;
    if constexpr (kType == PrimType::Sphere) {
      const float* rows[K];
      for (int l = 0; l < K; ++l) rows[l] = sc.spheres[g[l]].center;
      vfloat<K> s[4];
      LoadTransposed4(rows, s);
      ok = Sphere_IntersectN<kFast, K>(pr.org, s, pr.dir, pr.dd, s[3], pr.tmin, vfloat<K>(hit.t), t);
    } else if constexpr (kType == PrimType::Triangle) {
      // Each vertex is a 16-byte row (x, y, z, flags or pad).
      const Triangle* tri[K];
      for (int l = 0; l < K; ++l) tri[l] = &sc.triangles[Prim_Local(&c, CR_PRIM_TRIANGLE, g[l])];
      const float* rows[K];
      vfloat<K> vtx[3][4];  // [vertex][axis]
      for (int l = 0; l < K; ++l) rows[l] = tri[l]->v0;
      LoadTransposed4(rows, vtx[0]);
      for (int l = 0; l < K; ++l) rows[l] = tri[l]->v1;
      LoadTransposed4(rows, vtx[1]);
      for (int l = 0; l < K; ++l) rows[l] = tri[l]->v2;
      LoadTransposed4(rows, vtx[2]);
      if constexpr (kFast) {
        ok = Triangle_MollerTrumboreN<K>(vtx[0], vtx[1], vtx[2], pr.org, pr.dir, pr.tmin, vfloat<K>(hit.t), t, u, v);
      } else {
        vfloat<K> A[3], B[3], C[3];
        for (int j = 0; j < 3; ++j) {
          A[j] = vtx[0][pr.k[j]] - pr.orgK[j];
          B[j] = vtx[1][pr.k[j]] - pr.orgK[j];
          C[j] = vtx[2][pr.k[j]] - pr.orgK[j];
        }
        ok = Triangle_WatertightN<K>(A, B, C, pr.s, VecPlane<K>{vtx}, pr.org, pr.dir, pr.tmin, vfloat<K>(hit.t), t,
                                     u, v);
      }
    } else {
      // ConeData rows: (base, H), (w, r0), (k, pad).
      const ConeData* cd[K];
      for (int l = 0; l < K; ++l) cd[l] = &sc.cones[Prim_Local(&c, CR_PRIM_CONE, g[l])];
      const float* rows[K];
      vfloat<K> r0[4], r1[4], r2[4];
      for (int l = 0; l < K; ++l) rows[l] = cd[l]->base;
      LoadTransposed4(rows, r0);
      for (int l = 0; l < K; ++l) rows[l] = cd[l]->w;
      LoadTransposed4(rows, r1);
      for (int l = 0; l < K; ++l) rows[l] = &cd[l]->k;
      LoadTransposed4(rows, r2);
      vfloat<K> dl[3];
      for (int a = 0; a < 3; ++a) dl[a] = pr.org[a] - r0[a];
      ok = Cone_IntersectN<kFast, K>(pr.org, dl, pr.dir, r1, r0[3], r1[3], r2[0], pr.tmin, vfloat<K>(hit.t), t,
                                     [&](int l) { return &sc.coneGeometry[Prim_Local(&c, CR_PRIM_CONE, g[l])]; });
    }
    if (anyHit) {
      // The first occluder in reference order, as the scalar loop finds it
      // (the hit is still the ray's tmax: nothing was found before).
      const unsigned bits = (valid & ok).Bits();
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
    constexpr bool kSphereTies = kType == PrimType::Sphere && !kFast;
    if (Pack_Reduce<K>(valid & ok, t, u, v, g, hit, kSphereTies ? &sc : nullptr, &pr)) changed = true;
  }
  return changed;
}

// One ray against refs[begin, end), type by type. Returns true when the hit
// changed (occlusion: as soon as it does).
template <unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE bool RayRefs_Intersect(const KernelScene& sc, const std::uint32_t* refs, std::uint32_t begin,
                                      std::uint32_t end, const PackRay<4>& pr, Hit& hit, int anyHit, TraceStatsSum& st)
{
  bool changed = false;
  std::uint32_t i = begin;
  if constexpr (kTypes & kSphereBit) {
    const std::uint32_t e = Refs_RunEnd<kTypes, PrimType::Sphere>(refs, i, end, sc.ranges);
    if (RayRun_Intersect<kTypes, PrimType::Sphere, kFast, kStats>(sc, refs, i, e, pr, hit, anyHit, st)) {
      if (anyHit) return true;
      changed = true;
    }
    i = e;
  }
  if constexpr (kTypes & kTriangleBit) {
    const std::uint32_t e = Refs_RunEnd<kTypes, PrimType::Triangle>(refs, i, end, sc.ranges);
    if (RayRun_Intersect<kTypes, PrimType::Triangle, kFast, kStats>(sc, refs, i, e, pr, hit, anyHit, st)) {
      if (anyHit) return true;
      changed = true;
    }
    i = e;
  }
  if constexpr (kTypes & kConeBit) {
    if (RayRun_Intersect<kTypes, PrimType::Cone, kFast, kStats>(sc, refs, i, end, pr, hit, anyHit, st)) changed = true;
  }
  return changed;
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
    PackRay<4> pr;
    for (int a = 0; a < 3; ++a) {
      pr.org[a] = vfloat<4>(P.org[a][l]);
      pr.dir[a] = vfloat<4>(P.dir[a][l]);
      pr.orgK[a] = vfloat<4>(P.orgK[a][l]);
      pr.s[a] = vfloat<4>(P.s[a][l]);
      pr.k[a] = static_cast<int>(P.k[a][l]);
    }
    pr.tmin = vfloat<4>(P.tmin[l]);
    pr.dd = vfloat<4>(P.dd[l]);
    Hit hit;
    hit.t = H.t[l];
    hit.u = H.u[l];
    hit.v = H.v[l];
    hit.g = H.g[l];
    if (RayRefs_Intersect<kTypes, kFast, kStats>(sc, refs, begin, end, pr, hit, anyHit, st)) {
      const vbool<N> lane = vbool<N>::FromBits(1u << l);
      H.t = Select(lane, vfloat<N>(hit.t), H.t);
      H.u = Select(lane, vfloat<N>(hit.u), H.u);
      H.v = Select(lane, vfloat<N>(hit.v), H.v);
      H.g = Select(lane, vint<N>(static_cast<int>(hit.g)), H.g);
      if (anyHit) done |= 1u << l;
    }
  }
}

// The references of a grid cell or octree leaf against the lanes of m that
// stand in it: lane by lane (LaneRefs_Intersect) when only one or two lanes
// do and there are four references or more, else one packet pass
// (PacketRefs_Intersect). Measured on gears (grid) 4-7% faster than packet
// passes alone. Not where the scene has spheres: their packet test is cheap
// enough that lane passes lost (balls 2-7% slower).
template <int N, unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void CellRefs_Intersect(const KernelScene& sc, const std::uint32_t* refs, std::uint32_t begin,
                                       std::uint32_t end, const RayPacket<N>& P, HitPacket<N>& H, vbool<N> m,
                                       int anyHit, unsigned& done, TraceStatsSum& st)
{
  constexpr bool kLanePasses = !(kTypes & kSphereBit);
  if (kLanePasses && PopCount(m.Bits()) <= 2 && end - begin >= 4)
    LaneRefs_Intersect<N, kTypes, kFast, kStats>(sc, refs, begin, end, P, H, m, anyHit, done, st);
  else
    PacketRefs_Intersect<N, kTypes, kFast, kStats>(sc, refs, begin, end, P, H, m, anyHit, done, st);
}

}  // namespace cr::simd::CR_SIMD_NS
