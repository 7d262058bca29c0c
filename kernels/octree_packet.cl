/* Octree packet traversal (OpenCL only): the work-group walks the octree
 * together with a shared stack of nodes, like the BVH packet
 * (kernels/bvh_packet.cl; Garanzha & Loop 2010, Aila & Laine 2009), with
 * the per-lane cell parameters of Revelles et al. (kernels/octree.h).
 *
 * Every iteration visits one node for the whole group. Each live lane
 * computes the node's mirrored plane parameters t0, tm, t1 for its own ray
 * (Octree_CellT: the same planes, to the bit, as Octree_Trace), hence its
 * interval of the node's cell and of each of the eight children, and votes
 * for the non-empty children whose interval meets [tmin, hit t]. Lane 0 ORs
 * the votes and pushes the children some lane entered, far to near in the
 * mirrored order of the majority of the lanes' direction signs (for a lane
 * with those signs this is its own front-to-back order: Revelles' child
 * sequence only ever sets bits of the mirrored octant), then pops the next
 * node. At a leaf that some lane entered, the group loops over its
 * references (one barrier each) and every lane that entered keeps a closer
 * hit.
 *
 * The answer is the per-ray one: a lane skips a cell only when its interval
 * misses [tmin, hit t], and any closer hit would lie in a cell that the ray
 * enters before that hit (the builder puts a primitive in every cell its
 * shape meets), so the closest hit under Hit_Closer is found whatever the
 * order; the order only decides how soon hit t shrinks. An any-hit query
 * may report a different occluder than Octree_Trace. Counters (CR_STATS):
 * nTS nodes whose cell the lane entered, nLeaves leaves among them, nIT
 * primitive tests; empty octants are not visited (nEmptyLeaves stays 0).
 * With the mailbox (--octree-mailbox on) each lane skips a reference it has
 * tested in an earlier leaf (exact, as in Octree_Trace). With the ray's
 * margins (--octree-margin ray) each lane's intervals are widened by its own
 * rounding (Octree_Lo, Octree_Hi), as in Octree_TraceRay. */
#ifndef CELLRAY_KERNELS_OCTREE_PACKET_CL
#define CELLRAY_KERNELS_OCTREE_PACKET_CL
#include "octree.h"
#include "packet.cl"
#if CR_WITH_OCTREE

/* Stack entries: a node pushes at most its eight children and the visit
 * pops one, so each interior level below the root adds at most seven. */
#define CR_OCTREE_PACKET_STACK (7 * CR_OCTREE_MAX_DEPTH + 8)
/* Words per stack entry: node index, level, cell coordinates x, y, z. */
#define CR_OCTREE_PACKET_ENTRY 5
/* Local words of sState: the node under visit (the five words of an entry),
 * stack size, its childMask, and the range of the leaf to test. */
#define CR_OCTREE_PACKET_STATE 10
#define CR_OCTREE_PACKET_END 0xFFFFFFFFu

/* With the ray's margins (--octree-margin ray, CR_OCTREE_MARGIN_BUILD) each
 * lane widens its intervals as Octree_TraceRay does; this walk already
 * visits every child whose interval meets the lane's, in any order. */
#if CR_OCTREE_MARGIN_BUILD
#define CR_OCTREE_PACKET_LO(t) Octree_Lo(t)
#define CR_OCTREE_PACKET_HI(t) Octree_Hi(t)
#else
#define CR_OCTREE_PACKET_LO(t) (t)
#define CR_OCTREE_PACKET_HI(t) (t)
#endif

/* The node's planes as lane 0 publishes them (sPlane): low, high and mid
 * plane of each axis, CR_OCTREE_PACKET_PLANE_STRIDE floats apart. Computed
 * once per node rather than per lane, and kept apart in local memory: read
 * from neighbouring words, the lanes' three alike per-axis computations
 * were packed into 2-wide vectors by the compiler, which kept PoCL from
 * vectorising the step across the lanes. */
#define CR_OCTREE_PACKET_PLANE_STRIDE 4
#define CR_OCTREE_PACKET_PLANES (9 * CR_OCTREE_PACKET_PLANE_STRIDE)
#define CR_OCTREE_PACKET_PLANE(a, k) (((a) * 3 + (k)) * CR_OCTREE_PACKET_PLANE_STRIDE)

/* Lane 0: pops the top entry into sState[0..4] and publishes its childMask
 * and planes, or publishes the end. */
