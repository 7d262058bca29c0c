// Hierarchical grid (kernels/hgrid.h HGrid_Trace), one ray at a time: rays
// are prepared and enter the root grid N at a time (RayPacket_Init,
// GridPacket_Enter), then each walks the grids cell by cell, descending
// into a child grid from the parameter where it entered the child's cell
// (GridSingle_EnterAt of simd/grid_walk.h), jumping over empty space by
// the cells' distances (HGrid_Skip) and testing a cell's primitives not in
// the ray's mailbox 4 at a time. The structure has no packet walk of its
// own yet: its packet kernel is this one (kernels_hgrid.cpp).
#pragma once

#include <algorithm>
#include <limits>

#include "simd/bvh_single.h"
#include "simd/grid_single.h"
#include "simd/grid_walk.h"
#include "simd/kernel_common.h"

namespace cr::simd::CR_SIMD_NS {

// HGrid_Skip's exit of kernels/hgrid.h: where the ray leaves the box of
// cells within d - 1 of `cell` (grid g, resolution res, steps `step`): its
// parameter, the axis of the plane it leaves by and the box's last cell on
// that axis (x before y before z on ties).
CR_SIMD_INLINE float HGrid_SkipExit(const GridHeader& g, const Ray& ray, const int step[3], const int cell[3],
                                    const int res[3], int d, int& axis, int& last)
{
  float t = std::numeric_limits<float>::infinity();
  axis = 0;
  last = 0;
  for (int a = 0; a < 3; ++a) {
    const int b = step[a] > 0 ? std::min(cell[a] + d - 1, res[a] - 1) : std::max(cell[a] - d + 1, 0);
    const float ta = PlaneT(GridPlane(g, a, step[a] > 0 ? b + 1 : b), ray.org[a], ray.inv[a]);
    if (ta < t) {
      t = ta;
      axis = a;
      last = b;
    }
  }
  return t;
}

// The references refs[begin, end) of a cell not in the ray's mailbox
// (kernels/hgrid.h; slot k at mailbox[k * stride]), in order, a chunk at a
// time, then tested 4 at a time: the scalar loop's tests. True when an
// any-hit query is answered.
template <unsigned kTypes, bool kFast, bool kStats, class PR>
CR_SIMD_INLINE bool HGrid_TestCell(const KernelScene& sc, const std::uint32_t* refs, std::uint32_t begin,
                                   std::uint32_t end, std::uint32_t* mailbox, int stride, const PR& pr, Hit& hit,
                                   int anyHit, TraceStatsSum& st)
{
  constexpr std::uint32_t kChunk = 32;
  alignas(16) std::uint32_t fresh[kChunk];
  std::uint32_t i = begin;
  while (i < end) {
    std::uint32_t n = 0;
    for (; i < end && n < kChunk; ++i) {
      const std::uint32_t prim = refs[i];
      std::uint32_t& slot = mailbox[(prim & (CR_HGRID_MAILBOX - 1u)) * std::uint32_t(stride)];
      if (slot == prim) continue;
      slot = prim;
      fresh[n++] = prim;
    }
    if (n && RayRefs_Intersect<kTypes, kFast, kStats>(sc, fresh, 0, n, pr, hit, anyHit, st) && anyHit) return true;
  }
  return false;
}

// The walk of one ray from cell `first` of the root grid, entered at
// tEnter; HGrid_Trace step by step. Each level keeps the crossing parameter
// of its next plane per axis and recomputes only the axis it stepped (as
// GridSingle_Walk), and the stack keeps the ancestors' (bit for bit the
// scalar walk's recomputed values: their planes have not changed).
template <unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void HGridSingle_Walk(const KernelScene& sc, const Ray& ray, Hit& hit, const int first[3], float tEnter,
                                     int anyHit, TraceStatsSum& st)
{
  PackRayOf<4, kHasMotion<kTypes>> pr;
  PackRay_Init<4>(pr, ray);
  if constexpr (kHasMotion<kTypes>) pr.time = ray.time;
  pr.anyHit = anyHit != 0;
  const std::uint32_t* refs = sc.hgridRefs;
  int step[3];
  for (int a = 0; a < 3; ++a) step[a] = ray.inv[a] < 0.0f ? -1 : 1;
  const float reachPerT =
      CR_HGRID_RAY_ERR * std::max(std::fabs(ray.dir[0]), std::max(std::fabs(ray.dir[1]), std::fabs(ray.dir[2])));
  // The grid walked, in locals: header, cell offsets, cell, next crossings,
  // cell index, its change per step and the resolution; the ancestors' on
  // the stack (what follows from the header is recomputed when popped).
  const GridHeader* g = nullptr;
  const std::uint32_t* cellStart = nullptr;
  int cell[3], dIdx[3], res[3];
  float tNext[3];
  std::uint32_t idx = 0;
  struct Saved {
    const GridHeader* g;
    int cell[3];
    float tNext[3];
    std::uint32_t idx;
  };
  Saved stack[CR_HGRID_MAX_DEPTH];
  int sp = 0;
  std::uint32_t mailbox[CR_HGRID_MAILBOX];
  for (std::uint32_t& m : mailbox) m = CR_NO_HIT;
  const auto setGrid = [&](const GridHeader* ng) __attribute__((always_inline)) {
    g = ng;
    cellStart = refs + ng->first;
    const int stride[3] = {1, int(ng->res[0]), int(ng->res[0] * ng->res[1])};
    for (int a = 0; a < 3; ++a) {
      res[a] = int(ng->res[a]);
      dIdx[a] = step[a] * stride[a];
    }
  };
  const auto enterCell = [&](const int c[3]) __attribute__((always_inline)) {
    for (int a = 0; a < 3; ++a) {
      cell[a] = c[a];
      tNext[a] = PlaneT(GridPlane(*g, a, step[a] > 0 ? c[a] + 1 : c[a]), ray.org[a], ray.inv[a]);
    }
    idx = std::uint32_t(c[0]) + g->res[0] * (std::uint32_t(c[1]) + g->res[1] * std::uint32_t(c[2]));
  };
  setGrid(sc.hgridHeader);
  enterCell(first);
  for (;;) {
    if constexpr (kStats) ++st.nTS;
    std::uint32_t begin = cellStart[idx];
    const std::uint32_t end = cellStart[idx + 1];
    if (begin != end && (refs[begin] & CR_HGRID_CHILD) != 0u) {
      const GridHeader* child = sc.hgridNodes + (refs[begin] & ~CR_HGRID_CHILD);
      // HGrid_Reach at the cell's exit (Grid_CellExit: the smallest of the
      // next crossings, as the scalar walk computes them).
      const float tExit = std::min(tNext[0], std::min(tNext[1], tNext[2]));
      if (reachPerT * tExit <= child->margin) {
        Saved& s = stack[sp++];
        s.g = g;
        for (int a = 0; a < 3; ++a) {
          s.cell[a] = cell[a];
          s.tNext[a] = tNext[a];
        }
        s.idx = idx;
        setGrid(child);
        int c[3];
        GridSingle_EnterAt(*g, ray, tEnter, c);
        enterCell(c);
        continue;
      }
      ++begin;  // finer than the ray's precision: the cell's own references
    }
    if constexpr (kStats) ++st.nLeaves;
    // Set where a jump leaves this grid: the walk goes on in the parent's.
    bool leave = false;
    if (begin == end) {
      if constexpr (kStats) ++st.nEmptyLeaves;
      // HGrid_Distance and HGrid_Skip of kernels/hgrid.h.
      const int d = int((cellStart[g->nCells + 1 + (idx >> 2)] >> ((idx & 3u) * 8u)) & 0xffu);
      if (d >= CR_HGRID_SKIP_MIN) {
        int axis, last;
        const float t = HGrid_SkipExit(*g, ray, step, cell, res, d, axis, last);
        if (t > tEnter) {
          tEnter = t;
          if (hit.t <= t) return;
          const int next = last + step[axis];
          if (static_cast<unsigned>(next) < static_cast<unsigned>(res[axis])) {
            int c[3];
            GridSingle_EnterAt(*g, ray, t, c);
            c[axis] = next;
            enterCell(c);
            continue;
          }
          leave = true;
        }
      }
    } else {
      if (HGrid_TestCell<kTypes, kFast, kStats>(sc, refs, begin, end, mailbox, 1, pr, hit, anyHit, st)) return;
    }
    // Exit face: the smallest crossing, x before y before z on ties (the
    // scalar loop's strict <), chosen without branches.
    for (;;) {
      if (!leave) {
        const float t01 = tNext[1] < tNext[0] ? tNext[1] : tNext[0];
        const int axis = tNext[2] < t01 ? 2 : (tNext[1] < tNext[0] ? 1 : 0);
        tEnter = tNext[axis];
        if (hit.t <= tEnter) return;
        const int c = cell[axis] + step[axis];
        if (static_cast<unsigned>(c) < static_cast<unsigned>(res[axis])) {
          cell[axis] = c;
          idx += static_cast<std::uint32_t>(dIdx[axis]);
          tNext[axis] = PlaneT(GridPlane(*g, axis, step[axis] > 0 ? c + 1 : c), ray.org[axis], ray.inv[axis]);
          break;
        }
      }
      leave = false;
      if (sp == 0) return;
      const Saved& s = stack[--sp];
      setGrid(s.g);
      for (int a = 0; a < 3; ++a) {
        cell[a] = s.cell[a];
        tNext[a] = s.tNext[a];
      }
      idx = s.idx;
    }
  }
}

// Traces positions [job.begin, job.end) one ray at a time (the rays'
// preparation and root entry of simd/grid_single.h).
template <int N, unsigned kTypes, bool kFast, bool kStats>
void HGridSingle_TraceRange(const KernelScene& sc, const KernelJob& job)
{
  TraceStatsSum st;
  GridSingle_Rays<N, kFast, kHasMotion<kTypes>>(
      sc, *sc.hgridHeader, job, [&](const Ray& ray, Hit& hit, const int first[3], float tEnter) {
        HGridSingle_Walk<kTypes, kFast, kStats>(sc, ray, hit, first, tEnter, job.occlusion, st);
      });
  if constexpr (kStats) AddJobStats(job.stats, st, job.end - job.begin);
}

}  // namespace cr::simd::CR_SIMD_NS
