/* The CSG solid (NFF extension `csg union|intersection|difference` ...
 * `csg end`, docs/FORMATS.md): a boolean expression over convex leaf solids
 * (sphere, box, convex polyhedron, ellipsoidal quadric); the layout is Csg
 * of kernels/types.h, each leaf's record packed in its words.
 *
 * Interval classification along the ray (Roth 1982): each leaf's own test
 * (kernels/<type>.h, in the precision mode of the build) gives where the
 * ray's line enters the leaf and where it leaves it (the first crossing
 * from -inf of the ray and of the reversed ray); kernels/csg_sweep.h walks those
 * events in order and stops at the first where the expression's value
 * changes. The hit's u is the leaf's index in the block (the reported
 * primitive is the leaf statement: kernels/intersect.h Hit_ToRecord), v is 1
 * where the leaf's outward normal points into the solid (a difference's
 * subtrahend), else 0. */
#ifndef CELLRAY_KERNELS_CSG_H
#define CELLRAY_KERNELS_CSG_H
#include "numeric.h"
#include "sphere.h"
#include "box.h"
#include "quadric.h"
#include "polyhedron.h"

#ifndef CR_HAS_CSG
#define CR_HAS_CSG 1
#endif
/* The leaf types a program is built for: bit CR_PRIM_<TYPE> (OpenCL:
 * only those of the scene's blocks, host/cl/cl_options.cpp). */
#ifndef CR_CSG_LEAVES
#define CR_CSG_LEAVES 0x39u
#endif

#include "csg_sweep.h"

/* Where the ray's line enters the convex leaf (its first crossing from
 * -inf) and leaves it (the first crossing of the reversed ray `back`,
 * negated: the tests are symmetric under d -> -d, and asking the forward
 * ray for its first crossing past the entry instead would leave the entry
 * undecided against that tmin and send the robust polyhedron and quadric
 * tests to double-float every time). */
#define CR_CSG_SPAN_(T)                                                         \
  {                                                                             \
    T p;                                                                        \
    Csg_##T(c, w, &p);                                                          \
    if (!T##_Test(r, &p, -(real)CR_INF, (real)CR_INF, t0, &u, &v)) return 0;    \
    if (!T##_Test(back, &p, -(real)CR_INF, (real)CR_INF, t1, &u, &v)) return 0; \
    *t1 = -*t1;                                                                 \
    return *t1 >= *t0;                                                          \
  }
CR_FUNC int Csg_Span(const Ray* r, const Ray* back, const Csg* c, uint i, real* t0, real* t1)
{
  const uint type = c->leaf[i] & 255u, w = c->leaf[i] >> 8;
  real u = (real)0.0f, v = (real)0.0f;
#if CR_CSG_LEAVES & 1u
  if (type == CR_PRIM_SPHERE) CR_CSG_SPAN_(Sphere)
#endif
#if CR_CSG_LEAVES & 8u
  if (type == CR_PRIM_BOX) CR_CSG_SPAN_(Box)
#endif
#if CR_CSG_LEAVES & 16u
  if (type == CR_PRIM_QUADRIC) CR_CSG_SPAN_(Quadric)
#endif
#if CR_CSG_LEAVES & 32u
  if (type == CR_PRIM_POLYHEDRON) CR_CSG_SPAN_(Polyhedron)
#endif
  (void)type;
  (void)w;
  (void)u;
  (void)v;
  return 0;
}
#undef CR_CSG_SPAN_

CR_FUNC int Csg_Test(const Ray* ray, const Csg* c, real tmin, real tmax, real* tHit, real* u, real* v)
{
  /* Every crossing at full accuracy: an occlusion query's shortcuts
   * (Ray.anyHit) would leave the order of two leaves' crossings open. */
  Ray r = *ray, back = *ray;
  r.anyHit = back.anyHit = 0;
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    back.dir[a] = -r.dir[a];
    back.inv[a] = -r.inv[a];
  }
  real t0[CR_CSG_MAX_LEAVES], t1[CR_CSG_MAX_LEAVES];
  uint met = 0u;
  for (uint i = 0u; i < c->nLeaves; ++i) {
    t0[i] = t1[i] = (real)0.0f;
    if (Csg_Span(&r, &back, c, i, &t0[i], &t1[i])) met |= 1u << i;
  }
  uint leaf = 0u, flip = 0u;
  if (!Csg_Classify(c, t0, t1, met, tmin, tmax, tHit, &leaf, &flip)) return 0;
  *u = (real)leaf;
  *v = (real)flip;
  return 1;
}
/* A copy of a CSG solid in global memory: its used nodes, leaves and words. */
CR_FUNC Csg Csg_Load(CR_GLOBAL const Csg* p)
{
  Csg s;
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    s.lo[a] = p->lo[a];
    s.hi[a] = p->hi[a];
  }
  s.nNodes = p->nNodes;
  s.nLeaves = p->nLeaves;
  for (uint k = 0u; k < CR_CSG_MAX_NODES / 4u; ++k) s.node[k] = p->node[k];
  for (uint k = 0u; k < CR_CSG_MAX_LEAVES; ++k) s.leaf[k] = p->leaf[k];
  for (uint k = 0u; k < CR_CSG_MAX_WORDS; ++k) CR_UNROLL for (int a = 0; a < 4; ++a) s.word[k][a] = p->word[k][a];
  return s;
}

#endif /* CELLRAY_KERNELS_CSG_H */