CR_FUNC void OctreePacket_Pop(CR_GLOBAL const OctreeHeader* hdr, CR_GLOBAL const OctreeNode* nodes,
                              __local uint* sStack, __local uint* sState, __local float* sPlane, uint sp)
{
  if (sp == 0u) {
    sState[0] = CR_OCTREE_PACKET_END;
    sState[5] = 0u;
    return;
  }
  --sp;
  CR_UNROLL for (int w = 0; w < CR_OCTREE_PACKET_ENTRY; ++w)
    sState[w] = sStack[sp * CR_OCTREE_PACKET_ENTRY + (uint)w];
  sState[5] = sp;
  sState[6] = nodes[sState[0]].childMask;
  const uint level = sState[1];
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    const uint c = sState[2 + a];
    sPlane[CR_OCTREE_PACKET_PLANE(a, 0)] = Octree_Plane(hdr, a, level, c);
    sPlane[CR_OCTREE_PACKET_PLANE(a, 1)] = Octree_Plane(hdr, a, level, c + 1u);
    sPlane[CR_OCTREE_PACKET_PLANE(a, 2)] = Octree_Plane(hdr, a, level + 1u, 2u * c + 1u);
  }
}

/* Closest or any hit of each lane's ray, already stored in sRay, sAxes, sHit,
 * sHitG (packet.cl); `live` is 0 for a lane without a ray. Local memory:
 * sStack CR_OCTREE_PACKET_STACK entries of CR_OCTREE_PACKET_ENTRY words,
 * sPlane CR_OCTREE_PACKET_PLANES floats, sLane one word per lane (its votes), sState CR_OCTREE_PACKET_STATE words.
 * Every work-item of the group must call it (it contains barriers). */
