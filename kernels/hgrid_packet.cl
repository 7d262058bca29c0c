/* Hierarchical grid, packet variant (OpenCL only): each lane walks its own
 * ray through the levels (kernels/hgrid.h HGrid_Trace), with no pass shared
 * between lanes: the same answers and counters as the per-ray kernel. A
 * cooperative walk in the manner of kernels/grid_packet.cl (lanes kept busy
 * with primitive tests whatever their cells) is left for later; until then
 * the per-ray variant is the one to measure. */
#ifndef CELLRAY_KERNELS_HGRID_PACKET_CL
#define CELLRAY_KERNELS_HGRID_PACKET_CL
#include "hgrid.h"
#include "packet.cl"
#if CR_WITH_HGRID

/* For the dispatch trace.cl generates from CR_ACCEL_TYPES (Trace_Packet):
 * no local memory of its own; the call runs on Trace_Packet's ray and hit
 * and hands the hit back through the lane's slot. */
#define CR_PACKET_LOCALS_HGRID(X)
#define CR_PACKET_CALL_HGRID(hdr, nodes, refs)                 \
  if (live) {                                                  \
    ray.anyHit = anyHit;                                       \
    HGrid_Trace(hdr, nodes, refs, pv, &ray, &hit, anyHit, st); \
    Packet_StoreHit(sHit, sHitG, lid, CR_PACKET_SIZE, &hit);   \
  }

#endif /* CR_WITH_HGRID */
#endif /* CELLRAY_KERNELS_HGRID_PACKET_CL */
