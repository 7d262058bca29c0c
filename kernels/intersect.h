/* Ray-primitive intersection, shared by every structure and backend: the
 * primitive arrays of a scene (PrimView), the test of unified index g
 * (Prim_Intersect), the tie rule and hit records. Each type's test is in its
 * own header, included below in CR_PRIM_TYPES order (shared numerics in
 * numeric.h).
 *
 * Precision modes (macros):
 *   default  `robust`: watertight triangles (Woop, Benthin & Wald 2013), the
 *            stable sphere quadratic (Hearn & Baker 14-6; Haines et al., Ray
 *            Tracing Gems ch. 7: the discriminant from |f x d|, the roots as
 *            q/a and c/q), conservative slab tests (Ize 2013);
 *   CR_FAST  `fast`: Moller-Trumbore with a fixed determinant epsilon, the
 *            textbook quadratic, plain slab tests;
 *   CR_FP64  `fp64`: the robust algorithms with real = double.
 * Model only what the scene needs: CR_HAS_SPHERE, CR_HAS_TRIANGLE, ...
 * (kernels/types.h, default 1) remove the code of absent primitive types. */
#ifndef CELLRAY_KERNELS_INTERSECT_H
#define CELLRAY_KERNELS_INTERSECT_H
#include "ray.h"


/* The primitive arrays of a scene, unified index g as in types.h. */
typedef struct {
#define CR_PRIM_ARRAY(T, U, array) CR_GLOBAL const T* array;
  CR_PRIM_TYPES(CR_PRIM_ARRAY)
#undef CR_PRIM_ARRAY
  PrimRanges ranges;
  /* Motion of each unified piece, 4 floats (kernels/motion.h), or null for
   * a static scene. */
  CR_GLOBAL const float* motion;
} PrimView;

#include "motion.h"
#include "numeric.h"
#include "sphere.h"
#include "triangle.h"
#include "cone.h"
#include "box.h"
#include "quadric.h"
#include "polyhedron.h"
#include "sdf.h"
#include "csg.h"

/* Hit_Closer for primitive g met at t by ray r, with one refinement in
 * robust mode: an exact float tie between two different spheres goes to the
 * one that double-float arithmetic finds nearer (Sphere_TieOrder); any
 * other tie to the lower id. */
CR_FUNC int Hit_CloserOn(const PrimView* pv, const Ray* r, real t, uint g, const Hit* h)
{
#if CR_HAS_SPHERE && !defined(CR_FAST) && !defined(CR_FP64)
  if (t == h->t && g != h->g && Prim_Is(&pv->ranges, CR_PRIM_SPHERE, g) && Prim_Is(&pv->ranges, CR_PRIM_SPHERE, h->g)) {
    const Sphere a = pv->spheres[g];
    const Sphere b = pv->spheres[h->g];
    const int order = Sphere_TieOrder(r->org, r->dir, r->tmin, &a, &b);
    if (order != 0) return order < 0;
  }
#endif
  return Hit_Closer(t, g, h);
}

/* The typed tests take the primitive in private memory (a copy), so that a
 * caller may hold it anywhere: global memory (Prim_Intersect), or local
 * memory shared by a work-group (kernels/bvh_packet.cl). */


/* Tests primitive g and keeps the hit if it is closer (Hit_Closer). Returns 1
 * when the hit changed. */
