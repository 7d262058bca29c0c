// Hierarchical grid (kernels/hgrid.h HGrid_Trace), N rays at once: every
// lane walks its own ray through the grids, as simd/hgrid_single.h walks
// one, the lanes' states side by side (per lane: the grid walked and its
// planes, cell, next crossings, cell index, entry parameter, ancestors and
// mailbox). What every lane does at every cell runs on all lanes at once:
// the cells' reference ranges and child markers are gathered together; the
// step to the next cell (the exit axis by the scalar tie rule, the end of
// the walk at the closest hit so far, the crossing of the new exit plane
// recomputed from its plane), the entry into a child grid's cell
// (GridPacket_CellAt) and the jump over empty cells by their distance
// (HGrid_SkipExit's box exit) are vector passes with per-lane planes.
// Lanes that stand in one cell share a packet pass over its references
// (each primitive on the lanes that do not have it in their mailboxes);
// one or two lanes in a larger cell test it alone (MailboxRefs_Intersect, 4 at a
// time). Lane by lane: the choice to descend, the return to the parent
// grid, and the packet's last lanes (finishLane: the single walk's loop).
// The walk takes the packet's hits (HitPacket) and leaves its answers there.
//
// Per lane this is the single walk, step for step and bit for bit (the same
// planes, crossings, cells, tests in the same order), so the hits and the
// per-ray counts are the scalar backend's. As for the uniform grid (simd/
// grid_packet.h), the walks' dependent chains run side by side, which the
// single walk leaves to the core's out-of-order window.
#pragma once

#include <algorithm>
#include <limits>

#include "simd/grid_single.h"
#include "simd/hgrid_single.h"

