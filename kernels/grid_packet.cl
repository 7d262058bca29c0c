/* Grid packet traversal (OpenCL only): the work-group's lanes walk the grid
 * together, each with its own 3D-DDA state (kernels/grid.h: Grid_Enter,
 * Grid_Next), in a loop whose trip count is the same for every lane.
 *
 * One iteration visits one cell per active lane: lane 0 reduces the lanes'
 * states in local memory (how many are active, the most references any
 * lane's cell holds); the group then loops over that many reference slots,
 * one barrier each, and lane l tests slot k of its own cell while k is below
 * its count; then every active lane steps to its next cell (Grid_Next) and
 * publishes it. A lane is done when its walk ends (a hit at or before the
 * cell's exit, or the grid's far face) or, for any-hit, at its first hit;
 * the group is done when no lane is active. All loop conditions are read
 * from local memory, so every work-item takes the same path, and each step
 * between two barriers is straight-line code per lane (PoCL can vectorise
 * the work-item loops around such steps; a per-lane loop over a cell's
 * references could not be).
 *
 * Each lane visits exactly the cells Grid_Trace visits and tests exactly its
 * references, in the same order: the same answers and the same counters as
 * the per-ray kernel (Hit_Closer would make the order irrelevant anyway).
 * The price is idle lanes: an iteration costs the longest cell of the
 * packet, and the loop runs as long as the longest walk. */
#ifndef CELLRAY_KERNELS_GRID_PACKET_CL
#define CELLRAY_KERNELS_GRID_PACKET_CL
#include "grid.h"
#include "packet.cl"

/* Local words of sState that the grid packet uses. */
#define CR_GRID_PACKET_STATE 2

/* Publishes a lane's walk: its cell (sCell, three ints per lane, SoA), the
 * cell's reference range (sRange: begin, then count, SoA; count 0 for a lane
 * that is done) and whether it is active (sLane). Counts the visit. */
CR_FUNC void GridPacket_StoreLane(CR_GLOBAL const GridHeader* grid, CR_GLOBAL const uint* cellStart,
                                  __local int* sCell, __local uint* sRange, __local uint* sLane, uint lid,
                                  uint nLanes, const int cell[3], int active, TraceStats* st)
{
  const uint idx = active ? Grid_CellIndex(grid, cell) : 0u;
  const uint begin = cellStart[idx];
  const uint end = cellStart[idx + 1u];
  CR_UNROLL for (uint a = 0; a < 3u; ++a) sCell[a * nLanes + lid] = cell[a];
  sRange[lid] = begin;
  sRange[nLanes + lid] = active ? end - begin : 0u;
  sLane[lid] = (uint)active;
#ifdef CR_STATS
  st->nTS += (uint)active;
  st->nLeaves += (uint)active;
  st->nEmptyLeaves += (uint)active & (begin == end ? 1u : 0u);
#endif
}

/* Closest or any hit of each lane's ray, already stored in sRay, sAxes, sHit,
 * sHitG (packet.cl); `live` is 0 for a lane without a ray. Local memory:
 * sLane and sRange as above, sCell three ints per lane, sState
 * CR_GRID_PACKET_STATE words (active lanes, most references). Every
 * work-item of the group must call it (it contains barriers). */
CR_FUNC void GridPacket_Trace(CR_GLOBAL const GridHeader* grid, CR_GLOBAL const uint* cellStart,
                              CR_GLOBAL const uint* refs, const PrimView* pv, int anyHit, TraceStats* st, int live,
                              uint lid, uint nLanes, __local uint* sLane, __local uint* sState, __local int* sCell,
                              __local uint* sRange, __local real* sRay, __local uint* sAxes, __local real* sHit,
                              __local uint* sHitG)
{
  {
    Ray ray;
    Packet_LoadRay(sRay, sAxes, lid, nLanes, &ray);
    int cell[3] = {0, 0, 0};
    const int active = live && grid->nRefs != 0u && Grid_Enter(grid, &ray, sHit[lid], cell);
    GridPacket_StoreLane(grid, cellStart, sCell, sRange, sLane, lid, nLanes, cell, active, st);
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  for (;;) {
    if (lid == 0) {
      uint nActive = 0, most = 0;
      for (uint k = 0; k < nLanes; ++k) {
        nActive += sLane[k];
        most = max(most, sRange[nLanes + k]);
      }
      sState[0] = nActive;
      sState[1] = most;
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    if (sState[0] == 0u) break;
    /* Reference slot k of every lane's cell, one barrier each. A lane past
     * its count (or done) tests reference 0 and keeps nothing: every lane
     * runs the same code. */
    for (uint k = 0; k < sState[1]; ++k) {
      {
        const int want = (int)sLane[lid] & (k < sRange[nLanes + lid] ? 1 : 0);
        const uint g = refs[want ? sRange[lid] + k : 0u];
        Ray ray;
        Hit hit;
        Packet_LoadRay(sRay, sAxes, lid, nLanes, &ray);
        Packet_LoadHit(sHit, sHitG, lid, nLanes, &hit);
        real t, u, v;
        const int found = Packet_PrimTest(pv, g, &ray, &hit, &t, &u, &v);
        const int took = Packet_Commit(&hit, want & found, t, u, v, g);
        Packet_StoreHit(sHit, sHitG, lid, nLanes, &hit);
        sLane[lid] = sLane[lid] & (uint)!(took & anyHit);
#ifdef CR_STATS
        st->nIT += (uint)want;
#endif
      }
      barrier(CLK_LOCAL_MEM_FENCE);
    }
    /* Every active lane steps to its next cell. */
    {
      Ray ray;
      Packet_LoadRay(sRay, sAxes, lid, nLanes, &ray);
      int cell[3];
      CR_UNROLL for (uint a = 0; a < 3u; ++a) cell[a] = sCell[a * nLanes + lid];
      const int active = (int)sLane[lid] && Grid_Next(grid, &ray, sHit[lid], cell);
      GridPacket_StoreLane(grid, cellStart, sCell, sRange, sLane, lid, nLanes, cell, active, st);
    }
    barrier(CLK_LOCAL_MEM_FENCE);
  }
}

#endif /* CELLRAY_KERNELS_GRID_PACKET_CL */
