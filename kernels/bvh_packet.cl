/* BVH packet traversal (OpenCL only): the work-group walks the tree together
 * with uniform control flow, after the shared-stack packet traversals of
 * Garanzha & Loop ("Fast ray sorting and breadth-first packet traversal for
 * GPU ray tracing", 2010) and Aila & Laine 2009 (sec. 3, "packet traversal").
 *
 * Every iteration visits one node for the whole group: each live lane tests
 * the node's box against its own ray and current hit. The lanes' verdicts go
 * to local memory; after a barrier one lane reduces them and updates the
 * shared stack: at an interior node that some lane entered, descend to the
 * child that most lanes reach first and push the other; otherwise pop. At a
 * leaf that some lane entered, the group loops over its primitives and each
 * lane that entered keeps a closer hit (the trip count is the leaf's, the
 * same for all lanes). The next node and the loop conditions come from local
 * memory, so all work-items take the same path (PoCL vectorises the
 * work-item loops of such regions; per-lane early exits would not).
 *
 * The answer is the per-ray one: every box test is conservative and per
 * lane, and Hit_Closer makes the closest hit independent of the order. An
 * any-hit query may report a different occluder than BVH_Trace. */
#ifndef CELLRAY_KERNELS_BVH_PACKET_CL
#define CELLRAY_KERNELS_BVH_PACKET_CL
#include "bvh.h"
#include "packet.cl"
#if CR_WITH_BVH

#define CR_PACKET_END 0xFFFFFFFFu

/* The node the group visits next, as lane 0 publishes it in local memory
 * (CR_PACKET_NODE_FIELDS floats): its box, whether it is interior, and for
 * an interior node the axis that separates its children's centres most as a
 * signed unit weight per axis (sign: the second child's side). Every lane
 * then reads the same local words (loaded once per vector of lanes, rather
 * than gathered per lane from global memory). */
#define CR_PACKET_NODE_FIELDS 10

CR_FUNC void BVHPacket_PublishNode(CR_GLOBAL const BVHNode* nodes, uint ni, __local float* sNode)
{
  CR_GLOBAL const BVHNode* n = nodes + ni;
  CR_UNROLL for (int k = 0; k < 3; ++k) {
    sNode[k] = n->bmin[k];
    sNode[3 + k] = n->bmax[k];
    sNode[6 + k] = 0.0f;
  }
  sNode[9] = n->count == 0 ? 1.0f : 0.0f;
  if (n->count == 0) {
    CR_GLOBAL const BVHNode* a = nodes + n->first;
    CR_GLOBAL const BVHNode* b = a + 1;
    float best = -1.0f, sep = 0.0f;
    int axis = 0;
    for (int k = 0; k < 3; ++k) {
      const float d = (b->bmin[k] + b->bmax[k]) - (a->bmin[k] + a->bmax[k]);
      if (fabs(d) > best) {
        best = fabs(d);
        sep = d;
        axis = k;
      }
    }
    sNode[6 + axis] = sep > 0.0f ? 1.0f : -1.0f;
  }
}

/* Box_Slabs (intersect.h) of a box in local memory (min corner, then max). */
CR_FUNC int BVHPacket_Box(__local const float* box, const Ray* r, real tmin, real tmax)
{
  real lo[3], hi[3], tEnter;
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    lo[a] = (real)box[a];
    hi[a] = (real)box[3 + a];
  }
  return Box_Slabs(lo, hi, r, tmin, tmax, &tEnter);
}

/* Closest or any hit of each lane's ray, already stored in sRay, sAxes, sHit,
 * sHitG with Packet_StoreRay / Packet_StoreHit (packet.cl; read the answer
 * back with Packet_LoadHit after it returns); `live` is 0 for a lane without a
 * ray. Local memory: sStack CR_BVH_STACK node indices, sLane one word per
 * lane (the lanes' verdicts), sState four words (next node, stack size,
 * leaf range), sNode the node under test. None may be restrict: values pass between
 * work-items across barriers, and a compiler may keep a restrict-qualified
 * value across a call it does not give the pointer to (the barrier).
 * Every work-item of the group must call it (it contains barriers).
 *
 * Each step between two barriers is straight-line code per lane (a box test;
 * one primitive test; the reduction, by lane 0), so that the work-item loop
 * PoCL builds around it has no inner loop and no branch on a lane's data,
 * and can be vectorised: the loops over a leaf's primitives are group-level
 * loops with barriers in their body, every lane computes every test and
 * keeps the result only where it wants it, and the node all lanes test is
 * in local memory at a fixed address, loaded once per vector of lanes
 * rather than gathered per lane from global memory.
 *
 * (Tried and dropped on PoCL 3.1: the primitive copied to local memory the
 * same way costs one more barrier per primitive and measured no faster;
 * separate loops per primitive type, each with barriers, produced wrong
 * answers, hence one loop with a branch on the type, uniform in practice.) */
