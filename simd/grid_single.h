// Uniform grid, one ray at a time, for incoherent rays: the 3D-DDA of
// kernels/grid.h Grid_Trace step by step, with SIMD inside the ray's work:
//  - rays are prepared and entered N at a time (RayPacket_Init and
//    GridPacket_Enter: the slab test of the grid box and the branchy
//    first-cell correction on N lanes);
//  - a cell's primitives are tested 4 at a time, gathered from the scene
//    arrays (simd/prim_range.h), so the grid needs no extra memory
//    (GridSingle_Walk, simd/grid_walk.h).
#pragma once

#include "simd/bvh_single.h"
#include "simd/grid_walk.h"
#include "simd/kernel_common.h"

namespace cr::simd::CR_SIMD_NS {

// Positions [job.begin, job.end) of a grid-walking structure whose root is
// grid g, N rays at a time: rays prepared and entered N at a time, then
// walk(P, H, rays, in, cells, tEnter) with the packet, its hits (as Hit_Init
// leaves them; the walk updates them), its rays lane by lane, the lanes that
// enter the grid (bits of `in`), their first cells and entry parameters; the
// answers (H) to job.hits. kTiles: packets as Packet_Rays forms them (image
// tiles where the job has them), else in job order. kMotion (a moving
// scene): each ray also takes its time (Ray::time; the packet's,
// RayPacketOf).
template <int N, bool kFast, bool kMotion, bool kTiles, class Walk>
CR_SIMD_INLINE void GridEntry_Packets(const KernelScene& sc, const GridHeader& g, const KernelJob& job, Walk&& walk)
{
  const PrimView pv = MakePrimView(sc);
  for (std::size_t p = job.begin; p < job.end; p += N) {
    const RayRecord* recs[N];
    std::uint32_t idx[N];
    const int count = kTiles ? Packet_Rays<N>(job, p, recs, idx) : Job_Rays<N>(job, p, recs, idx);
    RayPacketOf<N, kMotion> P;
    HitPacket<N> H;
    RayPacket_Init<N>(P, H, recs);
    if constexpr (kMotion) P.time = Job_Times<N>(job, idx, count);
    vint<N> cellV[3] = {vint<N>(0), vint<N>(0), vint<N>(0)};
    vfloat<N> tEnterV(0.0f);
    unsigned in = 0;
    if (g.nRefs != 0u)
      in = GridPacket_Enter<N, kFast>(g, P, H, vbool<N>::FromBits((1u << count) - 1u), cellV, &tEnterV).Bits();
    if (in) {
      alignas(32) std::uint32_t cells[3][N];
      alignas(32) float tEnter[N];
      for (int a = 0; a < 3; ++a) cellV[a].Store(cells[a]);
      tEnterV.Store(tEnter);
      Ray rays[N];
      RayPacket_Extract<N>(P, H, rays);
      if constexpr (kMotion)
        for (int l = 0; l < N; ++l) rays[l].time = Job_Time(job, idx[l < count ? l : 0]);
      walk(P, H, rays, in, cells, tEnter);
    }
    Packet_StoreHits<N>(sc, pv, job, H, idx, count);
  }
}

// The same, one ray at a time: walk(ray, hit, first, tEnter) for each ray
// that enters, from its first cell and entry parameter. Serves the uniform
// grid and the hierarchical grid (simd/hgrid_single.h).
template <int N, bool kFast, bool kMotion, class Walk>
CR_SIMD_INLINE void GridSingle_Rays(const KernelScene& sc, const GridHeader& g, const KernelJob& job, Walk&& walk)
{
  GridEntry_Packets<N, kFast, kMotion, false>(
      sc, g, job,
      [&](const RayPacket<N>&, HitPacket<N>& H, const Ray* rays, unsigned in, const std::uint32_t (&cells)[3][N],
          const float* tEnter) {
        HitLanes<N> hits(H);
        for (unsigned rest = in; rest; rest &= rest - 1u) {
          const int l = LowestBit(rest);
          const int first[3] = {int(cells[0][l]), int(cells[1][l]), int(cells[2][l])};
          Hit hit = hits.Get(l);
          walk(rays[l], hit, first, tEnter[l]);
          hits.Set(l, hit);
        }
        hits.To(H);
      });
}

// Traces positions [job.begin, job.end) one ray at a time.
template <int N, unsigned kTypes, bool kFast, bool kStats>
void GridSingle_TraceRange(const KernelScene& sc, const KernelJob& job)
{
  const GridHeader& g = *sc.gridHeader;
  TraceStatsSum st;
  GridSingle_Rays<N, kFast, kHasMotion<kTypes>>(
      sc, g, job, [&](const Ray& ray, Hit& hit, const int first[3], float) {
        PackRayOf<4, kHasMotion<kTypes>> pr;
        PackRay_Init<4>(pr, ray);
        if constexpr (kHasMotion<kTypes>) pr.time = ray.time;
        pr.anyHit = job.occlusion != 0;
        GridSingle_Walk<kTypes, kFast, kStats>(sc, g, sc.gridNodes, sc.gridRefs, pr, ray, hit, first, job.occlusion,
                                               st);
      });
  if constexpr (kStats) AddJobStats(job.stats, st, job.end - job.begin);
}

}  // namespace cr::simd::CR_SIMD_NS
