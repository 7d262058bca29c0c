// Uniform grid, N rays at once: every lane walks its own 3D-DDA (Amanatides
// & Woo 1987; Hearn & Baker, section 14-6) with masked updates, as
// Grid_Trace of kernels/grid.h does for one ray:
//  - entry by the conservative slab test of the grid box against the lane's
//    current hit, the first cell from the entry point, then corrected until
//    the planes of Grid_Plane agree with the entry parameter;
//  - per iteration each live lane's exit plane is recomputed from its cell
//    through Grid_Plane and Ray_PlaneT (never accumulated), the smallest
//    of the three wins with the scalar tie rule (x before y before z);
//  - a lane stops when its closest hit so far lies at or before its cell's
//    exit, when it steps out of the grid, or (occlusion) at its first hit.
// Lanes that stand in the same cell share one pass over its references (the
// cell's primitives are loaded once for all of them); lanes in different
// cells take one pass each. Per lane this is the scalar walk step by step,
// so hits, order of tests and statistics are the scalar backend's.
//
// GridPacket_Enter is also the vectorised setup of the single-ray path
// (simd/grid_single.h): the branchy first-cell correction runs on N rays at
// once there too.
#pragma once

#include "simd/bvh_packet.h"
#include "simd/kernel_common.h"
#include "simd/prim_range.h"

