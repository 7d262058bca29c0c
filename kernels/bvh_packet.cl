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

/* Box_Intersect (intersect.h) with the same arithmetic, on a box in local
 * memory. */
CR_FUNC int BVHPacket_Box(__local const float* box, const Ray* r, real tmin, real tmax)
{
  real tn = tmin, tf = tmax;
  real boxFar = (real)CR_INF;
  real boxNear = -(real)CR_INF;
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    real lo = ((real)box[a] - r->org[a]) * r->inv[a];
    real hi = ((real)box[3 + a] - r->org[a]) * r->inv[a];
    real n = r->inv[a] < (real)0.0f ? hi : lo;
    real f = r->inv[a] < (real)0.0f ? lo : hi;
    boxNear = fmax(boxNear, n);
    boxFar = fmin(boxFar, f);
  }
#ifndef CR_FAST
#ifdef CR_FP64
  boxFar = boxFar * (real)1.0000000000000007;
#else
  boxFar = boxFar * 1.0000004f;
#endif
#endif
  tn = fmax(tn, boxNear);
  tf = fmin(tf, boxFar);
  return tn <= tf;
}

/* The packet's rays and hits live in local memory, one array per field
 * (structure of arrays, CR_PACKET_RAY_FIELDS reals and one uint per lane for
 * the ray, CR_PACKET_HIT_FIELDS reals and one uint for the hit). Each step
 * loads what it needs into private variables and stores back what it
 * changed: no ray or hit value is live across a barrier, so PoCL keeps no
 * per-lane copy of them ("context arrays"), and the per-lane loads of one
 * field are consecutive across the work-items, which its loop vectoriser
 * turns into vector loads. (Kept in private structs across barriers, the
 * fields came out pre-packed in 2-wide vectors, which the vectoriser
 * refuses: "instruction return type cannot be vectorized".) */
#define CR_PACKET_RAY_FIELDS 14
#define CR_PACKET_HIT_FIELDS 3

CR_FUNC void BVHPacket_StoreRay(__local real* sRay, __local uint* sAxes, uint lid, uint nLanes, const Ray* r)
{
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    sRay[(0 + a) * nLanes + lid] = r->org[a];
    sRay[(3 + a) * nLanes + lid] = r->dir[a];
    sRay[(6 + a) * nLanes + lid] = r->inv[a];
  }
  sRay[9 * nLanes + lid] = r->tmin;
  sRay[10 * nLanes + lid] = r->tmax;
  sRay[11 * nLanes + lid] = r->sx;
  sRay[12 * nLanes + lid] = r->sy;
  sRay[13 * nLanes + lid] = r->sz;
  sAxes[lid] = (uint)r->kx | ((uint)r->ky << 2) | ((uint)r->kz << 4);
}

CR_FUNC void BVHPacket_LoadRay(__local const real* sRay, __local const uint* sAxes, uint lid, uint nLanes, Ray* r)
{
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    r->org[a] = sRay[(0 + a) * nLanes + lid];
    r->dir[a] = sRay[(3 + a) * nLanes + lid];
    r->inv[a] = sRay[(6 + a) * nLanes + lid];
  }
  r->tmin = sRay[9 * nLanes + lid];
  r->tmax = sRay[10 * nLanes + lid];
  r->sx = sRay[11 * nLanes + lid];
  r->sy = sRay[12 * nLanes + lid];
  r->sz = sRay[13 * nLanes + lid];
  const uint k = sAxes[lid];
  r->kx = (int)(k & 3u);
  r->ky = (int)((k >> 2) & 3u);
  r->kz = (int)((k >> 4) & 3u);
}

CR_FUNC void BVHPacket_StoreHit(__local real* sHit, __local uint* sHitG, uint lid, uint nLanes, const Hit* h)
{
  sHit[lid] = h->t;
  sHit[nLanes + lid] = h->u;
  sHit[2 * nLanes + lid] = h->v;
  sHitG[lid] = h->g;
}

CR_FUNC void BVHPacket_LoadHit(__local const real* sHit, __local const uint* sHitG, uint lid, uint nLanes, Hit* h)
{
  h->t = sHit[lid];
  h->u = sHit[nLanes + lid];
  h->v = sHit[2 * nLanes + lid];
  h->g = sHitG[lid];
}

/* Keeps a candidate hit if the lane wants it and it is closer (Hit_Closer),
 * with selects rather than branches so that the work-item loop stays
 * straight-line. Returns 1 when the hit changed. */
CR_FUNC int BVHPacket_Commit(Hit* hit, int want, real t, real u, real v, uint g)
{
  const int take = want & Hit_Closer(t, g, hit);
  hit->t = take ? t : hit->t;
  hit->u = take ? u : hit->u;
  hit->v = take ? v : hit->v;
  hit->g = take ? g : hit->g;
  return take;
}

/* Closest or any hit of each lane's ray, already stored in sRay, sAxes, sHit,
 * sHitG with BVHPacket_StoreRay / BVHPacket_StoreHit (read the answer back
 * with BVHPacket_LoadHit after it returns); `live` is 0 for a lane without a
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
      BVHPacket_LoadRay(sRay, sAxes, lid, nLanes, &ray);
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
      for (uint k = 0; k < nLanes; ++k) {
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
        const uint g = refs[sState[2] + k];
        Ray ray;
        Hit hit;
        BVHPacket_LoadRay(sRay, sAxes, lid, nLanes, &ray);
        BVHPacket_LoadHit(sHit, sHitG, lid, nLanes, &hit);
        real t = (real)0.0f, u = (real)0.0f, v = (real)0.0f;
        int found = 0;
#if CR_HAS_SPHERES
        if (g < pv->nSpheres) {
          const Sphere prim = pv->spheres[g];
          found = Sphere_Intersect(&ray, &prim, ray.tmin, hit.t, &t);
        }
#endif
#if CR_HAS_TRIANGLES
        if (g >= pv->nSpheres && g < pv->nSpheres + pv->nTriangles) {
          const Triangle prim = pv->triangles[g - pv->nSpheres];
          found = Triangle_Intersect(&ray, &prim, ray.tmin, hit.t, &t, &u, &v);
        }
#endif
#if CR_HAS_CONES
        if (g >= pv->nSpheres + pv->nTriangles) {
          const Cone prim = pv->cones[g - pv->nSpheres - pv->nTriangles];
          found = Cone_Intersect(&ray, &prim, ray.tmin, hit.t, &t);
        }
#endif
        const int took = BVHPacket_Commit(&hit, want & found, t, u, v, g);
        BVHPacket_StoreHit(sHit, sHitG, lid, nLanes, &hit);
        live = live & !(took & anyHit);
      }
#ifdef CR_STATS
      st->nIT += (uint)want;
#endif
      barrier(CLK_LOCAL_MEM_FENCE);
    }
  }
}

#endif /* CELLRAY_KERNELS_BVH_PACKET_CL */
