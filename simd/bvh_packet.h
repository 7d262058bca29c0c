// BVH traversal of N coherent rays at once (Wald, Slusallek, Benthin & Wagner
// 2001, "Interactive rendering with coherent ray tracing"): the packet walks
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

#include "simd/kernel_common.h"

namespace cr::simd::CR_SIMD_NS {

template <int N>
struct RayPacket {
  vfloat<N> org[3], dir[3], inv[3];
  vbool<N> invNeg[3];  // inv < 0: the near plane is bmax
  vfloat<N> tmin;
  vfloat<N> dd;       // d.d, for the sphere test
  vfloat<N> s[3];     // shear constants sx, sy, sz
  vint<N> k[3];       // kx, ky, kz
  vint<N> sel[3];     // ComponentSelector of kx, ky, kz
  vfloat<N> orgK[3];  // org[kx], org[ky], org[kz]
  // When every lane has the same kx, ky, kz (coherent packets), they are
  // kScalar, and triangle tests broadcast components instead of permuting.
  bool kUniform;
  int kScalar[3];
  // When every lane has the same direction signs (coherent packets), the
  // near plane of axis a is node float nearOff[a] for all lanes (bmin[a] or
  // bmax[a] as BVHNode lays them out), and the per-lane plane choice is skipped.
  bool sameSigns;
  int nearOff[3], farOff[3];
};

template <int N>
struct HitPacket {
  vfloat<N> t, u, v;
  vint<N> g;
};

// Ray_Init of kernels/ray.h on all lanes at once, from the N records (a
// lane's record pointer may repeat another's to pad the packet); hits as
// Hit_Init leaves them. Same operations as Ray_Init, lane by lane: the
// reciprocals and shear constants are IEEE divisions, the dominant axis kz
// comes from the same comparisons (so NaN components choose as they do).
template <int N>
CR_SIMD_INLINE void RayPacket_Init(RayPacket<N>& p, HitPacket<N>& h, const RayRecord* const recs[N])
{
  static_assert(sizeof(RayRecord) == 8 * sizeof(float));
  const float* rows[N];
  for (int l = 0; l < N; ++l) rows[l] = recs[l]->org;
  vfloat<N> c[8];  // org x y z, tmin, dir x y z, tmax
  LoadTransposed(rows, c);
  const vfloat<N>* org = c;
  const vfloat<N>* dir = c + 4;
  for (int a = 0; a < 3; ++a) {
    p.org[a] = org[a];
    p.dir[a] = dir[a];
    p.inv[a] = vfloat<N>(1.0f) / dir[a];
    p.invNeg[a] = p.inv[a] < vfloat<N>(0.0f);
  }
  p.tmin = c[3];
  p.dd = Dot3N<N>(p.dir, p.dir);
  h.t = c[7];
  h.u = vfloat<N>(0.0f);
  h.v = vfloat<N>(0.0f);
  h.g = vint<N>(static_cast<int>(CR_NO_HIT));

  const vfloat<N> ax = Abs(dir[0]), ay = Abs(dir[1]), az = Abs(dir[2]);
  const vint<N> k0(0), k1(1), k2(2);
  const vint<N> kz = Select(ax > ay, Select(ax > az, k0, k2), Select(ay > az, k1, k2));
  vint<N> kx = Select(kz == k2, k0, kz + k1);
  vint<N> ky = Select(kx == k2, k0, kx + k1);
  auto pick = [&](const vfloat<N>* v, vint<N> k) { return Select(k == k0, v[0], Select(k == k1, v[1], v[2])); };
  const vfloat<N> dz = pick(dir, kz);
  const vbool<N> flip = dz < vfloat<N>(0.0f);
  const vint<N> kxs = Select(flip, ky, kx);
  ky = Select(flip, kx, ky);
  kx = kxs;
  p.s[0] = pick(dir, kx) / dz;
  p.s[1] = pick(dir, ky) / dz;
  p.s[2] = vfloat<N>(1.0f) / dz;
  p.k[0] = kx;
  p.k[1] = ky;
  p.k[2] = kz;
  for (int j = 0; j < 3; ++j) {
    p.sel[j] = ComponentSelector(p.k[j]);
    p.orgK[j] = pick(org, p.k[j]);
  }
  p.kUniform = true;
  for (int j = 0; j < 3; ++j) {
    const int first = static_cast<int>(p.k[j][0]);
    p.kScalar[j] = first;
    p.kUniform = p.kUniform && All(p.k[j] == vint<N>(first));
  }
  p.sameSigns = true;
  for (int a = 0; a < 3; ++a) {
    const unsigned neg = p.invNeg[a].Bits();
    p.sameSigns = p.sameSigns && (neg == 0 || neg == vbool<N>::kAll);
    p.nearOff[a] = neg ? 4 + a : a;  // BVHNode: bmin at floats 0..2, bmax at 4..6
    p.farOff[a] = neg ? a : 4 + a;
  }
}

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

// Primitive g, known to be of type kType, against the lanes of m; keeps each
// lane's closer hit (Hit_Closer). Returns the lanes whose hit changed.
template <int N, PrimType kType, bool kFast>
CR_SIMD_INLINE vbool<N> PacketPrim_IntersectAs(const KernelScene& sc, std::uint32_t g, const RayPacket<N>& P,
                                               HitPacket<N>& H, vbool<N> m)
{
  vfloat<N> t, u(0.0f), v(0.0f);
  vbool<N> ok;
  const PrimRanges& c = sc.ranges;
  if constexpr (kType == PrimType::Sphere) {
    const Sphere& sp = sc.spheres[g];
    const vfloat<N> cen[3] = {vfloat<N>(sp.center[0]), vfloat<N>(sp.center[1]), vfloat<N>(sp.center[2])};
    ok = Sphere_IntersectN<kFast, N>(P.org, cen, P.dir, P.dd, vfloat<N>(sp.radius), P.tmin, H.t, t);
  } else if constexpr (kType == PrimType::Triangle) {
    const Triangle& tri = sc.triangles[Prim_Local(&c, CR_PRIM_TRIANGLE, g)];
    if constexpr (kFast) {
      vfloat<N> v0[3], v1[3], v2[3];
      for (int i = 0; i < 3; ++i) {
        v0[i] = vfloat<N>(tri.v0[i]);
        v1[i] = vfloat<N>(tri.v1[i]);
        v2[i] = vfloat<N>(tri.v2[i]);
      }
      ok = Triangle_MollerTrumboreN<N>(v0, v1, v2, P.org, P.dir, P.tmin, H.t, t, u, v);
    } else {
      vfloat<N> A[3], B[3], C[3];
      if (P.kUniform) {
        // Every lane has the same axis permutation (coherent packets): the
        // permuted components are plain broadcasts.
        for (int j = 0; j < 3; ++j) {
          A[j] = vfloat<N>(tri.v0[P.kScalar[j]]) - P.orgK[j];
          B[j] = vfloat<N>(tri.v1[P.kScalar[j]]) - P.orgK[j];
          C[j] = vfloat<N>(tri.v2[P.kScalar[j]]) - P.orgK[j];
        }
      } else {
        for (int j = 0; j < 3; ++j) {
          A[j] = PermuteXYZ(tri.v0, P.sel[j]) - P.orgK[j];
          B[j] = PermuteXYZ(tri.v1, P.sel[j]) - P.orgK[j];
          C[j] = PermuteXYZ(tri.v2, P.sel[j]) - P.orgK[j];
        }
      }
      ok = Triangle_WatertightN<N>(A, B, C, P.s, OnePlane<N>{tri}, P.org, P.dir, P.tmin, H.t, t, u, v);
    }
  } else {
    const ConeData& cd = sc.cones[Prim_Local(&c, CR_PRIM_CONE, g)];
    vfloat<N> dl[3], w[3];
    for (int i = 0; i < 3; ++i) {
      dl[i] = P.org[i] - vfloat<N>(cd.base[i]);
      w[i] = vfloat<N>(cd.w[i]);
    }
    const Cone* cone = &sc.coneGeometry[Prim_Local(&c, CR_PRIM_CONE, g)];
    ok = Cone_IntersectN<kFast, N>(P.org, dl, P.dir, w, vfloat<N>(cd.H), vfloat<N>(cd.r0), vfloat<N>(cd.k), P.tmin,
                                   H.t, t, [cone](int) { return cone; });
  }
  const vint<N> gv(static_cast<int>(g));
  const vbool<N> found = m & ok;
  vbool<N> closer = found & (t < H.t);
  // An exact tie in t with the hit so far is rare: resolved off the hot path,
  // by the lower id (Hit_Closer) or, between two spheres, by double-float
  // distance (Hit_CloserOn), lane by lane.
  const vbool<N> tied = found & (t == H.t);
  if (Any(tied)) [[unlikely]] {
    closer = closer | (tied & LessUnsigned(gv, H.g));
    if constexpr (kType == PrimType::Sphere && !kFast) {
      const vbool<N> tie = tied & LessUnsigned(H.g, vint<N>(static_cast<int>(Prim_End(&c, CR_PRIM_SPHERE)))) & !(gv == H.g);
      unsigned bits = closer.Bits();
      for (unsigned rest = tie.Bits(); rest; rest &= rest - 1u) {
        const int l = LowestBit(rest);
        const float org[3] = {P.org[0][l], P.org[1][l], P.org[2][l]};
        const float dir[3] = {P.dir[0][l], P.dir[1][l], P.dir[2][l]};
        const int order = Sphere_TieOrder(org, dir, P.tmin[l], &sc.spheres[g], &sc.spheres[H.g[l]]);
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

// Primitive g of any type in kTypes against the lanes of m (as above).
template <int N, unsigned kTypes, bool kFast>
CR_SIMD_INLINE vbool<N> PacketPrim_Intersect(const KernelScene& sc, std::uint32_t g, const RayPacket<N>& P,
                                             HitPacket<N>& H, vbool<N> m)
{
  switch (TypeOf<kTypes>(g, sc.ranges)) {
    case PrimType::Sphere: return PacketPrim_IntersectAs<N, PrimType::Sphere, kFast>(sc, g, P, H, m);
    case PrimType::Triangle: return PacketPrim_IntersectAs<N, PrimType::Triangle, kFast>(sc, g, P, H, m);
    case PrimType::Cone: break;
  }
  return PacketPrim_IntersectAs<N, PrimType::Cone, kFast>(sc, g, P, H, m);
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
  const BVHNode* nodes = sc.nodes;
  const std::uint32_t* refs = sc.refs;
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

// Writes the hits of the first `count` lanes.
template <int N>
CR_SIMD_INLINE void Packet_StoreHits(const KernelScene& sc, const PrimView& pv, const KernelJob& job,
                                     const HitPacket<N>& H, const std::uint32_t idx[N], int count)
{
  alignas(32) float t[N], u[N], v[N];
  alignas(32) std::uint32_t g[N];
  H.t.Store(t);
  H.u.Store(u);
  H.v.Store(v);
  H.g.Store(g);
  for (int l = 0; l < count; ++l) {
    Hit h;
    h.t = t[l];
    h.u = u[l];
    h.v = v[l];
    h.g = g[l];
    job.hits[idx[l]] = Hit_ToRecord(&h, &pv, sc.primIds, job.occlusion, sc.unifiedHits);
  }
}

// The loop of every packet TraceRange: positions [job.begin, job.end) in
// packets of N (image tiles when the job is an image), each traced by
// trace(P, H, lanes, anyHit, st), hits stored.
template <int N, bool kStats, class TraceFn>
CR_SIMD_INLINE void Packet_TraceRangeWith(const KernelScene& sc, const KernelJob& job, TraceFn&& trace)
{
  const PrimView pv = MakePrimView(sc);
  TraceStatsSum st;
  for (std::size_t p = job.begin; p < job.end; p += N) {
    const RayRecord* recs[N];
    std::uint32_t idx[N];
    const int count = Packet_Rays<N>(job, p, recs, idx);
    RayPacket<N> P;
    HitPacket<N> H;
    RayPacket_Init<N>(P, H, recs);
    trace(P, H, vbool<N>::FromBits((1u << count) - 1u), job.occlusion, st);
    Packet_StoreHits<N>(sc, pv, job, H, idx, count);
  }
  if constexpr (kStats) AddJobStats(job.stats, st, job.end - job.begin);
}

// Traces positions [job.begin, job.end) in packets of N.
template <int N, unsigned kTypes, bool kFast, bool kStats>
void BVHPacket_TraceRange(const KernelScene& sc, const KernelJob& job)
{
  Packet_TraceRangeWith<N, kStats>(sc, job, [&](RayPacket<N>& P, HitPacket<N>& H, vbool<N> lanes, int anyHit,
                                                TraceStatsSum& st) {
    BVHPacket_Trace<N, kTypes, kFast, kStats>(sc, P, H, lanes, anyHit, st);
  });
}

}  // namespace cr::simd::CR_SIMD_NS
