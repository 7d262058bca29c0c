/* The CSG solid's leaf records and its classification along a ray (Roth 1982, for convex
 * leaves): given where the ray's line is inside each leaf, the first
 * parameter in [tmin, tmax] where the solid's membership changes. Shared by
 * the kernels (kernels/csg.h, in `real`) and the fp64 reference
 * (host/prims/csg.cpp, which includes it with real = double), so that both
 * follow one rule:
 *  - leaf i is inside over [t0[i], t1[i]] (a closed span; `live` holds the
 *    leaves whose span reaches [tmin, tmax], `mask` those inside just
 *    before tmin);
 *  - just after an event time te, leaf i is inside when t0 <= te < t1; the
 *    events at one te are taken together, so coincident faces that cancel
 *    (a union's shared face, a difference's flush cut) are no surface;
 *  - the hit names the lowest leaf with an event at te whose own crossing
 *    changes the solid there (else the lowest leaf with an event at te),
 *    and *flip says that its outward normal points into the solid there
 *    (the subtrahend of a difference). */
#ifndef CELLRAY_KERNELS_CSG_SWEEP_H
#define CELLRAY_KERNELS_CSG_SWEEP_H
#include "ray.h"

/* The leaves' records in the words, from word w on: a sphere in one word;
 * a box in two (lo, hi); a quadric in four (its 16 floats in order); a
 * polyhedron in three (centre and plane count, lo, hi) and one per plane. */
CR_FUNC void Csg_Sphere(const Csg* c, uint w, Sphere* s)
{
  CR_UNROLL for (int a = 0; a < 3; ++a) s->center[a] = c->word[w][a];
  s->radius = c->word[w][3];
}
CR_FUNC void Csg_Box(const Csg* c, uint w, Box* b)
{
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    b->lo[a] = c->word[w][a];
    b->hi[a] = c->word[w + 1u][a];
  }
  b->pad0 = b->pad1 = 0u;
}
CR_FUNC void Csg_Quadric(const Csg* c, uint w, Quadric* q)
{
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    q->center[a] = c->word[w][a];
    q->extent[a] = c->word[w + 1u][a];
    q->l[a] = c->word[w + 3u][a + 1];
  }
  q->j = c->word[w][3];
  q->q[0] = c->word[w + 1u][3];
  CR_UNROLL for (int a = 0; a < 4; ++a) q->q[a + 1] = c->word[w + 2u][a];
  q->q[5] = c->word[w + 3u][0];
}
CR_FUNC void Csg_Polyhedron(const Csg* c, uint w, Polyhedron* p)
{
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    p->center[a] = c->word[w][a];
    p->lo[a] = c->word[w + 1u][a];
    p->hi[a] = c->word[w + 2u][a];
  }
  p->count = (uint)c->word[w][3];
  p->pad0 = p->pad1 = 0u;
  for (uint k = 0u; k < p->count; ++k) CR_UNROLL for (int a = 0; a < 4; ++a) p->plane[k][a] = c->word[w + 3u + k][a];
}

/* Node k of the postfix expression. */
CR_FUNC uint Csg_Node(const Csg* c, uint k) { return (c->node[k >> 2] >> ((k & 3u) * 8u)) & 255u; }

/* The solid's membership for the leaves' memberships `mask` (bit i: leaf
 * i): the postfix expression on a stack of bits (at most 32 deep: one per
 * leaf). */
CR_FUNC uint Csg_Eval(const Csg* c, uint mask)
{
  uint st = 0u;
  for (uint k = 0u; k < c->nNodes; ++k) {
    const uint n = Csg_Node(c, k);
    if (n < CR_CSG_UNION) {
      st = (st << 1) | ((mask >> n) & 1u);
    } else {
      const uint b = st & 1u, a = (st >> 1) & 1u;
      const uint x = n == CR_CSG_UNION ? (a | b) : n == CR_CSG_INTERSECTION ? (a & b) : (a & (b ^ 1u));
      st = ((st >> 2) << 1) | x;
    }
  }
  return st & 1u;
}

CR_FUNC int Csg_Sweep(const Csg* c, const real* t0, const real* t1, uint live, uint mask, real tmin, real tmax,
                      real* tHit, uint* leaf, uint* flip)
{
  uint inside = Csg_Eval(c, mask);
  real after = tmin; /* events at or after tmin first, then strictly after the last */
  int strict = 0;
  for (uint round = 0u; round <= 2u * CR_CSG_MAX_LEAVES; ++round) {
    real te = (real)CR_INF;
    for (uint bits = live; bits != 0u; bits &= bits - 1u) {
      const uint i = cr_popcount((bits & (0u - bits)) - 1u);
      const real a = t0[i], b = t1[i];
      if (strict ? a > after : a >= after) te = fmin(te, a);
      if (strict ? b > after : b >= after) te = fmin(te, b);
    }
    if (!(te <= tmax)) return 0;
    uint now = 0u, at = 0u;
    for (uint bits = live; bits != 0u; bits &= bits - 1u) {
      const uint i = cr_popcount((bits & (0u - bits)) - 1u);
      if (t0[i] <= te && te < t1[i]) now |= 1u << i;
      if (t0[i] == te || t1[i] == te) at |= 1u << i;
    }
    const uint solid = Csg_Eval(c, now);
    if (solid != inside) {
      uint pick = at & (0u - at);
      for (uint bits = at; bits != 0u; bits &= bits - 1u) {
        const uint b = bits & (0u - bits);
        if (Csg_Eval(c, mask ^ b) != inside) {
          pick = b;
          break;
        }
      }
      const uint i = cr_popcount(pick - 1u);
      *tHit = te;
      *leaf = i;
      /* The leaf is entered here (t0) or left (t1); its outward normal
       * faces the ray where it is entered, the solid's where the solid is. */
      *flip = (t0[i] == te ? 1u : 0u) != solid ? 1u : 0u;
      return 1;
    }
    inside = solid;
    mask = now;
    after = te;
    strict = 1;
  }
  return 0;
}

#endif /* CELLRAY_KERNELS_CSG_SWEEP_H */
