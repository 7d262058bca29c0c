/* What every packet traversal shares (OpenCL only): a work-group is a packet
 * of rays that walks a structure together, with barriers between the steps
 * and every loop condition read from local memory, so that all work-items
 * take the same path (kernels/bvh_packet.cl, grid_packet.cl,
 * octree_packet.cl). PoCL's work-item loops around such straight-line steps
 * can be vectorised; a loop whose trip count differs per work-item cannot.
 *
 * The packet's rays and hits live in local memory, one array per field
 * (structure of arrays, CR_PACKET_RAY_FIELDS reals and one uint per lane for
 * the ray, CR_PACKET_HIT_FIELDS reals and one uint for the hit). Each step
 * loads what it needs into private variables and stores back what it
 * changed: no ray or hit value is live across a barrier, so PoCL keeps no
 * per-lane copy of them ("context arrays"), and the per-lane loads of one
 * field are consecutive across the work-items, which its loop vectoriser
 * turns into vector loads. (Kept in private structs across barriers, the
 * fields came out pre-packed in 2-wide vectors, which the vectoriser
 * refuses: "instruction return type cannot be vectorized".) */
#ifndef CELLRAY_KERNELS_PACKET_CL
#define CELLRAY_KERNELS_PACKET_CL
#include "intersect.h"

#define CR_PACKET_RAY_FIELDS 14
#define CR_PACKET_HIT_FIELDS 3

CR_FUNC void Packet_StoreRay(__local real* sRay, __local uint* sAxes, uint lid, uint nLanes, const Ray* r)
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

CR_FUNC void Packet_LoadRay(__local const real* sRay, __local const uint* sAxes, uint lid, uint nLanes, Ray* r)
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

CR_FUNC void Packet_StoreHit(__local real* sHit, __local uint* sHitG, uint lid, uint nLanes, const Hit* h)
{
  sHit[lid] = h->t;
  sHit[nLanes + lid] = h->u;
  sHit[2 * nLanes + lid] = h->v;
  sHitG[lid] = h->g;
}

CR_FUNC void Packet_LoadHit(__local const real* sHit, __local const uint* sHitG, uint lid, uint nLanes, Hit* h)
{
  h->t = sHit[lid];
  h->u = sHit[nLanes + lid];
  h->v = sHit[2 * nLanes + lid];
  h->g = sHitG[lid];
}

/* Keeps a candidate hit if the lane wants it and it is closer (Hit_Closer),
 * with selects rather than branches so that the work-item loop stays
 * straight-line. Returns 1 when the hit changed. */
CR_FUNC int Packet_Commit(Hit* hit, int want, real t, real u, real v, uint g)
{
  const int take = want & Hit_Closer(t, g, hit);
  hit->t = take ? t : hit->t;
  hit->u = take ? u : hit->u;
  hit->v = take ? v : hit->v;
  hit->g = take ? g : hit->g;
  return take;
}

/* Tests primitive g (a valid index) against the lane's ray and hit, as
 * Prim_Intersect does, without keeping the result: 1 with t, u, v when the
 * ray meets it within [tmin, hit.t]. One branch per primitive type, each
 * under its own condition (not an else chain), so that a vectoriser can run
 * all of them under masks. */
CR_FUNC int Packet_PrimTest(const PrimView* pv, uint g, const Ray* ray, const Hit* hit, real* t, real* u, real* v)
{
  int found = 0;
  *t = (real)0.0f;
  *u = (real)0.0f;
  *v = (real)0.0f;
#if CR_HAS_SPHERES
  if (g < pv->nSpheres) {
    const Sphere prim = pv->spheres[g];
    found = Sphere_Intersect(ray, &prim, ray->tmin, hit->t, t);
  }
#endif
#if CR_HAS_TRIANGLES
  if (g >= pv->nSpheres && g < pv->nSpheres + pv->nTriangles) {
    const Triangle prim = pv->triangles[g - pv->nSpheres];
    found = Triangle_Intersect(ray, &prim, ray->tmin, hit->t, t, u, v);
  }
#endif
#if CR_HAS_CONES
  if (g >= pv->nSpheres + pv->nTriangles) {
    const Cone prim = pv->cones[g - pv->nSpheres - pv->nTriangles];
    found = Cone_Intersect(ray, &prim, ray->tmin, hit->t, t);
  }
#endif
  return found;
}

#endif /* CELLRAY_KERNELS_PACKET_CL */
