/* Grid packet traversal (OpenCL only): the work-group's lanes walk the grid
 * together, each with its own 3D-DDA state (kernels/grid.h: Grid_Enter,
 * Grid_Next), in a loop whose trip count is the same for every lane.
 *
 * Each iteration has two steps. In the first, every active lane that has a
 * reference left in its current cell tests it (one primitive test per lane:
 * straight-line code that PoCL vectorises across the lanes). In the second,
 * every active lane whose cell is exhausted walks on (Grid_Next) to the
 * next cell that holds references, or ends its walk; each lane still active
 * sets the flag that runs the next iteration. The group stops when no lane
 * is active. So the lanes stay busy with primitive tests whatever the
 * cells they are in: the loop runs about as long as the packet's longest
 * list of tests (Aila & Laine 2009's "if-if" rather than "while-while").
 *
 * (Also written and measured: one iteration per cell, the group looping
 * over the most references any lane's cell holds, reduced by lane 0. Lanes
 * soon sit in cells of different sizes, so many tests of that loop are
 * masked off, and it takes a barrier per test and two per cell; on PoCL the
 * two ran equally fast (balls, gears, 256x256 primary rays), both well
 * behind the per-ray kernel: docs/OPENCL.md.)
 *
 * Each lane visits exactly the cells Grid_Trace visits and tests exactly its
 * references, in the same order: the same answers and the same counters as
 * the per-ray kernel (Hit_Closer would make the order irrelevant anyway). */
#ifndef CELLRAY_KERNELS_GRID_PACKET_CL
#define CELLRAY_KERNELS_GRID_PACKET_CL
#include "grid.h"
#include "packet.cl"
#if CR_WITH_GRID

/* Local words of sState that the grid packet uses: the "some lane is
 * active" flags of two consecutive iterations. */
#define CR_GRID_PACKET_STATE 2

/* Enters the cell `cell` (a lane's walk) and walks on past empty cells, as
 * Grid_Trace does (counting each visit); publishes the lane's cell (sCell,
 * three ints per lane, SoA), its reference range (sRange: next reference,
 * then end, SoA) and whether the walk goes on (sLane). */
CR_FUNC void GridPacket_Enter(CR_GLOBAL const GridHeader* grid, CR_GLOBAL const uint* cellStart, const Ray* ray,
                              real hitT, __local int* sCell, __local uint* sRange, __local uint* sLane, uint lid,
                              uint nLanes, int cell[3], int active, TraceStats* st)
{
  uint begin = 0u, end = 0u;
  while (active) {
    const uint idx = Grid_CellIndex(grid, cell);
    begin = cellStart[idx];
    end = cellStart[idx + 1u];
    CR_COUNT(st, nTS);
    CR_COUNT(st, nLeaves);
    if (begin != end) break;
    CR_COUNT(st, nEmptyLeaves);
    active = Grid_Next(grid, ray, hitT, cell);
  }
  CR_UNROLL for (uint a = 0; a < 3u; ++a) sCell[a * nLanes + lid] = cell[a];
  sRange[lid] = begin;
  sRange[nLanes + lid] = active ? end : begin;
  sLane[lid] = (uint)active;
}

/* Closest or any hit of each lane's ray, already stored in sRay, sAxes, sHit,
 * sHitG (packet.cl); `live` is 0 for a lane without a ray. Local memory:
 * sLane, sCell and sRange as above, sState CR_GRID_PACKET_STATE words. Every
 * work-item of the group must call it (it contains barriers). */
CR_FUNC void GridPacket_Trace(CR_GLOBAL const GridHeader* grid, CR_GLOBAL const uint* cellStart,
                              CR_GLOBAL const uint* refs, const PrimView* pv, int anyHit, TraceStats* st, int live,
                              uint lid, uint nLanes, __local uint* sLane, __local uint* sState, __local int* sCell,
                              __local uint* sRange, __local real* sRay, __local uint* sAxes, __local real* sHit,
                              __local uint* sHitG)
{
  if (lid == 0) {
    sState[0] = 0u;
    sState[1] = 0u;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  {
    Ray ray;
    Packet_LoadRay(sRay, sAxes, lid, nLanes, &ray);
    int cell[3] = {0, 0, 0};
    const int active = live && grid->nRefs != 0u && Grid_Enter(grid, &ray, sHit[lid], cell);
    GridPacket_Enter(grid, cellStart, &ray, sHit[lid], sCell, sRange, sLane, lid, nLanes, cell, active, st);
    /* So that no iteration runs (and no reference is read) when no lane
     * has a reference to test: the grid may have none. */
    if (active) atomic_or(sState, 1u);
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  /* Iteration i runs when flag i & 1 is set; its second step sets flag
   * (i + 1) & 1 (any active lane) and clears flag i & 1, which every lane
   * read before the barrier between the steps. */
  for (uint i = 0;; ++i) {
    if (sState[i & 1u] == 0u) break;
    /* Step 1: the next reference of every lane that has one. A lane without
     * tests reference 0 and keeps nothing: every lane runs the same code. */
    {
      const uint next = sRange[lid];
      const int want = (int)sLane[lid] & (next < sRange[nLanes + lid] ? 1 : 0);
      const int took = Packet_TestStep(pv, refs[want ? next : 0u], want, sRay, sAxes, sHit, sHitG, lid, nLanes);
      sRange[lid] = next + (uint)want;
      sLane[lid] = sLane[lid] & (uint)!(took & anyHit);
#ifdef CR_STATS
      st->nIT += (uint)want;
#endif
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    /* Step 2: lanes whose cell is exhausted walk on. */
    {
      int active = (int)sLane[lid];
      if (active && sRange[lid] == sRange[nLanes + lid]) {
        Ray ray;
        Packet_LoadRay(sRay, sAxes, lid, nLanes, &ray);
        int cell[3];
        CR_UNROLL for (uint a = 0; a < 3u; ++a) cell[a] = sCell[a * nLanes + lid];
        const real hitT = sHit[lid];
        active = Grid_Next(grid, &ray, hitT, cell);
        GridPacket_Enter(grid, cellStart, &ray, hitT, sCell, sRange, sLane, lid, nLanes, cell, active, st);
      }
      if (active) atomic_or(sState + ((i + 1u) & 1u), 1u);
      if (lid == 0) sState[i & 1u] = 0u;
    }
    barrier(CLK_LOCAL_MEM_FENCE);
  }
}

/* For the dispatch trace.cl generates from CR_ACCEL_TYPES (Trace_Packet):
 * this traversal's local memory (its pieces: X(type, name, count), carved
 * from the kernel's pool; trace.cl passes them on as parameters of the
 * same names) and its call (the names are Trace_Packet's). */
#define CR_PACKET_LOCALS_GRID(X) X(int, sGridCell, 3 * CR_PACKET_SIZE) X(uint, sGridRange, 2 * CR_PACKET_SIZE)
#define CR_PACKET_CALL_GRID(hdr, nodes, refs)                                                                     \
  GridPacket_Trace(hdr, nodes, refs, pv, anyHit, st, live, lid, CR_PACKET_SIZE, sLane, sState, sGridCell, sGridRange, \
                   sRay, sAxes, sHit, sHitG)

#endif /* CR_WITH_GRID */
#endif /* CELLRAY_KERNELS_GRID_PACKET_CL */