CR_FUNC void OctreePacket_Trace(CR_GLOBAL const OctreeHeader* hdr, CR_GLOBAL const OctreeNode* nodes,
                                CR_GLOBAL const uint* refs, const PrimView* pv, int anyHit, TraceStats* st, int live,
                                uint lid, uint nLanes, __local uint* sStack, __local float* sPlane,
                                __local uint* sLane,
                                __local uint* sState, __local real* sRay, __local uint* sAxes, __local real* sHit,
                                __local uint* sHitG)
{
#if CR_OCTREE_MAILBOX_BUILD
  /* The lane's mailbox (kernels/octree.h): a reference it has tested in an
   * earlier leaf is skipped. */
  uint mailbox[CR_OCTREE_MAILBOX];
  CR_UNROLL for (int k = 0; k < CR_OCTREE_MAILBOX; ++k) mailbox[k] = CR_NO_HIT;
#endif
  if (lid == 0) {
    CR_UNROLL for (int w = 0; w < CR_OCTREE_PACKET_ENTRY; ++w) sStack[w] = 0u; /* the root */
    OctreePacket_Pop(hdr, nodes, sStack, sState, sPlane, 1u);
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  /* The node's words are read from sState where they are used, and the
   * loop's exit test has a region of its own: PoCL takes a value loaded
   * alike by every work-item (the node, the exit test) for uniform and uses
   * the last work-item's copy after the work-item loop, and its loop
   * vectoriser refuses a loop whose value is used outside ("value that
   * could not be identified as reduction is used outside the loop"). */
  for (;;) {
    if (sState[0] == CR_OCTREE_PACKET_END) break;
    barrier(CLK_LOCAL_MEM_FENCE);
    /* Step 1, every lane: its interval of the node's cell and of the
     * children, from the node's planes. */
    int in;
    {
      const uint childMask = sState[6];
      Ray ray;
      Packet_LoadRay(sRay, sAxes, lid, nLanes, &ray);
      const real hitT = sHit[lid];
      const uint signMask = (ray.inv[0] < (real)0.0f ? 1u : 0u) | (ray.inv[1] < (real)0.0f ? 2u : 0u) |
                            (ray.inv[2] < (real)0.0f ? 4u : 0u);
      /* Octree_CellT's parameters, from the published planes. */
      real t0[3], tm[3], t1[3];
      CR_UNROLL for (int a = 0; a < 3; ++a) {
        const real lo = Ray_PlaneT(&ray, a, (real)sPlane[CR_OCTREE_PACKET_PLANE(a, 0)]);
        const real hi = Ray_PlaneT(&ray, a, (real)sPlane[CR_OCTREE_PACKET_PLANE(a, 1)]);
        tm[a] = Ray_PlaneT(&ray, a, (real)sPlane[CR_OCTREE_PACKET_PLANE(a, 2)]);
        const int neg = (int)((signMask >> a) & 1u);
        t0[a] = neg ? hi : lo;
        t1[a] = neg ? lo : hi;
      }
      const real ce = CR_OCTREE_PACKET_LO(fmax(fmax(t0[0], t0[1]), t0[2]));
      const real cx = CR_OCTREE_PACKET_HI(fmin(fmin(t1[0], t1[1]), t1[2]));
      in = live & (fmax(ce, ray.tmin) <= fmin(cx, hitT) ? 1 : 0);
      uint enter = 0u;
      CR_UNROLL for (uint m = 0u; m < 8u; ++m) {
        const real cce =
            CR_OCTREE_PACKET_LO(fmax(fmax((m & 1u) ? tm[0] : t0[0], (m & 2u) ? tm[1] : t0[1]), (m & 4u) ? tm[2] : t0[2]));
        const real ccx =
            CR_OCTREE_PACKET_HI(fmin(fmin((m & 1u) ? t1[0] : tm[0], (m & 2u) ? t1[1] : tm[1]), (m & 4u) ? t1[2] : tm[2]));
        const uint hit = (cce <= ccx && ccx >= ray.tmin && cce <= hitT) ? 1u : 0u;
        enter |= hit << (m ^ signMask);
      }
      enter = in ? enter & childMask : 0u;
#ifdef CR_STATS
      st->nTS += (uint)in;
      st->nLeaves += (uint)in & (childMask == 0u ? 1u : 0u);
#endif
#if CR_OCTREE_MARGIN_BUILD
      /* A leaf with a box (CR_OCTREE_LEAF_BOXES): only the lanes entering
       * it test its references (Octree_Leaf). */
      if (childMask == 0u && CR_OCTREE_USE_LEAF_BOXES(hdr)) {
        CR_GLOBAL const OctreeNode* leaf = nodes + sState[0];
        if (in && leaf->count != 0u) in = Octree_LeafBoxHit(leaf, refs, &ray, hitT);
      }
#endif
      sLane[lid] = enter | ((uint)in << 8) | (signMask << 9) | ((uint)live << 12);
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    /* Step 2, lane 0: push the children some lane entered, pop the next
     * node, publish the leaf's references if some lane entered it. */
    if (lid == 0) {
      uint any = 0u, nIn = 0u, nLive = 0u, nVoters = 0u, neg[3] = {0u, 0u, 0u};
      CR_ROLLED for (uint k = 0; k < nLanes; ++k) {
        const uint f = sLane[k];
        any |= f & 0xFFu;
        nIn += (f >> 8) & 1u;
        nLive += (f >> 12) & 1u;
        const uint voter = (f & 0xFFu) != 0u ? 1u : 0u;
        nVoters += voter;
        CR_UNROLL for (int a = 0; a < 3; ++a) neg[a] += voter & (f >> (9 + a));
      }
      const uint order = (2u * neg[0] > nVoters ? 1u : 0u) | (2u * neg[1] > nVoters ? 2u : 0u) |
                         (2u * neg[2] > nVoters ? 4u : 0u);
      CR_GLOBAL const OctreeNode* n = nodes + sState[0];
      const uint childMask = sState[6];
      uint sp = sState[5];
      const uint level = sState[1];
      uint c[3];
      CR_UNROLL for (int a = 0; a < 3; ++a) c[a] = sState[2 + a];
      for (int m = 7; m >= 0; --m) {
        const uint o = (uint)m ^ order;
        if ((any >> o) & 1u) {
          __local uint* e = sStack + sp * CR_OCTREE_PACKET_ENTRY;
          e[0] = n->first + cr_popcount(n->childMask & ((1u << o) - 1u));
          e[1] = level + 1u;
          CR_UNROLL for (int a = 0; a < 3; ++a) e[2 + a] = 2u * c[a] + ((o >> a) & 1u);
          ++sp;
        }
      }
      sState[7] = n->first;
      sState[8] = (childMask == 0u && nIn > 0u) ? n->count : 0u;
      /* No live lane left (any-hit queries all answered): the end. */
      OctreePacket_Pop(hdr, nodes, sStack, sState, sPlane, nLive > 0u ? sp : 0u);
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    /* Step 3, once per reference of the leaf (one barrier each). */
    for (uint k = 0; k < sState[8]; ++k) {
      {
        const uint prim = refs[sState[7] + k];
        int test = in;
#if CR_OCTREE_MAILBOX_BUILD
        if (in) {
          const uint slot = prim & (CR_OCTREE_MAILBOX - 1u);
          test = mailbox[slot] != prim ? 1 : 0;
          mailbox[slot] = prim;
        }
#endif
        const int took = Packet_TestStep(pv, prim, test, sRay, sAxes, sHit, sHitG, lid, nLanes);
#ifdef CR_STATS
        st->nIT += (uint)test;
#endif
        live = live & !(took & anyHit);
        in = in & live;
      }
      barrier(CLK_LOCAL_MEM_FENCE);
    }
  }
}

/* For the dispatch trace.cl generates from CR_ACCEL_TYPES (Trace_Packet):
 * this traversal's local memory (its pieces: X(type, name, count), carved
 * from the kernel's pool; trace.cl passes them on as parameters of the
 * same names) and its call (the names are Trace_Packet's). */
#define CR_PACKET_LOCALS_OCTREE(X) \
  X(uint, sOctStack, CR_OCTREE_PACKET_STACK * CR_OCTREE_PACKET_ENTRY) X(float, sOctPlane, CR_OCTREE_PACKET_PLANES)
#define CR_PACKET_CALL_OCTREE(hdr, nodes, refs)                                                                 \
  OctreePacket_Trace(hdr, nodes, refs, pv, anyHit, st, live, lid, CR_PACKET_SIZE, sOctStack, sOctPlane, sLane,    \
                     sState, sRay, sAxes, sHit, sHitG)

#endif /* CR_WITH_OCTREE */
#endif /* CELLRAY_KERNELS_OCTREE_PACKET_CL */