CR_FUNC_HOT int Prim_Intersect(const PrimView* pv, uint g, const Ray* r, Hit* hit)
{
  real t = (real)0.0f, u = (real)0.0f, v = (real)0.0f;
  int found = 0;
#if CR_HAS_MOTION
  /* A moving piece meets the ray shifted into its rest frame (motion.h). */
  Ray moved;
  if (pv->motion && Motion_Shift(pv->motion, g, r, &moved)) r = &moved;
#endif
  /* In type order: each test below knows g is past the types above; no
   * code for the types the kernel is not built for. */
#define CR_PRIM_TEST(T, U, array)                                     \
  CR_IF(U, if (g < Prim_End(&pv->ranges, CR_PRIM_##U)) {              \
    const T p = pv->array[Prim_Local(&pv->ranges, CR_PRIM_##U, g)];   \
    found = T##_Test(r, &p, r->tmin, hit->t, &t, &u, &v);             \
  } else)
  CR_PRIM_TYPES(CR_PRIM_TEST) {}
#undef CR_PRIM_TEST
  if (found && Hit_CloserOn(pv, r, t, g, hit)) {
    hit->t = t;
    hit->u = u;
    hit->v = v;
    hit->g = g;
    return 1;
  }
  return 0;
}

/* How far boxes and cells are still entered for a closest hit at t: a little
 * beyond t. A primitive lying in a face of its box (coplanar faces of a mesh)
 * can have a computed t a few ulps below the box's computed entry; culling
 * that box at exactly t would make the nearest answer depend on which box was
 * visited first, and so differ between traversal orders and backends.
 * 8 ulps (2^-20 relative) covers it; fast mode culls at t. */
CR_FUNC real Cull_Distance(real t)
{
#ifdef CR_FAST
  return t;
#elif defined(CR_FP64)
  return t * ((real)1.0f + (real)0x1.0p-49f);
#else
  return t * (1.0f + 0x1.0p-20f);
#endif
}

/* Conservative slab test of a box against [tmin, tmax] (Williams et al. 2005
 * with Ize 2013's rounding: the far distance is scaled by 1 + 2 gamma(3) so
 * that rounding can never cull a box the exact ray enters). 0 * inf = NaN on
 * a plane-parallel ray is dropped by fmin/fmax. The corners come as private
 * values, so that boxes in any address space share it. Writes the entry
 * distance. */
CR_FUNC int Box_Slabs(const real lo3[3], const real hi3[3], const Ray* r, real tmin, real tmax, real* tEnter)
{
  real tn = tmin, tf = tmax;
  real boxFar = (real)CR_INF;
  real boxNear = -(real)CR_INF;
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    real lo = (lo3[a] - r->org[a]) * r->inv[a];
    real hi = (hi3[a] - r->org[a]) * r->inv[a];
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
  *tEnter = tn;
  return tn <= tf;
}

/* Box_Slabs of a box in global memory. */
CR_FUNC int Box_Intersect(CR_GLOBAL const float* bmin, CR_GLOBAL const float* bmax, const Ray* r, real tmin, real tmax,
                          real* tEnter)
{
  real lo[3], hi[3];
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    lo[a] = (real)bmin[a];
    hi[a] = (real)bmax[a];
  }
  return Box_Slabs(lo, hi, r, tmin, tmax, tEnter);
}

/* The .hits record of a finished query: closest hit (t, prim id, u, v) or
 * occlusion (t = 0, an occluder's id); a miss is (+inf, CR_NO_HIT). u, v are
 * reported for whole triangle statements only (FORMATS.md); a hit on a CSG
 * solid reports its leaf statement.
 * With `unified` set, the record is the renderer's internal form instead: prim
 * holds the unified piece index g and u, v are the barycentrics of every
 * triangle piece (primIds is not read). */
CR_FUNC HitRecord Hit_ToRecord(const Hit* h, const PrimView* pv, CR_GLOBAL const uint* primIds, int anyHit, int unified)
{
  HitRecord r;
  r.u = 0.0f;
  r.v = 0.0f;
  if (h->g == CR_NO_HIT) {
    r.t = CR_INF;
    r.prim = CR_NO_HIT;
    return r;
  }
  r.prim = unified ? h->g : primIds[h->g];
  r.t = anyHit ? 0.0f : (float)h->t;
  /* A CSG solid: the leaf statement (its index in the block, in u), and
   * in the renderer's form the leaf and its normal's side. */
  CR_IF(CSG, if (Prim_Is(&pv->ranges, CR_PRIM_CSG, h->g)) {
    if (unified) {
      r.u = (float)h->u;
      r.v = (float)h->v;
    } else {
      r.prim += (uint)h->u;
    }
    return r;
  })
  if (!anyHit && Prim_Is(&pv->ranges, CR_PRIM_TRIANGLE, h->g) &&
      (unified || (pv->triangles[Prim_Local(&pv->ranges, CR_PRIM_TRIANGLE, h->g)].flags & CR_TRI_REPORT_UV))) {
    r.u = (float)h->u;
    r.v = (float)h->v;
  }
  return r;
}

#endif /* CELLRAY_KERNELS_INTERSECT_H */
