/* Two-level grid, packet variant (OpenCL only): each lane walks its own ray
 * through both levels (kernels/grid2.h Grid2_Trace), with no pass shared
 * between lanes: the same answers and counters as the per-ray kernel. A
 * cooperative walk in the manner of kernels/grid_packet.cl (lanes kept busy
 * with primitive tests whatever their cells) is left for later; until then
 * the per-ray variant is the one to measure. */
#ifndef CELLRAY_KERNELS_GRID2_PACKET_CL
#define CELLRAY_KERNELS_GRID2_PACKET_CL
#include "grid2.h"
#include "packet.cl"
#if CR_WITH_GRID2

/* For the dispatch trace.cl generates from CR_ACCEL_TYPES (Trace_Packet):
 * no local memory of its own; the call runs on Trace_Packet's ray and hit
 * and hands the hit back through the lane's slot. */
#define CR_PACKET_LOCALS_GRID2
#define CR_PACKET_PARAMS_GRID2
#define CR_PACKET_ARGS_GRID2
#define CR_PACKET_CALL_GRID2(hdr, nodes, refs)                 \
  if (live) {                                                  \
    ray.anyHit = anyHit;                                       \
    Grid2_Trace(hdr, nodes, refs, pv, &ray, &hit, anyHit, st); \
    Packet_StoreHit(sHit, sHitG, lid, CR_PACKET_SIZE, &hit);   \
  }

#endif /* CR_WITH_GRID2 */
#endif /* CELLRAY_KERNELS_GRID2_PACKET_CL */
