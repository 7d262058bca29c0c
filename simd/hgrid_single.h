// Hierarchical grid (kernels/hgrid.h HGrid_Trace), one ray at a time: rays
// are prepared and enter the root grid N at a time (RayPacket_Init,
// GridPacket_Enter), then each walks the grids cell by cell, descending
// into a child grid from the parameter where it entered the child's cell
// (GridSingle_EnterAt of simd/grid_walk.h), jumping over empty space by
// the cells' distances (HGrid_Skip) and testing a cell's primitives not in
// the ray's mailbox 4 at a time. The packet walk (simd/hgrid_packet.h)
// finishes its last lanes with this walk's loop (HGridWalk_Run).
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

// The descent's test of kernels/hgrid.h: Box_Intersect of child grid g's
// box from tmin up to the closest hit's Cull_Distance; the entry parameter
// in tEnter.
template <bool kFast>
CR_SIMD_INLINE bool HGrid_BoxEnter(const GridHeader& g, const Ray& ray, float tmin, float hitT, float& tEnter)
{
  return Box_SlabsOne<kFast>(g.bmin, g.bmax, ray, tmin, hitT, tEnter);
}

// An ancestor grid on a walk's stack: the cell the walk goes on from (what
// follows from the header is recomputed when popped).
struct HGridSaved {
  const GridHeader* g;
  int cell[3];
  float tNext[3];
  std::uint32_t idx;
};

// One ray's walk state: the grid walked (header, cell offsets, resolution,
// the cell index's change per step), the cell, the next crossing per axis,
// the cell index, the parameter at which the ray entered the cell, the
// ancestors' stack and the mailbox (slot k at mailbox[k * mailboxStride]).
// The single walk keeps it in locals; the packet walk's lanes keep it in
// arrays and a finishing lane runs on a copy (simd/hgrid_packet.h).
struct HGridWalkState {
  const GridHeader* g;
  const std::uint32_t* cellStart;
  int cell[3], dIdx[3], res[3];
  float tNext[3];
  std::uint32_t idx;
  float tEnter;
  HGridSaved* stack;
  int sp;
  std::uint32_t* mailbox;
  int mailboxStride;
};

// The walk in grid ng (its header's fields; not the cell).
CR_SIMD_INLINE void HGridWalk_SetGrid(HGridWalkState& w, const std::uint32_t* refs, const GridHeader* ng,
                                      const int step[3])
{
  w.g = ng;
  w.cellStart = refs + ng->first;
  const int stride[3] = {1, int(ng->res[0]), int(ng->res[0] * ng->res[1])};
  for (int a = 0; a < 3; ++a) {
    w.res[a] = int(ng->res[a]);
    w.dIdx[a] = step[a] * stride[a];
  }
}

// The walk enters cell c of its grid: the crossings of its exit planes and
// its index.
CR_SIMD_INLINE void HGridWalk_EnterCell(HGridWalkState& w, const Ray& ray, const int step[3], const int c[3])
{
  for (int a = 0; a < 3; ++a) {
    w.cell[a] = c[a];
    w.tNext[a] = PlaneT(GridPlane(*w.g, a, step[a] > 0 ? c[a] + 1 : c[a]), ray.org[a], ray.inv[a]);
  }
  w.idx = std::uint32_t(c[0]) + w.g->res[0] * (std::uint32_t(c[1]) + w.g->res[1] * std::uint32_t(c[2]));
}

