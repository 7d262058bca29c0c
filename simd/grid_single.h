// Uniform grid, one ray at a time, for incoherent rays: the 3D-DDA of
// kernels/grid.h Grid_Trace step by step, with SIMD inside the ray's work:
//  - rays are prepared and entered N at a time (RayPacket_Init and
//    GridPacket_Enter: the slab test of the grid box and the branchy
//    first-cell correction on N lanes);
//  - a cell's primitives are tested 4 at a time, gathered from the scene
//    arrays (simd/prim_range.h), so the grid needs no extra memory.
// The walk keeps the crossing parameter of each axis's next plane and
// recomputes only the axis it stepped: the other two planes have not changed,
// so their parameters are the scalar loop's recomputed values, bit for bit.
#pragma once

#include "simd/bvh_single.h"
#include "simd/grid_packet.h"
#include "simd/kernel_common.h"
#include "simd/prim_range.h"

namespace cr::simd::CR_SIMD_NS {

// The walk of one ray from its first cell; `hit` from Hit_Init.
template <unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void GridSingle_Walk(const KernelScene& sc, const Ray& ray, Hit& hit, const int first[3], int anyHit,
                                    StatsSum& st)
{
  const GridHeader& g = *sc.grid;
  PackRay<4> pr;
  PackRay_Init<4>(pr, ray);
  int cell[3], step[3], res[3];
  float tNext[3];  // crossing of each axis's exit plane
  for (int a = 0; a < 3; ++a) {
    cell[a] = first[a];
    res[a] = static_cast<int>(g.res[a]);
    step[a] = ray.inv[a] < 0.0f ? -1 : 1;
    tNext[a] = PlaneT(GridPlane(g, a, step[a] > 0 ? cell[a] + 1 : cell[a]), ray.org[a], ray.inv[a]);
  }
  for (;;) {
    if constexpr (kStats) {
      ++st.nTS;
      ++st.nLeaves;
    }
    const std::uint32_t idx =
        std::uint32_t(cell[0]) + g.res[0] * (std::uint32_t(cell[1]) + g.res[1] * std::uint32_t(cell[2]));
    const std::uint32_t begin = sc.cellStart[idx], end = sc.cellStart[idx + 1];
    if (begin == end) {
      if constexpr (kStats) ++st.nEmptyLeaves;
    } else if (RayRefs_Intersect<kTypes, kFast, kStats>(sc, sc.gridRefs, begin, end, pr, hit, anyHit, st) && anyHit) {
      return;
    }
    int axis = 0;
    float tExit = __builtin_inff();
    for (int a = 0; a < 3; ++a) {
      if (tNext[a] < tExit) {
        tExit = tNext[a];
        axis = a;
      }
    }
    if (hit.t <= tExit) return;
    cell[axis] += step[axis];
    if (cell[axis] < 0 || cell[axis] >= res[axis]) return;
    tNext[axis] =
        PlaneT(GridPlane(g, axis, step[axis] > 0 ? cell[axis] + 1 : cell[axis]), ray.org[axis], ray.inv[axis]);
  }
}

// Traces positions [job.begin, job.end) one ray at a time.
template <int N, unsigned kTypes, bool kFast, bool kStats>
void GridSingle_TraceRange(const KernelScene& sc, const KernelJob& job)
{
  const PrimView pv = MakePrimView(sc);
  const GridHeader& g = *sc.grid;
  StatsSum st;
  for (std::size_t p = job.begin; p < job.end; p += N) {
    const int count = static_cast<int>(job.end - p < std::size_t(N) ? job.end - p : std::size_t(N));
    const RayRecord* recs[N];
    std::uint32_t idx[N];
    for (int l = 0; l < count; ++l) {
      idx[l] = RayIndex(job, p + std::size_t(l));
      recs[l] = &job.rays[idx[l]];
    }
    for (int l = count; l < N; ++l) recs[l] = recs[0];
    RayPacket<N> P;
    HitPacket<N> H;
    RayPacket_Init<N>(P, H, recs);
    vint<N> cellV[3] = {vint<N>(0), vint<N>(0), vint<N>(0)};
    unsigned in = 0;
    if (g.nRefs != 0u) in = GridPacket_Enter<N, kFast>(g, P, H, vbool<N>::FromBits((1u << count) - 1u), cellV).Bits();
    alignas(32) std::uint32_t cells[3][N];
    for (int a = 0; a < 3; ++a) cellV[a].Store(cells[a]);
    Ray rays[N];
    RayPacket_Extract<N>(P, H, rays);
    for (int l = 0; l < count; ++l) {
      const Ray& ray = rays[l];
      Hit hit;
      Hit_Init(&hit, &ray);
      if ((in >> l) & 1u) {
        const int first[3] = {int(cells[0][l]), int(cells[1][l]), int(cells[2][l])};
        GridSingle_Walk<kTypes, kFast, kStats>(sc, ray, hit, first, job.occlusion, st);
      }
      job.hits[idx[l]] = Hit_ToRecord(&hit, &pv, sc.primIds, job.occlusion, sc.unifiedHits);
    }
  }
  if constexpr (kStats) AddStats(job.stats, st, job.end - job.begin);
}

}  // namespace cr::simd::CR_SIMD_NS
