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
// cells take one pass each (one or two lanes in a cell of four references or
// more: lane by lane, 4 primitives at once, CellRefs_Intersect). Per lane
// this is the scalar walk step by step, so hits, order of tests and
// closest-hit statistics are the scalar backend's.
//
// Lanes stay busy: on gears and teapot primary rays 88% and 92% of the
// iterations have all 8 lanes live, so finishing a lone lane with the
// single-ray walk gained nothing (measured).
#pragma once

#include "simd/bvh_packet.h"
#include "simd/grid_walk.h"
#include "simd/kernel_common.h"
#include "simd/prim_range.h"

namespace cr::simd::CR_SIMD_NS {

// Closest hit (anyHit = 0) or any hit of the lanes in `active`.
template <int N, unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void GridPacket_Trace(const KernelScene& sc, const RayPacket<N>& P, HitPacket<N>& H, vbool<N> active,
                                     int anyHit, TraceStatsSum& st)
{
  const GridHeader& g = *sc.gridHeader;
  if (g.nRefs == 0u) return;
  vint<N> cell[3];
  vbool<N> live = GridPacket_Enter<N, kFast>(g, P, H, active, cell);
  if (None(live)) return;
  // Per lane and axis: the index of the exit plane, its crossing parameter,
  // the step, the exit plane index at which the walk has left the grid, and
  // the change of the cell index per step (cell strides 1, res x, res x res y).
  const int stride[3] = {1, int(g.res[0]), int(g.res[0] * g.res[1])};
  vint<N> exitPlane[3], step[3], limit[3], dIdx[3];
  vfloat<N> tNext[3];
  auto planeT = [&](int a, vint<N> i) { return PlaneTN<N>(GridPlaneN<N>(g, a, i), P.org[a], P.inv[a]); };
  // (p - org) * inv is NaN only where inv is infinite (a direction component
  // +-0); on axes where no lane has one, the crossings need no NaN rule.
  bool flatAxis[3];
  for (int a = 0; a < 3; ++a) flatAxis[a] = Any(Abs(P.inv[a]) == vfloat<N>(__builtin_inff()));
  for (int a = 0; a < 3; ++a) {
    const vbool<N> down = P.invNeg[a];
    exitPlane[a] = Select(down, cell[a], cell[a] + vint<N>(1));
    tNext[a] = planeT(a, exitPlane[a]);
    step[a] = Select(down, vint<N>(-1), vint<N>(1));
    limit[a] = Select(down, vint<N>(-1), vint<N>(int(g.res[a]) + 1));
    dIdx[a] = Select(down, vint<N>(-stride[a]), vint<N>(stride[a]));
  }
  vint<N> idx = cell[0] + vint<N>(stride[1]) * cell[1] + vint<N>(stride[2]) * cell[2];
  const std::uint32_t* cellStart = sc.gridNodes;
  const std::uint32_t* refs = sc.gridRefs;
  for (;;) {
    const unsigned liveBits = live.Bits();
    if constexpr (kStats) {
      st.nTS += PopCount(liveBits);
      st.nLeaves += PopCount(liveBits);
    }
    // The crossing after one more step on each axis, computed before it is
    // known which axis steps, so that the walk's chain of dependent
    // operations from one cell to the next stays short.
    vfloat<N> cand[3];
    for (int a = 0; a < 3; ++a) {
      const vint<N> next = exitPlane[a] + step[a];
      cand[a] = flatAxis[a] ? planeT(a, next) : (GridPlaneN<N>(g, a, next) - P.org[a]) * P.inv[a];
    }
    // The reference ranges of the lanes' cells, gathered for all lanes at
    // once: most cells are empty, and that test is well predicted, where a
    // test for "all lanes in one cell" first was not (measured: 3-7% slower).
    const vint<N> safeIdx = Select(live, idx, vint<N>(0));  // lanes that are not live read cell 0
    vint<N> begin, end;
    GatherPairs(cellStart, safeIdx, begin, end);
    const vbool<N> full = AndNot(live, begin == end);
    if constexpr (kStats) st.nEmptyLeaves += PopCount(AndNot(live, full).Bits());
    unsigned done = 0;  // occlusion: lanes with an occluder
    if (Any(full)) {
      alignas(32) std::uint32_t idxs[N], begins[N], ends[N];
      idx.Store(idxs);
      begin.Store(begins);
      end.Store(ends);
      // One pass over each occupied cell, for all the lanes that stand in it
      // (the lanes of a coherent packet often stand in one).
      for (unsigned pending = full.Bits(); pending;) {
        const int l = LowestBit(pending);
        const vbool<N> m = full & (idx == vint<N>(static_cast<int>(idxs[l])));
        pending &= ~m.Bits();
        CellRefs_Intersect<N, kTypes, kFast, kStats>(sc, refs, begins[l], ends[l], P, H, m, anyHit, done, st);
      }
    }
    if (done) {
      live = AndNot(live, vbool<N>::FromBits(done));
      if (None(live)) return;
    }
    // Exit face: the smallest crossing; on a tie x wins over y and z, and y
    // over z (the scalar loop's strict <). No crossing is NaN (PlaneTN).
    // Every lane steps, the ones that stop here too: a lane that is not live
    // is never read again (its cell index is masked off the gather), so the
    // step needs no live mask, and the chain of dependent operations from
    // one crossing to the next is the choice of the axis and one blend; the
    // three axes' choices exclude each other, so their updates are
    // independent.
    const vfloat<N> tExit = Min(Min(tNext[0], tNext[1]), tNext[2]);
    vbool<N> s[3];
    s[2] = (tNext[2] < tNext[0]) & (tNext[2] < tNext[1]);
    s[1] = AndNot(tNext[1] < tNext[0], s[2]);
    s[0] = !(s[1] | s[2]);
    vbool<N> out = H.t <= tExit;
    for (int a = 0; a < 3; ++a) {
      exitPlane[a] = exitPlane[a] + MaskedOrZero(s[a], step[a]);
      idx = idx + MaskedOrZero(s[a], dIdx[a]);
      tNext[a] = Select(s[a], cand[a], tNext[a]);
      out = out | (s[a] & (exitPlane[a] == limit[a]));
    }
    live = AndNot(live, out);
    if (None(live)) return;
  }
}

// Traces positions [job.begin, job.end) in packets of N.
template <int N, unsigned kTypes, bool kFast, bool kStats>
void GridPacket_TraceRange(const KernelScene& sc, const KernelJob& job)
{
  Packet_TraceRangeWith<N, kStats, kHasMotion<kTypes>>(
      sc, job, [&](RayPacket<N>& P, HitPacket<N>& H, vbool<N> lanes, int anyHit, TraceStatsSum& st) {
        GridPacket_Trace<N, kTypes, kFast, kStats>(sc, P, H, lanes, anyHit, st);
      });
}

}  // namespace cr::simd::CR_SIMD_NS
