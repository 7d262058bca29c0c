/* The axis-aligned box (NFF extension `box xmin ymin zmin xmax ymax zmax`,
 * docs/FORMATS.md): its surface, the six faces; the layout is Box of
 * kernels/types.h. The slab test gives where the ray enters the box and
 * where it leaves; the hit is the entry, or the exit for a ray that starts
 * inside. Watertight by construction: faces that meet at an edge share the
 * parameters of their planes, so a ray through an edge or a corner finds
 * the same t from either face and never slips between them. A ray lying in
 * a face's plane, parallel to it, has 0 / 0 there: fmin and fmax pass over
 * the NaN, so that slab's bound goes to +-inf and the box is missed (unless
 * the box is flat on that axis, when the slab bounds nothing), in every mode
 * and in the fp64 reference alike. Robust and fp64 modes divide (p - o) / d: the
 * exact or once-rounded difference, rounded once more, so t is within about
 * one ulp of the true t whatever the coordinates' magnitude; fast mode
 * multiplies by the rounded reciprocal. */
#ifndef CELLRAY_KERNELS_BOX_H
#define CELLRAY_KERNELS_BOX_H
#include "numeric.h"

#ifndef CR_HAS_BOX
#define CR_HAS_BOX 1
#endif

/* The parameters where the ray enters (*tn) and leaves (*tf) the box's
 * slabs; the box is met where tn <= tf. */
CR_FUNC void Box_Slabs3(const Ray* r, const Box* b, real* tn, real* tf)
{
  real n = -CR_INF, f = CR_INF;
  CR_UNROLL for (int a = 0; a < 3; ++a) {
#ifdef CR_FAST
    const real t0 = ((real)b->lo[a] - r->org[a]) * r->inv[a];
    const real t1 = ((real)b->hi[a] - r->org[a]) * r->inv[a];
#else
    const real t0 = ((real)b->lo[a] - r->org[a]) / r->dir[a];
    const real t1 = ((real)b->hi[a] - r->org[a]) / r->dir[a];
#endif
    /* fmin/fmax pass over a NaN operand (see above). */
    n = fmax(n, fmin(t0, t1));
    f = fmin(f, fmax(t0, t1));
  }
  *tn = n;
  *tf = f;
}

/* The first point of the surface in [tmin, tmax]. */
CR_FUNC int Box_Hit(const Ray* r, const Box* b, real tmin, real tmax, real* tHit)
{
  real tn, tf;
  Box_Slabs3(r, b, &tn, &tf);
  if (!(tn <= tf)) return 0;
  const real t = tn >= tmin ? tn : tf;
  if (!(t >= tmin && t <= tmax)) return 0;
  *tHit = t;
  return 1;
}
/* The uniform form of the dispatch (CR_PRIM_TYPES): no barycentrics. */
CR_FUNC int Box_Test(const Ray* r, const Box* b, real tmin, real tmax, real* tHit, real* u, real* v)
{
  (void)u;
  (void)v;
  return Box_Hit(r, b, tmin, tmax, tHit);
}
/* A copy of a box in global memory (field by field). */
CR_FUNC Box Box_Load(CR_GLOBAL const Box* p)
{
  Box b;
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    b.lo[a] = p->lo[a];
    b.hi[a] = p->hi[a];
  }
  b.pad0 = 0u;
  b.pad1 = 0u;
  return b;
}

#endif /* CELLRAY_KERNELS_BOX_H */
