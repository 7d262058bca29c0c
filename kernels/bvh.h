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

#if defined(CR_BVH_STACKLESS)
/* The stackless walk (Hapala, Davidovic, Wald, Havran & Slusallek, "Efficient
 * Stack-less BVH Traversal for Ray Tracing", SCCG 2011): a depth-first walk
 * that keeps no stack, only the node it is at and how it got there, and
 * finds its way on through each node's parent (refs[hdr->parents + node],
 * host/accel/bvh_builder.cpp AddBVHParents) and sibling (children come in
 * pairs). A GPU keeps its state in registers: the stack walk's 64 entries
 * live in private memory (scratch; docs/OPENCL.md). Each node's box is tested
 * as it is entered, with the cull distance of that moment (the order differs
 * from the stack walk's, which sorts children by entry distance, so the two
 * may visit different nodes; the answers are the same); the nearer child goes first, by
 * the children's centres along the ray: the same answer at every visit of
 * a node, which the way back up relies on. Selected by --variant stackless. */
CR_FUNC uint BVH_NearChild(CR_GLOBAL const BVHNode* nodes, uint first, const Ray* ray)
{
  CR_GLOBAL const BVHNode* a = nodes + first;
  CR_GLOBAL const BVHNode* b = a + 1;
  real d = 0;
  CR_UNROLL for (int k = 0; k < 3; ++k)
    d += ray->dir[k] * (real)((b->bmin[k] + b->bmax[k]) - (a->bmin[k] + a->bmax[k]));
  return d < 0 ? first + 1 : first;
}

#define CR_BVH_FROM_PARENT 0  /* entering the nearer child */
#define CR_BVH_FROM_SIBLING 1 /* entering the farther child, the nearer one done */
#define CR_BVH_FROM_CHILD 2   /* leaving a node whose subtree is done */

CR_FUNC void BVH_Trace(CR_GLOBAL const BVHHeader* hdr, CR_GLOBAL const BVHNode* nodes, CR_GLOBAL const uint* refs,
                       const PrimView* pv, const Ray* ray, Hit* hit, int anyHit, TraceStats* st)
{
  CR_GLOBAL const uint* parent = refs + hdr->parents;
  /* The root enters as a farther child: once done, the walk is at node 0
   * coming from a child, which ends it. */
  uint ni = 0, first = 0;
  int from = CR_BVH_FROM_SIBLING;
  for (;;) {
    if (from == CR_BVH_FROM_CHILD) {
      if (ni == 0) return;
      first = nodes[parent[ni]].first;
      if (ni == BVH_NearChild(nodes, first, ray)) {
        ni = first + (ni == first);
        from = CR_BVH_FROM_SIBLING;
      } else {
        ni = parent[ni];
      }
      continue;
    }
    CR_GLOBAL const BVHNode* n = nodes + ni;
    real t;
    if (Box_Intersect(n->bmin, n->bmax, ray, ray->tmin, Cull_Distance(hit->t), &t)) {
      CR_COUNT(st, nTS);
      if (n->count == 0) {
        first = n->first;
        ni = BVH_NearChild(nodes, first, ray);
        from = CR_BVH_FROM_PARENT;
        continue;
      }
      CR_COUNT(st, nLeaves);
      const uint end = n->first + n->count;
      for (uint i = n->first; i < end; ++i) {
        CR_COUNT(st, nIT);
        if (Prim_Intersect(pv, refs[i], ray, hit) && anyHit) return;
      }
    }
    /* ni is done: on to its sibling if it was the nearer child, else up. */
    if (from == CR_BVH_FROM_PARENT) {
      ni = first + (ni == first);
      from = CR_BVH_FROM_SIBLING;
    } else {
      from = CR_BVH_FROM_CHILD;
    }
  }
}

#elif defined(CR_BVH_WIDE)
/* The wide walk of CPU devices (OpenCL only; --variant wide). */
#include "bvh_wide.cl"

#else /* the stack walk */

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
#endif /* CR_BVH_STACKLESS */

#endif /* CR_WITH_BVH */
#endif /* CELLRAY_KERNELS_BVH_H */
