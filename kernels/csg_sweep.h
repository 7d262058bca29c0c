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

/* A folded expression's extra operator: the complement of the top. */
#define CR_CSG_NOT 67u

/* The solid's membership for the leaves' memberships `mask` (bit i: leaf
 * i), by a program of Csg_Fold (n nodes of prog): the postfix expression on
 * a stack of bits (at most 32 deep: one per leaf). */
CR_FUNC uint Csg_EvalProgram(const uint* prog, uint n, uint mask)
{
  uint st = 0u;
  for (uint k = 0u; k < n; ++k) {
    const uint x = prog[k];
    if (x < CR_CSG_UNION) {
      st = (st << 1) | ((mask >> x) & 1u);
    } else if (x == CR_CSG_NOT) {
      st ^= 1u;
    } else {
      const uint b = st & 1u, a = (st >> 1) & 1u;
      const uint y = x == CR_CSG_UNION ? (a | b) : x == CR_CSG_INTERSECTION ? (a & b) : (a & (b ^ 1u));
      st = ((st >> 2) << 1) | y;
    }
  }
  return st & 1u;
}

/* The expression with the leaves that do not change over the ray's range
 * folded into constants: the `live` leaves keep their nodes, every other
 * leaf is inside there when its bit of `inside` is set. A ray that meets
 * two pips of a die's 21 classifies against a handful of nodes instead of
 * 45. Writes the program (at most CR_CSG_MAX_NODES nodes) and returns its
 * length; 0 when the whole expression is constant over the range (no
 * crossing there). */
CR_FUNC uint Csg_Fold(const Csg* c, uint live, uint inside, uint* prog)
{
  uint kind[CR_CSG_MAX_LEAVES]; /* 0, 1: a constant; 2: code from start[] on */
  uint start[CR_CSG_MAX_LEAVES];
  uint n = 0u, sp = 0u;
  for (uint k = 0u; k < c->nNodes; ++k) {
    const uint x = Csg_Node(c, k);
    if (x < CR_CSG_UNION) {
      kind[sp] = (live >> x) & 1u ? 2u : (inside >> x) & 1u;
      start[sp] = n;
      if (kind[sp] == 2u) prog[n++] = x;
      ++sp;
      continue;
    }
    --sp;
    const uint ka = kind[sp - 1u], kb = kind[sp], sa = start[sp - 1u], sb = start[sp];
    if (ka == 2u && kb == 2u) {
      prog[n++] = x;
    } else if (kb != 2u) {
      /* a op constant: a itself (a | 0, a & 1, a - 0), or a constant. */
      const int keep = x == CR_CSG_INTERSECTION ? kb == 1u : kb == 0u;
      if (!keep) {
        n = sa;
        kind[sp - 1u] = x == CR_CSG_UNION ? 1u : 0u;
      }
    } else {
      /* constant op b: b (0 | b, 1 & b), its complement (1 - b), or a
       * constant. */
      start[sp - 1u] = sb;
      if (x == CR_CSG_UNION ? ka == 1u : ka == 0u) {
        n = sb;
        kind[sp - 1u] = ka;
      } else {
        kind[sp - 1u] = 2u;
        if (x == CR_CSG_DIFFERENCE) prog[n++] = CR_CSG_NOT;
      }
    }
  }
  return kind[0] == 2u ? n : 0u;
}

/* The first crossing in [tmin, tmax] of the folded program prog (n nodes). */
CR_FUNC int Csg_Sweep(const uint* prog, uint n, const real* t0, const real* t1, uint live, uint mask, real tmin,
                      real tmax, real* tHit, uint* leaf, uint* flip)
{
  uint inside = Csg_EvalProgram(prog, n, mask);
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
    const uint solid = Csg_EvalProgram(prog, n, now);
    if (solid != inside) {
      uint pick = at & (0u - at);
      for (uint bits = at; bits != 0u; bits &= bits - 1u) {
        const uint b = bits & (0u - bits);
        if (Csg_EvalProgram(prog, n, mask ^ b) != inside) {
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

/* The classification of a ray whose line meets leaf i over [t0[i], t1[i]]
 * where bit i of `met` is set: the leaves with a crossing in [tmin, tmax]
 * are live, those spanning the whole range constants inside, the rest
 * constants outside; the expression folded; the sweep. */
CR_FUNC int Csg_Classify(const Csg* c, const real* t0, const real* t1, uint met, real tmin, real tmax, real* tHit,
                         uint* leaf, uint* flip)
{
  uint live = 0u, whole = 0u, mask = 0u;
  for (uint bits = met; bits != 0u; bits &= bits - 1u) {
    const uint b = bits & (0u - bits);
    const uint i = cr_popcount(b - 1u);
    if (t1[i] < tmin || t0[i] > tmax) continue;
    if (t0[i] < tmin && t1[i] > tmax) {
      whole |= b;
      continue;
    }
    live |= b;
    if (t0[i] < tmin) mask |= b;
  }
  uint prog[CR_CSG_MAX_NODES];
  const uint n = Csg_Fold(c, live, whole, prog);
  if (n == 0u) return 0;
  return Csg_Sweep(prog, n, t0, t1, live, mask, tmin, tmax, tHit, leaf, flip);
}

#endif /* CELLRAY_KERNELS_CSG_SWEEP_H */
