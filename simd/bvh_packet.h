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
  vfloat<N> s[3];     // shear constants sx, sy, sz
  vint<N> sel[3];     // ComponentSelector of kx, ky, kz
  vfloat<N> orgK[3];  // org[kx], org[ky], org[kz]
};

template <int N>
struct HitPacket {
  vfloat<N> t, u, v;
  vint<N> g;
};

// Lanes from prepared rays (Ray_Init), hits as Hit_Init leaves them.
template <int N>
inline void RayPacket_Init(RayPacket<N>& p, HitPacket<N>& h, const Ray* rays)
{
  alignas(32) float org[3][N], dir[3][N], inv[3][N], s[3][N], orgK[3][N], tmin[N], tmax[N];
  alignas(32) std::uint32_t k[3][N];
  for (int l = 0; l < N; ++l) {
    const Ray& r = rays[l];
    const int kk[3] = {r.kx, r.ky, r.kz};
    for (int a = 0; a < 3; ++a) {
      org[a][l] = r.org[a];
      dir[a][l] = r.dir[a];
      inv[a][l] = r.inv[a];
      k[a][l] = static_cast<std::uint32_t>(kk[a]);
      orgK[a][l] = r.org[kk[a]];
    }
    s[0][l] = r.sx;
    s[1][l] = r.sy;
    s[2][l] = r.sz;
    tmin[l] = r.tmin;
    tmax[l] = r.tmax;
  }
  for (int a = 0; a < 3; ++a) {
    p.org[a] = vfloat<N>::Load(org[a]);
    p.dir[a] = vfloat<N>::Load(dir[a]);
    p.inv[a] = vfloat<N>::Load(inv[a]);
    p.invNeg[a] = p.inv[a] < vfloat<N>(0.0f);
    p.s[a] = vfloat<N>::Load(s[a]);
    p.sel[a] = ComponentSelector(vint<N>::Load(k[a]));
    p.orgK[a] = vfloat<N>::Load(orgK[a]);
  }
  p.tmin = vfloat<N>::Load(tmin);
  h.t = vfloat<N>::Load(tmax);
  h.u = vfloat<N>(0.0f);
  h.v = vfloat<N>(0.0f);
  h.g = vint<N>(static_cast<int>(CR_NO_HIT));
}

// Primitive g against the lanes of m; keeps each lane's closer hit
// (Hit_Closer). Returns the lanes whose hit changed.
template <int N, unsigned kTypes, bool kFast>
inline vbool<N> PacketPrim_Intersect(const KernelScene& sc, std::uint32_t g, const RayPacket<N>& P,
                                     HitPacket<N>& H, vbool<N> m)
{
  vfloat<N> t, u(0.0f), v(0.0f);
  vbool<N> ok;
  const PrimCounts& c = sc.counts;
  switch (TypeOf<kTypes>(g, c)) {
    case PrimType::Sphere: {
      const Sphere& sp = sc.spheres[g];
      vfloat<N> f[3];
      for (int i = 0; i < 3; ++i) f[i] = P.org[i] - vfloat<N>(sp.center[i]);
      ok = Sphere_IntersectN<kFast, N>(f, P.dir, vfloat<N>(sp.radius), P.tmin, H.t, t);
      break;
    }
    case PrimType::Triangle: {
      const Triangle& tri = sc.triangles[g - c.nSpheres];
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
        for (int j = 0; j < 3; ++j) {
          A[j] = PermuteXYZ(tri.v0, P.sel[j]) - P.orgK[j];
          B[j] = PermuteXYZ(tri.v1, P.sel[j]) - P.orgK[j];
          C[j] = PermuteXYZ(tri.v2, P.sel[j]) - P.orgK[j];
        }
        ok = Triangle_WatertightN<N>(A, B, C, P.s, P.tmin, H.t, t, u, v);
      }
      break;
    }
    case PrimType::Cone: {
      const ConeData& cd = sc.cones[g - c.nSpheres - c.nTriangles];
      vfloat<N> dl[3], w[3];
      for (int i = 0; i < 3; ++i) {
        dl[i] = P.org[i] - vfloat<N>(cd.base[i]);
        w[i] = vfloat<N>(cd.w[i]);
      }
      ok = Cone_IntersectN<kFast, N>(dl, P.dir, w, vfloat<N>(cd.H), vfloat<N>(cd.r0), vfloat<N>(cd.k), P.tmin, H.t, t);
      break;
    }
  }
  const vint<N> gv(static_cast<int>(g));
  const vbool<N> closer = m & ok & ((t < H.t) | ((t == H.t) & LessUnsigned(gv, H.g)));
  if (None(closer)) return closer;
  H.t = Select(closer, t, H.t);
  H.u = Select(closer, u, H.u);
  H.v = Select(closer, v, H.v);
  H.g = Select(closer, gv, H.g);
  return closer;
}

// Closest hit (anyHit = 0) or any hit of the lanes in `active`.
template <int N, unsigned kTypes, bool kFast, bool kStats>
inline void BVHPacket_Trace(const KernelScene& sc, const RayPacket<N>& P, HitPacket<N>& H, vbool<N> active,
                            int anyHit, StatsSum& st)
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
  vbool<N> m = active & Box_IntersectRays<kFast, N>(nodes[0].bmin, nodes[0].bmax, P.org, P.inv, P.invNeg, P.tmin,
                                                     H.t, tEnter);
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
      const vbool<N> h0 =
          m & Box_IntersectRays<kFast, N>(nodes[c0].bmin, nodes[c0].bmax, P.org, P.inv, P.invNeg, P.tmin, H.t, t0);
      const vbool<N> h1 =
          m & Box_IntersectRays<kFast, N>(nodes[c1].bmin, nodes[c1].bmax, P.org, P.inv, P.invNeg, P.tmin, H.t, t1);
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
      bits = stack[sp].bits & ~done & (stack[sp].t <= H.t).Bits();
      if (bits) {
        ni = stack[sp].node;
        m = vbool<N>::FromBits(bits);
        break;
      }
    }
  }
}

// Traces positions [job.begin, job.end) in packets of N consecutive positions.
template <int N, unsigned kTypes, bool kFast, bool kStats>
void BVHPacket_TraceRange(const KernelScene& sc, const KernelJob& job)
{
  const PrimView pv = MakePrimView(sc);
  StatsSum st;
  for (std::size_t p = job.begin; p < job.end; p += N) {
    const int count = static_cast<int>(job.end - p < std::size_t(N) ? job.end - p : std::size_t(N));
    Ray rays[N];
    std::uint32_t idx[N];
    for (int l = 0; l < count; ++l) {
      idx[l] = RayIndex(job, p + std::size_t(l));
      Ray_Init(&rays[l], &job.rays[idx[l]]);
    }
    for (int l = count; l < N; ++l) rays[l] = rays[0];
    RayPacket<N> P;
    HitPacket<N> H;
    RayPacket_Init<N>(P, H, rays);
    const vbool<N> active = vbool<N>::FromBits((1u << count) - 1u);
    BVHPacket_Trace<N, kTypes, kFast, kStats>(sc, P, H, active, job.occlusion, st);
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
  if constexpr (kStats) AddStats(job.stats, st, job.end - job.begin);
}

}  // namespace cr::simd::CR_SIMD_NS
