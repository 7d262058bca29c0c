// Two-level grid (kernels/grid2.h Grid2_Trace), one ray at a time: rays are
// prepared and enter the top grid N at a time (RayPacket_Init,
// GridPacket_Enter), then each walks the top grid cell by cell and, in each
// non-empty top cell, that cell's sub-grid from the parameter where it
// entered the cell (GridSingle_EnterAt, GridSingle_Walk of simd/grid_walk.h:
// primitives 4 at a time). The structure has no packet walk of its own yet:
// its packet kernel is this one (kernels_grid2.cpp).
#pragma once

#include "simd/bvh_single.h"
#include "simd/grid_walk.h"
#include "simd/kernel_common.h"

namespace cr::simd::CR_SIMD_NS {

// The walk of one ray through the top grid from cell `first`, entered at
// tEnter; as Grid2_Trace step by step.
template <unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void Grid2Single_Walk(const KernelScene& sc, const Ray& ray, Hit& hit, const int first[3], float tEnter,
                                     int anyHit, TraceStatsSum& st)
{
  const GridHeader& g = *sc.grid2Header;
  int cell[3], step[3], res[3], dIdx[3];
  float tNext[3];
  const int stride[3] = {1, int(g.res[0]), int(g.res[0] * g.res[1])};
  for (int a = 0; a < 3; ++a) {
    cell[a] = first[a];
    res[a] = static_cast<int>(g.res[a]);
    step[a] = ray.inv[a] < 0.0f ? -1 : 1;
    dIdx[a] = step[a] * stride[a];
    tNext[a] = PlaneT(GridPlane(g, a, step[a] > 0 ? cell[a] + 1 : cell[a]), ray.org[a], ray.inv[a]);
  }
  std::uint32_t idx = std::uint32_t(cell[0] + stride[1] * cell[1] + stride[2] * cell[2]);
  for (;;) {
    if constexpr (kStats) ++st.nTS;
    const GridHeader& sub = sc.grid2Nodes[idx];
    if (sub.nRefs == 0u) {
      if constexpr (kStats) {
        ++st.nLeaves;
        ++st.nEmptyLeaves;
      }
    } else {
      int subCell[3];
      GridSingle_EnterAt(sub, ray, tEnter, subCell);
      if (GridSingle_Walk<kTypes, kFast, kStats>(sc, sub, sc.grid2Refs + sub.first, sc.grid2Refs, ray, hit, subCell,
                                                 anyHit, st))
        return;
    }
    const float t01 = tNext[1] < tNext[0] ? tNext[1] : tNext[0];
    const int axis = tNext[2] < t01 ? 2 : (tNext[1] < tNext[0] ? 1 : 0);
    tEnter = tNext[axis];
    if (hit.t <= tEnter) return;
    cell[axis] += step[axis];
    if (static_cast<unsigned>(cell[axis]) >= static_cast<unsigned>(res[axis])) return;
    idx += static_cast<std::uint32_t>(dIdx[axis]);
    tNext[axis] =
        PlaneT(GridPlane(g, axis, step[axis] > 0 ? cell[axis] + 1 : cell[axis]), ray.org[axis], ray.inv[axis]);
  }
}

// Traces positions [job.begin, job.end) one ray at a time.
template <int N, unsigned kTypes, bool kFast, bool kStats>
void Grid2Single_TraceRange(const KernelScene& sc, const KernelJob& job)
{
  const PrimView pv = MakePrimView(sc);
  const GridHeader& g = *sc.grid2Header;
  TraceStatsSum st;
  for (std::size_t p = job.begin; p < job.end; p += N) {
    const RayRecord* recs[N];
    std::uint32_t idx[N];
    const int count = Job_Rays<N>(job, p, recs, idx);
    RayPacket<N> P;
    HitPacket<N> H;
    RayPacket_Init<N>(P, H, recs);
    vint<N> cellV[3] = {vint<N>(0), vint<N>(0), vint<N>(0)};
    vfloat<N> tEnterV(0.0f);
    unsigned in = 0;
    if (g.nRefs != 0u)
      in = GridPacket_Enter<N, kFast>(g, P, H, vbool<N>::FromBits((1u << count) - 1u), cellV, &tEnterV).Bits();
    alignas(32) std::uint32_t cells[3][N];
    alignas(32) float tEnter[N];
    for (int a = 0; a < 3; ++a) cellV[a].Store(cells[a]);
    tEnterV.Store(tEnter);
    Ray rays[N];
    RayPacket_Extract<N>(P, H, rays);
    for (int l = 0; l < count; ++l) {
      const Ray& ray = rays[l];
      Hit hit;
      Hit_Init(&hit, &ray);
      if ((in >> l) & 1u) {
        const int first[3] = {int(cells[0][l]), int(cells[1][l]), int(cells[2][l])};
        Grid2Single_Walk<kTypes, kFast, kStats>(sc, ray, hit, first, tEnter[l], job.occlusion, st);
      }
      job.hits[idx[l]] = Hit_ToRecord(&hit, &pv, sc.primIds, job.occlusion, sc.unifiedHits);
    }
  }
  if constexpr (kStats) AddJobStats(job.stats, st, job.end - job.begin);
}

}  // namespace cr::simd::CR_SIMD_NS