CR_FUNC void BVHPacket_Trace(CR_GLOBAL const BVHNode* nodes, CR_GLOBAL const uint* refs, const PrimView* pv,
                             int anyHit, TraceStats* st, int live, uint lid, uint nLanes,
                             __local uint* sStack, __local uint* sLane, __local uint* sState,
                             __local float* sNode, __local real* sRay,
                             __local uint* sAxes, __local real* sHit,
                             __local uint* sHitG)
{
  if (lid == 0) {
    sState[0] = 0;
    sState[1] = 0;
    BVHPacket_PublishNode(nodes, 0, sNode);
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  for (;;) {
    const uint ni = sState[0];
    if (ni == CR_PACKET_END) break;
    /* Step 1, every lane: the node's box against the lane's ray, and the
     * lane's vote on the order of the children. */
    const uint interior = sNode[9] != 0.0f ? 1u : 0u;
    int in;
    uint vote;
    {
      Ray ray;
      Packet_LoadRay(sRay, sAxes, lid, nLanes, &ray);
      in = live & BVHPacket_Box(sNode, &ray, ray.tmin, Cull_Distance(sHit[lid]));
      const real w = (real)sNode[6] * ray.dir[0] + (real)sNode[7] * ray.dir[1] + (real)sNode[8] * ray.dir[2];
      vote = (w < (real)0.0f ? 1u : 0u) & (uint)in & interior;
    }
#ifdef CR_STATS
    st->nTS += (uint)in;
    st->nLeaves += (uint)in & (1u - interior);
#endif
    sLane[lid] = (uint)in | (vote << 1) | ((uint)live << 2);
    barrier(CLK_LOCAL_MEM_FENCE);
    /* Step 2, lane 0: reduce the verdicts, pick and publish the next node,
     * publish the leaf's references to test if any lane entered it. */
    if (lid == 0) {
      uint nIn = 0, nVote = 0, nLive = 0;
      CR_ROLLED for (uint k = 0; k < nLanes; ++k) {
        const uint f = sLane[k];
        nIn += f & 1u;
        nVote += (f >> 1) & 1u;
        nLive += (f >> 2) & 1u;
      }
      CR_GLOBAL const BVHNode* n = nodes + ni;
      uint sp = sState[1];
      uint next = CR_PACKET_END;
      uint nPrims = 0;
      if (nLive > 0) {
        if (nIn > 0 && interior) {
          const uint nearer = 2 * nVote > nIn ? n->first + 1 : n->first;
          sStack[sp++] = nearer == n->first ? n->first + 1 : n->first;
          next = nearer;
        } else {
          if (nIn > 0) nPrims = n->count;
          if (sp > 0) next = sStack[--sp];
        }
      }
      sState[0] = next;
      sState[1] = sp;
      if (next != CR_PACKET_END) BVHPacket_PublishNode(nodes, next, sNode);
      sState[2] = n->first;
      sState[3] = nPrims;
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    /* Step 3, once per primitive of the leaf (one barrier each). */
    const int want = in & live;
    for (uint k = 0; k < sState[3]; ++k) {
      {
        const int took = Packet_TestStep(pv, refs[sState[2] + k], want, sRay, sAxes, sHit, sHitG, lid, nLanes);
        live = live & !(took & anyHit);
      }
#ifdef CR_STATS
      st->nIT += (uint)want;
#endif
      barrier(CLK_LOCAL_MEM_FENCE);
    }
  }
}

/* For the dispatch trace.cl generates from CR_ACCEL_TYPES (Trace_Packet):
 * this traversal's local memory (its pieces: X(type, name, count), carved
 * from the kernel's pool; trace.cl passes them on as parameters of the
 * same names) and its call (the names are Trace_Packet's). */
#define CR_PACKET_LOCALS_BVH(X) X(uint, sBvhStack, CR_BVH_STACK) X(float, sBvhNode, CR_PACKET_NODE_FIELDS)
#define CR_PACKET_CALL_BVH(hdr, nodes, refs)                                                                    \
  BVHPacket_Trace(nodes, refs, pv, anyHit, st, live, lid, CR_PACKET_SIZE, sBvhStack, sLane, sState, sBvhNode, sRay, \
                  sAxes, sHit, sHitG)

#endif /* CR_WITH_BVH */
#endif /* CELLRAY_KERNELS_BVH_PACKET_CL */
