/* What every packet traversal shares (OpenCL only): a work-group is a packet
 * of rays that walks a structure together, with barriers between the steps
 * and every loop condition read from local memory, so that all work-items
 * take the same path (each structure's kernels/<lower>_packet.cl). PoCL's work-item loops around such straight-line steps
 * can be vectorised; a loop whose trip count differs per work-item cannot.
 *
 * The packet's rays and hits live in local memory, one array per field
 * (structure of arrays: CR_PACKET_RAY_FIELDS reals and CR_PACKET_AXES_FIELDS
 * uints per lane for the ray, CR_PACKET_HIT_FIELDS reals and one uint for the
 * hit). Each step loads what it needs into private variables and stores back
 * what it changed: no ray or hit value is live across a barrier, so PoCL
 * keeps no per-lane copy of them ("context arrays"), and the per-lane loads
 * of one field are consecutive across the work-items, which its loop
 * vectoriser turns into vector loads.
 *
 * PoCL's loop vectoriser refuses a work-item loop that holds any value of
 * vector type ("instruction return type cannot be vectorized"), and the
 * compiler makes such values out of alike scalar operations on neighbouring
 * fields before the work-item loops exist: private structs kept across
 * barriers, struct copies, arrays indexed by a computed axis, and the three
 * axes of the triangle test unpacked from one word by three alike
 * shift-and-masks all came out as 2-wide vectors. Hence the structure of
 * arrays, primitives copied field by field, CR_PICK3 (prelude.h), and one
 * word per axis. */
#ifndef CELLRAY_KERNELS_PACKET_CL
#define CELLRAY_KERNELS_PACKET_CL
#include "intersect.h"

/* Field 14 is the ray's time where the scene moves (kernels/motion.h). */
#define CR_PACKET_RAY_FIELDS (14 + CR_HAS_MOTION)
#define CR_PACKET_AXES_FIELDS 3
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
#if CR_HAS_MOTION
  sRay[14 * nLanes + lid] = r->time;
#endif
  sAxes[lid] = (uint)r->kx;
  sAxes[nLanes + lid] = (uint)r->ky;
  sAxes[2 * nLanes + lid] = (uint)r->kz;
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
#if CR_HAS_MOTION
  r->time = sRay[14 * nLanes + lid];
#else
  r->time = (real)0.0f;
#endif
  r->kx = (int)sAxes[lid];
  r->ky = (int)sAxes[nLanes + lid];
  r->kz = (int)sAxes[2 * nLanes + lid];
  r->anyHit = 0;
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

/* Keeps a candidate hit if the lane wants it and it is closer (Hit_CloserOn),
 * with selects rather than branches so that the work-item loop stays
 * straight-line. Returns 1 when the hit changed. */
CR_FUNC int Packet_Commit(const PrimView* pv, const Ray* ray, Hit* hit, int want, real t, real u, real v, uint g)
{
  const int take = want & Hit_CloserOn(pv, ray, t, g, hit);
  hit->t = take ? t : hit->t;
  hit->u = take ? u : hit->u;
  hit->v = take ? v : hit->v;
  hit->g = take ? g : hit->g;
  return take;
}

/* Private copies of a primitive, field by field: a struct copy becomes a
 * memcpy, or a load of the whole struct as one vector, either of which
 * keeps the work-item loop vectoriser from widening the step. */
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
#if CR_HAS_MOTION
  Ray moved;
  if (pv->motion && Motion_Shift(pv->motion, g, ray, &moved)) ray = &moved;
#endif
#define CR_PACKET_TEST(T, U, array)                                                  \
  CR_IF(U, if (Prim_Is(&pv->ranges, CR_PRIM_##U, g)) {                               \
    const T prim = T##_Load(pv->array + Prim_Local(&pv->ranges, CR_PRIM_##U, g));    \
    found = T##_Test(ray, &prim, ray->tmin, hit->t, t, u, v);                        \
  })
  CR_PRIM_TYPES(CR_PACKET_TEST)
#undef CR_PACKET_TEST
  return found;
}

/* The primitive-test step every packet traversal runs: the lane's ray and hit
 * from local memory, primitive g tested, the hit kept when `want` (the lane
 * asked for this test) and nearer, written back. Returns whether it took. */
CR_FUNC int Packet_TestStep(const PrimView* pv, uint g, int want, __local const real* sRay,
                            __local const uint* sAxes, __local real* sHit, __local uint* sHitG, uint lid, uint nLanes)
{
  Ray ray;
  Hit hit;
  Packet_LoadRay(sRay, sAxes, lid, nLanes, &ray);
  Packet_LoadHit(sHit, sHitG, lid, nLanes, &hit);
  real t, u, v;
  const int found = Packet_PrimTest(pv, g, &ray, &hit, &t, &u, &v);
  const int took = Packet_Commit(pv, &ray, &hit, want & found, t, u, v, g);
  Packet_StoreHit(sHit, sHitG, lid, nLanes, &hit);
  return took;
}

#endif /* CELLRAY_KERNELS_PACKET_CL */
