/* BVH packet traversal (OpenCL only): the work-group walks the tree together
 * with uniform control flow, after the shared-stack packet traversals of
 * Garanzha & Loop ("Fast ray sorting and breadth-first packet traversal for
 * GPU ray tracing", 2010) and Aila & Laine 2009 (sec. 3, "packet traversal").
 *
 * Every iteration visits one node for the whole group: each live lane tests
 * the node's box against its own ray and current hit; a lane inside a leaf
 * intersects the leaf's primitives (the trip count is the leaf's, the same
 * for all lanes). The lanes' verdicts go to local memory; after a barrier one
 * lane reduces them and updates the shared stack: at an interior node that
 * some lane entered, descend to the child that most lanes reach first and
 * push the other; otherwise pop. The next node and the loop condition come
 * from local memory, so all work-items take the same path (PoCL vectorises
 * the work-item loops of such regions; per-lane early exits would not).
 *
 * The answer is the per-ray one: every box test is conservative and per
 * lane, and Hit_Closer makes the closest hit independent of the order. An
 * any-hit query may report a different occluder than BVH_Trace. */
#ifndef CELLRAY_KERNELS_BVH_PACKET_CL
#define CELLRAY_KERNELS_BVH_PACKET_CL
#include "bvh.h"

#define CR_PACKET_END 0xFFFFFFFFu

/* Lane vote at an interior node: 1 when the ray probably reaches child
 * first + 1 before child first, judged on the axis that separates the two
 * children's centres most (one sign test, no box test). Reads only valid
 * nodes whatever `n` is (a leaf compares itself with itself). */
