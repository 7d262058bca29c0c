/* BVH traversal: ordered stack traversal, nearer child first, conservative
 * slab tests (Box_Intersect). Layout: BVHNode in types.h. */
#ifndef CELLRAY_KERNELS_BVH_H
#define CELLRAY_KERNELS_BVH_H
#include "intersect.h"

/* Compiled unless the build is for one other structure (CR_ACCEL_ONE, see
 * trace.cl); CR_WITH_BVH tells the generated dispatch (CR_IF_WITH). */
#if !defined(CR_ACCEL_ONE) || defined(CR_ACCEL_BVH)
#define CR_WITH_BVH 1
#else
#define CR_WITH_BVH 0
#endif
#if CR_WITH_BVH

/* Deep enough for the builder's depth limit (host/accel/bvh_builder.cpp). */
#define CR_BVH_STACK 64

/* Closest hit (anyHit = 0) or any hit (anyHit = 1) of the ray against the
 * BVH; `hit` must come from Hit_Init. */
CR_FUNC void BVH_Trace(CR_GLOBAL const BVHHeader* hdr, CR_GLOBAL const BVHNode* nodes, CR_GLOBAL const uint* refs,
                       const PrimView* pv, const Ray* ray, Hit* hit, int anyHit, TraceStats* st)
{
  (void)hdr;
  uint stackNode[CR_BVH_STACK];
  real stackT[CR_BVH_STACK];
  int sp = 0;
  real tEnter;
  if (!Box_Intersect(nodes[0].bmin, nodes[0].bmax, ray, ray->tmin, Cull_Distance(hit->t), &tEnter)) return;
  uint ni = 0;
  for (;;) {
    CR_GLOBAL const BVHNode* n = nodes + ni;
    CR_COUNT(st, nTS);
    if (n->count > 0) {
      CR_COUNT(st, nLeaves);
      const uint end = n->first + n->count;
      for (uint i = n->first; i < end; ++i) {
        CR_COUNT(st, nIT);
        if (Prim_Intersect(pv, refs[i], ray, hit) && anyHit) return;
      }
    } else {
      uint c0 = n->first, c1 = n->first + 1;
      real t0, t1;
      const real cull = Cull_Distance(hit->t);
      int h0 = Box_Intersect(nodes[c0].bmin, nodes[c0].bmax, ray, ray->tmin, cull, &t0);
      int h1 = Box_Intersect(nodes[c1].bmin, nodes[c1].bmax, ray, ray->tmin, cull, &t1);
      if (h0 && h1) {
        if (t1 < t0) {
          uint tc = c0;
          c0 = c1;
          c1 = tc;
          real tt = t0;
          t0 = t1;
          t1 = tt;
        }
        stackNode[sp] = c1;
        stackT[sp] = t1;
        ++sp;
        ni = c0;
        continue;
      }
      if (h0 || h1) {
        ni = h0 ? c0 : c1;
        continue;
      }
    }
    /* Pop the nearest pending node that can still hold a closer hit. */
    for (;;) {
      if (sp == 0) return;
      --sp;
      if (stackT[sp] <= Cull_Distance(hit->t)) {
        ni = stackNode[sp];
        break;
      }
    }
  }
}

#endif /* CR_WITH_BVH */
#endif /* CELLRAY_KERNELS_BVH_H */