// HGrid_Trace step by step from the walk's cell to the walk's end, for the
// ray (pr: its 4-wide form for the cells' tests; step: its cell steps;
// reachPerT: CR_HGRID_RAY_ERR times its largest direction component). Each
// level keeps the crossing parameter of its next plane per axis and
// recomputes only the axis it stepped (as GridSingle_Walk), and the stack
// keeps the ancestors' (bit for bit the scalar walk's recomputed values:
// their planes have not changed).
template <unsigned kTypes, bool kFast, bool kStats, class PR>
CR_SIMD_INLINE void HGridWalk_Run(const KernelScene& sc, const Ray& ray, const PR& pr, const int step[3],
                                  float reachPerT, HGridWalkState& w, Hit& hit, int anyHit, TraceStatsSum& st)
{
  const std::uint32_t* refs = sc.hgridRefs;
  for (;;) {
    if constexpr (kStats) ++st.nTS;
    std::uint32_t begin = w.cellStart[w.idx];
    std::uint32_t end = w.cellStart[w.idx + 1];
    // A child cell: its large references, then its child grid where the
    // child is precise enough for the ray (HGrid_Reach at the cell's exit,
    // Grid_CellExit: the smallest of the next crossings, as the scalar walk
    // computes them); else all its references.
    const GridHeader* child = nullptr;
    if (begin != end && (refs[begin] & CR_HGRID_CHILD) != 0u) {
      const GridHeader* c = sc.hgridNodes + (refs[begin] & ~CR_HGRID_CHILD);
      const std::uint32_t nAll = refs[begin + 1];
      begin += 2;
      const float tExit = std::min(w.tNext[0], std::min(w.tNext[1], w.tNext[2]));
      if (reachPerT * tExit <= c->margin) {
        child = c;
        begin += nAll;  // the large references
      } else {
        end = begin + nAll;
      }
    }
    // Set where a jump leaves this grid: the walk goes on in the parent's.
    bool leave = false;
    if (child == nullptr || begin != end) {
      if constexpr (kStats) ++st.nLeaves;
      if (begin == end) {
        if constexpr (kStats) ++st.nEmptyLeaves;
        // HGrid_Distance and HGrid_Skip of kernels/hgrid.h.
        const std::uint32_t idx = w.idx;
        const int d = int((w.cellStart[w.g->nCells + 1 + (idx >> 2)] >> ((idx & 3u) * 8u)) & 0xffu);
        if (d >= CR_HGRID_SKIP_MIN) {
          int axis, last;
          const float t = HGrid_SkipExit(*w.g, ray, step, w.cell, w.res, d, axis, last);
          if (t > w.tEnter) {
            w.tEnter = t;
            if (hit.t <= t) return;
            const int next = last + step[axis];
            if (static_cast<unsigned>(next) < static_cast<unsigned>(w.res[axis])) {
              int c[3];
              GridSingle_EnterAt(*w.g, ray, t, c);
              c[axis] = next;
              HGridWalk_EnterCell(w, ray, step, c);
              continue;
            }
            leave = true;
          }
        }
      } else {
        if (MailboxRefs_Intersect<CR_HGRID_MAILBOX, kTypes, kFast, kStats>(sc, refs, begin, end, w.mailbox,
                                                                           w.mailboxStride, pr, hit, anyHit, st))
          return;
      }
    }
    // Into the child where the ray meets its box before the closest hit,
    // from where it enters the box.
    float tBox;
    if (child != nullptr && HGrid_BoxEnter<kFast>(*child, ray, w.tEnter, hit.t, tBox)) {
      HGridSaved& s = w.stack[w.sp++];
      s.g = w.g;
      for (int a = 0; a < 3; ++a) {
        s.cell[a] = w.cell[a];
        s.tNext[a] = w.tNext[a];
      }
      s.idx = w.idx;
      HGridWalk_SetGrid(w, refs, child, step);
      w.tEnter = tBox;
      int c[3];
      GridSingle_EnterAt(*w.g, ray, w.tEnter, c);
      HGridWalk_EnterCell(w, ray, step, c);
      continue;
    }
    // Exit face: the smallest crossing, x before y before z on ties (the
    // scalar loop's strict <), chosen without branches.
    for (;;) {
      if (!leave) {
        const float t01 = w.tNext[1] < w.tNext[0] ? w.tNext[1] : w.tNext[0];
        const int axis = w.tNext[2] < t01 ? 2 : (w.tNext[1] < w.tNext[0] ? 1 : 0);
        w.tEnter = w.tNext[axis];
        if (hit.t <= w.tEnter) return;
        const int c = w.cell[axis] + step[axis];
        if (static_cast<unsigned>(c) < static_cast<unsigned>(w.res[axis])) {
          w.cell[axis] = c;
          w.idx += static_cast<std::uint32_t>(w.dIdx[axis]);
          w.tNext[axis] =
              PlaneT(GridPlane(*w.g, axis, step[axis] > 0 ? c + 1 : c), ray.org[axis], ray.inv[axis]);
          break;
        }
      }
      leave = false;
      if (w.sp == 0) return;
      const HGridSaved& s = w.stack[--w.sp];
      HGridWalk_SetGrid(w, refs, s.g, step);
      for (int a = 0; a < 3; ++a) {
        w.cell[a] = s.cell[a];
        w.tNext[a] = s.tNext[a];
      }
      w.idx = s.idx;
    }
  }
}

// The walk of one ray from cell `first` of the root grid, entered at
// tEnter (HGridWalk_Run, its state in locals).
template <unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void HGridSingle_Walk(const KernelScene& sc, const Ray& ray, Hit& hit, const int first[3], float tEnter,
                                     int anyHit, TraceStatsSum& st)
{
  PackRayOf<4, kHasMotion<kTypes>> pr;
  PackRay_Init<4>(pr, ray);
  if constexpr (kHasMotion<kTypes>) pr.time = ray.time;
  pr.anyHit = anyHit != 0;
  int step[3];
  for (int a = 0; a < 3; ++a) step[a] = ray.inv[a] < 0.0f ? -1 : 1;
  const float reachPerT =
      CR_HGRID_RAY_ERR * std::max(std::fabs(ray.dir[0]), std::max(std::fabs(ray.dir[1]), std::fabs(ray.dir[2])));
  HGridSaved stack[CR_HGRID_MAX_DEPTH];
  std::uint32_t mailbox[CR_HGRID_MAILBOX];
  for (std::uint32_t& m : mailbox) m = CR_NO_HIT;
  HGridWalkState w;
  w.stack = stack;
  w.sp = 0;
  w.mailbox = mailbox;
  w.mailboxStride = 1;
  w.tEnter = tEnter;
  HGridWalk_SetGrid(w, sc.hgridRefs, sc.hgridHeader, step);
  HGridWalk_EnterCell(w, ray, step, first);
  HGridWalk_Run<kTypes, kFast, kStats>(sc, ray, pr, step, reachPerT, w, hit, anyHit, st);
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