namespace cr::simd::CR_SIMD_NS {

// A packet's last lanes, this many or fewer, finish their walks one at a
// time (finishLane).
inline constexpr int kHGridFinishLanes = 2;

template <int N>
struct HGridLanes {
  // The grid each lane walks: header, planes (bmin + i * cellSize), cell
  // offsets (first), resolution and change of the cell index per step.
  const GridHeader* g[N];
  alignas(32) float bmin[3][N], cs[3][N];
  alignas(32) std::int32_t res[3][N], dIdx[3][N];
  alignas(32) std::uint32_t first[N], dist[N];  // where the cell offsets and the distance bytes begin
  // Where each lane is: cell, next crossing per axis, cell index, the
  // parameter at which it entered the cell, its closest hit's t.
  alignas(32) std::int32_t cell[3][N];
  alignas(32) float tNext[3][N];
  alignas(32) std::uint32_t idx[N];
  alignas(32) float tEnter[N], hitT[N];
  HGridSaved stack[N][CR_HGRID_MAX_DEPTH];
  int sp[N];
  // The lanes' mailboxes, slot by slot (slot k of lane l: mailbox[k][l]).
  alignas(32) std::uint32_t mailbox[CR_HGRID_MAILBOX][N];
};

template <int N, unsigned kTypes, bool kFast, bool kStats>
CR_SIMD_INLINE void HGridPacket_Walk(const KernelScene& sc, const RayPacket<N>& P, HitPacket<N>& H, const Ray* rays,
                                     unsigned live, const std::uint32_t (&cells)[3][N], const float* tEnter0,
                                     int anyHit, TraceStatsSum& st)
{
  const std::uint32_t* refs = sc.hgridRefs;
  HGridLanes<N> L;
  PackRayOf<4, kHasMotion<kTypes>> prs[N];
  int step[3][N];
  float reachPerT[N];
  // Lane l's grid (the single walk's setGrid).
  const auto setGrid = [&](int l, const GridHeader* ng) __attribute__((always_inline)) {
    L.g[l] = ng;
    L.first[l] = ng->first;
    L.dist[l] = ng->first + ng->nCells + 1u;
    const int stride[3] = {1, int(ng->res[0]), int(ng->res[0] * ng->res[1])};
    for (int a = 0; a < 3; ++a) {
      L.bmin[a][l] = ng->bmin[a];
      L.cs[a][l] = ng->cellSize[a];
      L.res[a][l] = int(ng->res[a]);
      L.dIdx[a][l] = step[a][l] * stride[a];
    }
  };
  // Lane l into child grid `child`: its grid and cell onto its stack (the
  // cell within the child is entered by the caller).
  const auto descend = [&](int l, const GridHeader* child) __attribute__((always_inline)) {
    HGridSaved& s = L.stack[l][L.sp[l]++];
    s.g = L.g[l];
    for (int a = 0; a < 3; ++a) {
      s.cell[a] = L.cell[a][l];
      s.tNext[a] = L.tNext[a][l];
    }
    s.idx = L.idx[l];
    setGrid(l, child);
  };
  // The ordinary step of lane l: 0 when its walk ends (the closest hit at
  // or before the cell's exit), 1 when it moved to the next cell of its
  // grid, 2 when it leaves the grid.
  const auto stepLane = [&](int l) __attribute__((always_inline)) {
    const float t0 = L.tNext[0][l], t1 = L.tNext[1][l], t2 = L.tNext[2][l];
    const float t01 = t1 < t0 ? t1 : t0;
    const int axis = t2 < t01 ? 2 : (t1 < t0 ? 1 : 0);
    const float t = L.tNext[axis][l];
    L.tEnter[l] = t;
    if (L.hitT[l] <= t) return 0;
    const int c = L.cell[axis][l] + step[axis][l];
    if (static_cast<unsigned>(c) >= static_cast<unsigned>(L.res[axis][l])) return 2;
    L.cell[axis][l] = c;
    L.idx[l] += static_cast<std::uint32_t>(L.dIdx[axis][l]);
    L.tNext[axis][l] = PlaneT(GridPlane(*L.g[l], axis, step[axis][l] > 0 ? c + 1 : c), rays[l].org[axis],
                              rays[l].inv[axis]);
    return 1;
  };
  // Lane l leaves its grid: the walk goes on in the nearest ancestor it
  // does not leave; false when the lane's walk ends.
  const auto ascend = [&](int l) {
    for (;;) {
      if (L.sp[l] == 0) return false;
      const HGridSaved& s = L.stack[l][--L.sp[l]];
      setGrid(l, s.g);
      for (int a = 0; a < 3; ++a) {
        L.cell[a][l] = s.cell[a];
        L.tNext[a][l] = s.tNext[a];
      }
      L.idx[l] = s.idx;
      const int r = stepLane(l);
      if (r != 2) return r == 1;
    }
  };
  // The lanes of `bits` enter their cells (L.cell): the crossings of their
  // exit planes and the cell index, as the single walk's enterCell.
  const auto enterCells = [&](unsigned bits) __attribute__((always_inline)) {
    const vbool<N> m = vbool<N>::FromBits(bits);
    vint<N> c[3], res[3];
    for (int a = 0; a < 3; ++a) {
      c[a] = vint<N>::Load(reinterpret_cast<const std::uint32_t*>(L.cell[a]));
      res[a] = vint<N>::Load(reinterpret_cast<const std::uint32_t*>(L.res[a]));
      const vint<N> plane = c[a] + Select(P.invNeg[a], vint<N>(0), vint<N>(1));
      const vfloat<N> p = vfloat<N>::Load(L.bmin[a]) + ToFloat(plane) * vfloat<N>::Load(L.cs[a]);
      Select(m, PlaneTN<N>(p, P.org[a], P.inv[a]), vfloat<N>::Load(L.tNext[a])).Store(L.tNext[a]);
    }
    const vint<N> idx = c[0] + res[0] * (c[1] + res[1] * c[2]);
    Select(m, idx, vint<N>::Load(L.idx)).Store(L.idx);
  };
  // Grid_EnterAt for the lanes of `bits` at once, each in its grid at its
  // tEnter, then fix(bits) on the cells, then the lanes enter them.
  const auto enterAt = [&](unsigned bits, auto fix) __attribute__((always_inline)) {
    const vbool<N> m = vbool<N>::FromBits(bits);
    const vfloat<N> t = vfloat<N>::Load(L.tEnter);
    for (int a = 0; a < 3; ++a) {
      const vint<N> c = GridPacket_CellAt<N>(
          vfloat<N>::Load(L.bmin[a]), vfloat<N>::Load(L.cs[a]),
          vint<N>::Load(reinterpret_cast<const std::uint32_t*>(L.res[a])), P.org[a], P.dir[a], P.inv[a], P.invNeg[a], t, m);
      Select(m, c, vint<N>::Load(reinterpret_cast<const std::uint32_t*>(L.cell[a])))
          .Store(reinterpret_cast<std::uint32_t*>(L.cell[a]));
    }
    fix(bits);
    enterCells(bits);
  };
  // Every lane starts in the root (the lanes that do not enter it too, so
  // that the vector passes read defined values; they are never live).
  for (int l = 0; l < N; ++l) {
    const Ray& ray = rays[l];
    for (int a = 0; a < 3; ++a) {
      step[a][l] = ray.inv[a] < 0.0f ? -1 : 1;
      L.tNext[a][l] = 0.0f;
    }
    L.idx[l] = 0;
    reachPerT[l] =
        CR_HGRID_RAY_ERR * std::max(std::fabs(ray.dir[0]), std::max(std::fabs(ray.dir[1]), std::fabs(ray.dir[2])));
    L.sp[l] = 0;
    for (int k = 0; k < CR_HGRID_MAILBOX; ++k) L.mailbox[k][l] = CR_NO_HIT;
    L.tEnter[l] = tEnter0[l];
    setGrid(l, sc.hgridHeader);
    for (int a = 0; a < 3; ++a) L.cell[a][l] = int(cells[a][l]);
  }
  enterCells(live);
  H.t.Store(L.hitT);  // the lanes' hits' t also lane by lane (the scalar steps')
  unsigned prReady = 0;  // lanes whose prs[] is prepared
  const auto packRay = [&](int l) -> const PackRayOf<4, kHasMotion<kTypes>>& {
    if (!((prReady >> l) & 1u)) {
      PackRay_Init<4>(prs[l], rays[l]);
      if constexpr (kHasMotion<kTypes>) prs[l].time = rays[l].time;
      prs[l].anyHit = anyHit != 0;
      prReady |= 1u << l;
    }
    return prs[l];
  };
  // The walk of lane l alone, from its cell on, to its end: the single
  // walk's loop on the lane's state (for the last lanes of a packet, whose
  // vector passes would run mostly empty).
  const auto finishLane = [&](int l) {
    HGridWalkState w;
    int st3[3];
    w.g = L.g[l];
    w.cellStart = refs + L.first[l];
    for (int a = 0; a < 3; ++a) {
      w.cell[a] = L.cell[a][l];
      w.dIdx[a] = L.dIdx[a][l];
      w.res[a] = L.res[a][l];
      w.tNext[a] = L.tNext[a][l];
      st3[a] = step[a][l];
    }
    w.idx = L.idx[l];
    w.tEnter = L.tEnter[l];
    w.stack = L.stack[l];
    w.sp = L.sp[l];
    w.mailbox = &L.mailbox[0][l];
    w.mailboxStride = N;
    Hit hit = HitPacket_Lane<N>(H, l);
    HGridWalk_Run<kTypes, kFast, kStats>(sc, rays[l], packRay(l), st3, reachPerT[l], w, hit, anyHit, st);
    HitPacket_SetLane<N>(H, l, hit);
  };
  vint<N> stepV[3];
  for (int a = 0; a < 3; ++a) stepV[a] = Select(P.invNeg[a], vint<N>(-1), vint<N>(1));
  const vint<N> one(1), zero(0);
  while (live) {
    if (PopCount(live) <= kHGridFinishLanes) {
      for (unsigned rest = live; rest; rest &= rest - 1u) finishLane(LowestBit(rest));
      break;
    }
    if constexpr (kStats) st.nTS += PopCount(live);
    // The lanes' reference ranges, gathered at once (lanes not live read
    // the root's first offsets).
    const vbool<N> liveV = vbool<N>::FromBits(live);
    vint<N> beginV, endV;
    GatherPairs(refs, Select(liveV, vint<N>::Load(L.first) + vint<N>::Load(L.idx), vint<N>(int(sc.hgridHeader->first))),
                beginV, endV);
    alignas(32) std::uint32_t begins[N], ends[N];
    beginV.Store(begins);
    endV.Store(ends);
    const vbool<N> fullV = AndNot(liveV, beginV == endV);
    const unsigned full = fullV.Bits();
    unsigned steps = live;  // the lanes that take the ordinary step below
    unsigned leaving = 0;   // lanes that leave their grid by a jump
    unsigned childOnly = 0;  // child cells walked as empty cells (their child too fine for the ray)
    // Which full cells are child grids (their first item), read for all
    // lanes at once.
    const vint<N> head = Gather(refs, Select(fullV, beginV, zero));
    const unsigned childs = AndNot(fullV, And(head, vint<N>(int(CR_HGRID_CHILD))) == zero).Bits();
    // Child cells: where the child is precise enough for the lane, it tests
    // the cell's large references and then descends where it meets the
    // child's box (below); else it tests all the cell's references.
    unsigned tests = full & ~childs;
    unsigned descents = 0;  // lanes that test the large references, then meet the child's box
    const GridHeader* childOf[N];
    for (unsigned rest = childs; rest; rest &= rest - 1u) {
      const int l = LowestBit(rest);
      const unsigned bit = 1u << l;
      const std::uint32_t begin = begins[l];
      const GridHeader* child = sc.hgridNodes + (refs[begin] & ~CR_HGRID_CHILD);
      const std::uint32_t nAll = refs[begin + 1u];
      begins[l] = begin + 2u;
      const float tExit = std::min(L.tNext[0][l], std::min(L.tNext[1][l], L.tNext[2][l]));
      if (reachPerT[l] * tExit <= child->margin) {
        childOf[l] = child;
        descents |= bit;
        begins[l] += nAll;  // the large references
        if (begins[l] != ends[l]) tests |= bit;
        continue;
      }
      ends[l] = begins[l] + nAll;
      if (begins[l] == ends[l]) {  // no references of its own: an empty cell (below)
        childOnly |= bit;
        continue;
      }
      tests |= bit;
    }
    // One pass over each cell for the lanes that stand in it (the lanes of
    // a coherent packet often do): a primitive against the lanes that do not
    // have it in their mailboxes; lane by lane where one or two lanes stand
    // in a cell of four references or more (CellRefs_ByLane).
    if (tests) {
      const vint<N> bv = vint<N>::Load(begins), ev = vint<N>::Load(ends);
      unsigned done = 0;  // occlusion: lanes with an occluder
      for (unsigned pending = tests; pending;) {
        const int l0 = LowestBit(pending);
        vbool<N> m = vbool<N>::FromBits(tests) & (bv == vint<N>(int(begins[l0]))) & (ev == vint<N>(int(ends[l0])));
        pending &= ~m.Bits();
        if constexpr (kStats) st.nLeaves += PopCount(m.Bits());
        MailboxPacketRefs_Intersect<N, CR_HGRID_MAILBOX, kTypes, kFast, kStats>(
            sc, refs, begins[l0], ends[l0], L.mailbox, P, H, m, anyHit, done, st, packRay);
      }
      if (done) {
        live &= ~done;
        steps &= ~done;
        descents &= ~done;
      }
      H.t.Store(L.hitT);
    }
    // The descents: into the child where the lane meets its box before its
    // closest hit (HGrid_BoxEnter), from where it enters the box.
    if (descents) {
      unsigned enters = 0;
      for (unsigned rest = descents; rest; rest &= rest - 1u) {
        const int l = LowestBit(rest);
        float tBox;
        if (HGrid_BoxEnter<kFast>(*childOf[l], rays[l], L.tEnter[l], L.hitT[l], tBox)) {
          descend(l, childOf[l]);
          L.tEnter[l] = tBox;
          enters |= 1u << l;
        }
      }
      if (enters) {
        enterAt(enters, [](unsigned) {});
        steps &= ~enters;
      }
    }
    // Empty cells (and child cells without references of their own whose
    // child is too fine for the ray): HGrid_Distance and HGrid_Skip on all
    // of them at once; the statistics count every empty cell.
    const unsigned empties = (steps & ~full) | childOnly;
    if constexpr (kStats) {
      st.nLeaves += PopCount(empties);
      st.nEmptyLeaves += PopCount(empties);
    }
    if (empties) {
      const vbool<N> emptyV = vbool<N>::FromBits(empties);
      const vint<N> idxV = vint<N>::Load(L.idx);
      const vint<N> word = Gather(refs, Select(emptyV, vint<N>::Load(L.dist) + ShiftRight(idxV, vint<N>(2)), zero));
      const vint<N> d = And(ShiftRight(word, And(idxV, vint<N>(3)) * vint<N>(8)), vint<N>(0xff));
      const vbool<N> far = emptyV & (d > vint<N>(CR_HGRID_SKIP_MIN - 1));
      if (Any(far)) {
        // HGrid_SkipExit on each lane: the box's exit over the three axes,
        // x before y before z on ties (strict <).
        vint<N> c[3], res[3];
        vfloat<N> best(std::numeric_limits<float>::infinity());
        vint<N> axisV = zero, lastV = zero, stepA = zero, resA = zero;
        const vint<N> dm1 = d - one;
        for (int a = 0; a < 3; ++a) {
          c[a] = vint<N>::Load(reinterpret_cast<const std::uint32_t*>(L.cell[a]));
          res[a] = vint<N>::Load(reinterpret_cast<const std::uint32_t*>(L.res[a]));
          const vint<N> hi = c[a] + dm1, top = res[a] - one, lo = c[a] - dm1;
          const vint<N> b = Select(P.invNeg[a], Select(lo > zero, lo, zero), Select(hi < top, hi, top));
          const vint<N> plane = b + Select(P.invNeg[a], zero, one);
          const vfloat<N> ta =
              PlaneTN<N>(vfloat<N>::Load(L.bmin[a]) + ToFloat(plane) * vfloat<N>::Load(L.cs[a]), P.org[a], P.inv[a]);
          const vbool<N> take = ta < best;
          best = Select(take, ta, best);
          axisV = Select(take, vint<N>(a), axisV);
          lastV = Select(take, b, lastV);
          stepA = Select(take, stepV[a], stepA);
          resA = Select(take, res[a], resA);
        }
        const vfloat<N> tEnterV = vfloat<N>::Load(L.tEnter);
        const vbool<N> go = far & (best > tEnterV);  // else the ordinary step
        if (Any(go)) {
          Select(go, best, tEnterV).Store(L.tEnter);
          const vbool<N> stop = go & (H.t <= best);
          const vint<N> next = lastV + stepA;
          const vbool<N> inside = LessUnsigned(next, resA);
          const vbool<N> moved = AndNot(go & inside, stop);
          steps &= ~go.Bits();
          live &= ~stop.Bits();
          leaving |= AndNot(AndNot(go, inside), stop).Bits();
          // The cell across the box's exit plane, at its parameter
          // (Grid_EnterAt's on the other two axes).
          if (Any(moved))
            enterAt(moved.Bits(), [&](unsigned) {
              for (int a = 0; a < 3; ++a) {
                const vbool<N> on = moved & (axisV == vint<N>(a));
                const vint<N> ca = vint<N>::Load(reinterpret_cast<const std::uint32_t*>(L.cell[a]));
                Select(on, next, ca).Store(reinterpret_cast<std::uint32_t*>(L.cell[a]));
              }
            });
        }
      }
    }
    // The ordinary step, on the lanes that take it at once.
    if (steps) {
      const vbool<N> m = vbool<N>::FromBits(steps);
      vfloat<N> tn[3];
      vint<N> c[3];
      for (int a = 0; a < 3; ++a) {
        tn[a] = vfloat<N>::Load(L.tNext[a]);
        c[a] = vint<N>::Load(reinterpret_cast<const std::uint32_t*>(L.cell[a]));
      }
      vbool<N> s[3];
      s[2] = (tn[2] < tn[0]) & (tn[2] < tn[1]);
      s[1] = AndNot(tn[1] < tn[0], s[2]);
      s[0] = !(s[1] | s[2]);
      const vfloat<N> tE = Select(s[2], tn[2], Select(s[1], tn[1], tn[0]));
      const vbool<N> ended = m & (H.t <= tE);
      vbool<N> out = ended;  // stays out of range: lanes that end do not move
      vint<N> nc[3];
      for (int a = 0; a < 3; ++a) {
        nc[a] = c[a] + MaskedOrZero(s[a], stepV[a]);
        const vint<N> res = vint<N>::Load(reinterpret_cast<const std::uint32_t*>(L.res[a]));
        out = out | (s[a] & !LessUnsigned(nc[a], res));
      }
      const vbool<N> move = AndNot(m, out);
      vint<N> idx = vint<N>::Load(L.idx);
      for (int a = 0; a < 3; ++a) {
        const vbool<N> ma = move & s[a];
        const vint<N> dIdx = vint<N>::Load(reinterpret_cast<const std::uint32_t*>(L.dIdx[a]));
        idx = idx + MaskedOrZero(ma, dIdx);
        const vint<N> plane = nc[a] + Select(P.invNeg[a], zero, one);
        const vfloat<N> p = vfloat<N>::Load(L.bmin[a]) + ToFloat(plane) * vfloat<N>::Load(L.cs[a]);
        Select(ma, PlaneTN<N>(p, P.org[a], P.inv[a]), tn[a]).Store(L.tNext[a]);
        Select(ma, nc[a], c[a]).Store(reinterpret_cast<std::uint32_t*>(L.cell[a]));
      }
      idx.Store(L.idx);
      Select(m, tE, vfloat<N>::Load(L.tEnter)).Store(L.tEnter);
      live &= ~ended.Bits();
      leaving |= AndNot(AndNot(m, ended), move).Bits();
    }
    for (unsigned rest = leaving; rest; rest &= rest - 1u) {
      const int l = LowestBit(rest);
      if (!ascend(l)) live &= ~(1u << l);
    }
  }
}

// Traces positions [job.begin, job.end) in packets of N.
template <int N, unsigned kTypes, bool kFast, bool kStats>
void HGridPacket_TraceRange(const KernelScene& sc, const KernelJob& job)
{
  TraceStatsSum st;
  GridEntry_Packets<N, kFast, kHasMotion<kTypes>, true>(
      sc, *sc.hgridHeader, job,
      [&](const RayPacket<N>& P, HitPacket<N>& H, const Ray* rays, unsigned in, const std::uint32_t (&cells)[3][N],
          const float* tEnter) {
        HGridPacket_Walk<N, kTypes, kFast, kStats>(sc, P, H, rays, in, cells, tEnter, job.occlusion, st);
      });
  if constexpr (kStats) AddJobStats(job.stats, st, job.end - job.begin);
}

}  // namespace cr::simd::CR_SIMD_NS