CR_FUNC uint BVHPacket_SecondFirst(CR_GLOBAL const BVHNode* nodes, uint ni, uint interior, const Ray* ray)
{
  CR_GLOBAL const BVHNode* a = nodes + (interior ? nodes[ni].first : ni);
  CR_GLOBAL const BVHNode* b = a + (interior ? 1 : 0);
  /* Selects, not an index by axis: the work-item loop must stay branch-free. */
  float sep = 0.0f, best = -1.0f;
  int neg = 0;
  CR_UNROLL for (int k = 0; k < 3; ++k) {
    const float d = (b->bmin[k] + b->bmax[k]) - (a->bmin[k] + a->bmax[k]);
    const int better = d * d > best;
    best = better ? d * d : best;
    sep = better ? d : sep;
    neg = better ? (ray->dir[k] < (real)0.0f) : neg;
  }
  return (sep > 0.0f) == (neg != 0) ? 1u : 0u;
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
 * ray. sStack holds CR_BVH_STACK node indices, sLane one word per lane (the
 * lanes' verdicts), sState six words (next node, stack size, leaf range by
 * type). sStack, sLane and sState pass values between work-items across
 * barriers and must not be (a compiler may then keep their values
 * across a barrier); the per-lane ray and hit arrays are.
 * Every work-item of the group must call it (it contains barriers).
 *
 * Each step between two barriers is straight-line code per lane (a box test;
 * one primitive test of a type known to the whole group; the reduction, by
 * lane 0), so that the work-item loop PoCL builds around it has no inner loop
 * and no branch on a lane's data, and can be vectorised: the loops over a
 * leaf's primitives are group-level loops with a barrier in their body, and
 * every lane computes every test, keeping the result only where it wants it. */
CR_FUNC void BVHPacket_Trace(CR_GLOBAL const BVHNode* nodes, CR_GLOBAL const uint* refs, const PrimView* pv,
                             int anyHit, TraceStats* st, int live, uint lid, uint nLanes,
                             __local uint* sStack, __local uint* sLane, __local uint* sState,
                             __local real* sRay,
                             __local uint* sAxes, __local real* sHit,
                             __local uint* sHitG)
{
  if (lid == 0) {
    sState[0] = 0;
    sState[1] = 0;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  for (;;) {
    const uint ni = sState[0];
    if (ni == CR_PACKET_END) break;
    /* Step 1, every lane: the node's box against the lane's ray. */
    const uint interior = nodes[ni].count == 0 ? 1u : 0u;
    int in;
    uint vote;
    {
      Ray ray;
      BVHPacket_LoadRay(sRay, sAxes, lid, nLanes, &ray);
      real tEnter;
      in = live & Box_Intersect(nodes[ni].bmin, nodes[ni].bmax, &ray, ray.tmin, sHit[lid], &tEnter);
      vote = BVHPacket_SecondFirst(nodes, ni, interior, &ray) & (uint)in & interior;
    }
#ifdef CR_STATS
    st->nTS += (uint)in;
    st->nLeaves += (uint)in & (1u - interior);
#endif
    sLane[lid] = (uint)in | (vote << 1) | ((uint)live << 2);
    barrier(CLK_LOCAL_MEM_FENCE);
    /* Step 2, lane 0: reduce the verdicts, pick the next node, publish the
     * leaf to test (its references split by type) if any lane entered it. */
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
      uint nSph = 0, nTri = 0, nCone = 0;
      if (nLive > 0) {
        if (nIn > 0 && interior) {
          const uint nearer = 2 * nVote > nIn ? n->first + 1 : n->first;
          sStack[sp++] = nearer == n->first ? n->first + 1 : n->first;
          next = nearer;
        } else {
          if (nIn > 0) {
            /* References are sorted, so grouped by type (types.h). */
            for (uint i = n->first; i < n->first + n->count; ++i) {
              const uint g = refs[i];
              if (g < pv->nSpheres)
                ++nSph;
              else if (g < pv->nSpheres + pv->nTriangles)
                ++nTri;
              else
                ++nCone;
            }
          }
          if (sp > 0) next = sStack[--sp];
        }
      }
      sState[0] = next;
      sState[1] = sp;
      sState[2] = n->first;
      sState[3] = nSph;
      sState[4] = nTri;
      sState[5] = nCone;
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    /* Step 3, every lane, once per primitive of the leaf, type by type. */
    uint i = sState[2];
    const int want = in & live;
#if CR_HAS_SPHERES
    for (uint end = i + sState[3]; i < end; ++i) {
      const uint g = refs[i];
      Ray ray;
      Hit hit;
      BVHPacket_LoadRay(sRay, sAxes, lid, nLanes, &ray);
      BVHPacket_LoadHit(sHit, sHitG, lid, nLanes, &hit);
      real t = (real)0.0f;
      const int found = Sphere_Intersect(&ray, pv->spheres + g, ray.tmin, hit.t, &t);
      const int took = BVHPacket_Commit(&hit, want & found, t, (real)0.0f, (real)0.0f, g);
      BVHPacket_StoreHit(sHit, sHitG, lid, nLanes, &hit);
#ifdef CR_STATS
      st->nIT += (uint)want;
#endif
      live = live & !(took & anyHit);
      barrier(CLK_LOCAL_MEM_FENCE);
    }
#endif
#if CR_HAS_TRIANGLES
    for (uint end = i + sState[4]; i < end; ++i) {
      const uint g = refs[i];
      Ray ray;
      Hit hit;
      BVHPacket_LoadRay(sRay, sAxes, lid, nLanes, &ray);
      BVHPacket_LoadHit(sHit, sHitG, lid, nLanes, &hit);
      real t = (real)0.0f, u = (real)0.0f, v = (real)0.0f;
      const int found = Triangle_Intersect(&ray, pv->triangles + (g - pv->nSpheres), ray.tmin, hit.t, &t, &u, &v);
      const int took = BVHPacket_Commit(&hit, want & found, t, u, v, g);
      BVHPacket_StoreHit(sHit, sHitG, lid, nLanes, &hit);
#ifdef CR_STATS
      st->nIT += (uint)want;
#endif
      live = live & !(took & anyHit);
      barrier(CLK_LOCAL_MEM_FENCE);
    }
#endif
#if CR_HAS_CONES
    for (uint end = i + sState[5]; i < end; ++i) {
      const uint g = refs[i];
      Ray ray;
      Hit hit;
      BVHPacket_LoadRay(sRay, sAxes, lid, nLanes, &ray);
      BVHPacket_LoadHit(sHit, sHitG, lid, nLanes, &hit);
      real t = (real)0.0f;
      const int found =
          Cone_Intersect(&ray, pv->cones + (g - pv->nSpheres - pv->nTriangles), ray.tmin, hit.t, &t);
      const int took = BVHPacket_Commit(&hit, want & found, t, (real)0.0f, (real)0.0f, g);
      BVHPacket_StoreHit(sHit, sHitG, lid, nLanes, &hit);
#ifdef CR_STATS
      st->nIT += (uint)want;
#endif
      live = live & !(took & anyHit);
      barrier(CLK_LOCAL_MEM_FENCE);
    }
#endif
  }
}

#endif /* CELLRAY_KERNELS_BVH_PACKET_CL */