namespace cr::simd::CR_SIMD_NS {

// Grid_Plane of kernels/grid.h: bmin + (float)i * cellSize, in float.
CR_SIMD_INLINE float GridPlane(const GridHeader& g, int axis, int i)
{
  return g.bmin[axis] + static_cast<float>(i) * g.cellSize[axis];
}
template <int N>
CR_SIMD_INLINE vfloat<N> GridPlaneN(const GridHeader& g, int axis, vint<N> i)
{
  return vfloat<N>(g.bmin[axis]) + ToFloat(i) * vfloat<N>(g.cellSize[axis]);
}

// The lanes of `active` that enter the grid, and each one's first cell
// (kernels/grid.h Grid_Trace before its loop).
template <int N, bool kFast>
CR_SIMD_INLINE vbool<N> GridPacket_Enter(const GridHeader& g, const RayPacket<N>& P, const HitPacket<N>& H,
                                         vbool<N> active, vint<N> cell[3])
{
  vfloat<N> tEnter;
  const vbool<N> in =
      active & Box_IntersectRays<kFast, N>(g.bmin, g.bmax, P.org, P.inv, P.invNeg, P.tmin, H.t, tEnter);
  if (None(in)) return in;
  const vint<N> one(1), zero(0);
  for (int a = 0; a < 3; ++a) {
    const int res = static_cast<int>(g.res[a]);
    const vfloat<N> p = P.org[a] + tEnter * P.dir[a];
    vfloat<N> rel = (p - vfloat<N>(GridPlane(g, a, 0))) / vfloat<N>(g.cellSize[a]);
    rel = FMin(FMax(rel, vfloat<N>(0.0f)), vfloat<N>(static_cast<float>(res - 1)));
    vint<N> c = FloorToInt(rel);
    const vint<N> top(res - 1);
    auto planeT = [&](vint<N> i) { return PlaneTN<N>(GridPlaneN<N>(g, a, i), P.org[a], P.inv[a]); };
    const vbool<N> up = AndNot(in, P.invNeg[a]), down = in & P.invNeg[a];
    // Each loop is a scalar `while` run on its lanes at once: a lane leaves
    // it at its first failed test. Lanes stepping up run
    //   while (c > 0 && T(c) > tEnter) --c;  while (c < res - 1 && T(c + 1) < tEnter) ++c;
    // lanes stepping down
    //   while (c < res - 1 && T(c + 1) > tEnter) ++c;  while (c > 0 && T(c) < tEnter) --c;
    // (the second loop below serves the second of the first and the first of the second).
    vbool<N> m = up & (c > zero);
    while (Any(m = m & (planeT(c) > tEnter))) {
      c = c - Select(m, one, zero);
      m = m & (c > zero);
    }
    m = (up | down) & (c < top);
    for (;;) {
      const vfloat<N> tn = planeT(c + one);
      m = m & ((down & (tn > tEnter)) | AndNot(tn < tEnter, down));
      if (None(m)) break;
      c = c + Select(m, one, zero);
      m = m & (c < top);
    }
    m = down & (c > zero);
    while (Any(m = m & (planeT(c) < tEnter))) {
      c = c - Select(m, one, zero);
      m = m & (c > zero);
    }
    cell[a] = c;
  }
  return in;
}

// Closest hit (anyHit = 0) or any hit of the lanes in `active`.
template <int N, unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void GridPacket_Trace(const KernelScene& sc, const RayPacket<N>& P, HitPacket<N>& H, vbool<N> active,
                                     int anyHit, StatsSum& st)
{
  const GridHeader& g = *sc.grid;
  if (g.nRefs == 0u) return;
  vint<N> cell[3];
  vbool<N> live = GridPacket_Enter<N, kFast>(g, P, H, active, cell);
  if (None(live)) return;
  const vint<N> res[3] = {vint<N>(int(g.res[0])), vint<N>(int(g.res[1])), vint<N>(int(g.res[2]))};
  vint<N> step[3];
  for (int a = 0; a < 3; ++a) step[a] = Select(P.invNeg[a], vint<N>(-1), vint<N>(1));
  const std::uint32_t* cellStart = sc.cellStart;
  const std::uint32_t* refs = sc.gridRefs;
  for (;;) {
    if constexpr (kStats) {
      st.nTS += PopCount(live.Bits());
      st.nLeaves += PopCount(live.Bits());
    }
    const vint<N> idx = cell[0] + res[0] * (cell[1] + res[1] * cell[2]);
    alignas(32) std::uint32_t idxs[N];
    idx.Store(idxs);
    unsigned done = 0;  // occlusion: lanes with an occluder
    for (unsigned pending = live.Bits(); pending;) {
      const std::uint32_t c = idxs[LowestBit(pending)];
      const vbool<N> m = live & (idx == vint<N>(static_cast<int>(c)));
      pending &= ~m.Bits();
      const std::uint32_t begin = cellStart[c], end = cellStart[c + 1];
      if (begin == end) {
        if constexpr (kStats) st.nEmptyLeaves += PopCount(m.Bits());
        continue;
      }
      PacketRefs_Intersect<N, kTypes, kFast, kStats>(sc, refs, begin, end, P, H, m, anyHit, done, st);
    }
    if (done) {
      live = AndNot(live, vbool<N>::FromBits(done));
      if (None(live)) return;
    }
    // Exit face: the smallest crossing of the three exit planes (strict <,
    // so x wins ties over y and z, as in the scalar loop).
    vfloat<N> tExit(__builtin_inff());
    vint<N> axis(0);
    for (int a = 0; a < 3; ++a) {
      const vint<N> plane = Select(P.invNeg[a], cell[a], cell[a] + vint<N>(1));
      const vfloat<N> t = PlaneTN<N>(GridPlaneN<N>(g, a, plane), P.org[a], P.inv[a]);
      const vbool<N> lt = t < tExit;
      tExit = Select(lt, t, tExit);
      axis = Select(lt, vint<N>(a), axis);
    }
    live = AndNot(live, H.t <= tExit);
    if (None(live)) return;
    for (int a = 0; a < 3; ++a) {
      const vbool<N> s = live & (axis == vint<N>(a));
      cell[a] = cell[a] + Select(s, step[a], vint<N>(0));
      live = AndNot(live, s & !LessUnsigned(cell[a], res[a]));
    }
    if (None(live)) return;
  }
}

// Traces positions [job.begin, job.end) in packets of N.
template <int N, unsigned kTypes, bool kFast, bool kStats>
void GridPacket_TraceRange(const KernelScene& sc, const KernelJob& job)
{
  const PrimView pv = MakePrimView(sc);
  StatsSum st;
  for (std::size_t p = job.begin; p < job.end; p += N) {
    const RayRecord* recs[N];
    std::uint32_t idx[N];
    const int count = Packet_Rays<N>(job, p, recs, idx);
    RayPacket<N> P;
    HitPacket<N> H;
    RayPacket_Init<N>(P, H, recs);
    GridPacket_Trace<N, kTypes, kFast, kStats>(sc, P, H, vbool<N>::FromBits((1u << count) - 1u), job.occlusion, st);
    Packet_StoreHits<N>(sc, pv, job, H, idx, count);
  }
  if constexpr (kStats) AddStats(job.stats, st, job.end - job.begin);
}

}  // namespace cr::simd::CR_SIMD_NS
