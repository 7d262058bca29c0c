/* Octree traversal: front to back by cell entry and exit parameters, after
 * Revelles, Urena & Lastra 2000, "An efficient parametric algorithm for octree
 * traversal", made robust:
 *  - every parameter comes directly from a cell plane (Octree_Plane, the only
 *    place planes are computed, shared with the builder) through Ray_PlaneT,
 *    never from averages of other parameters, so axis-parallel rays (0 * inf)
 *    and rays in a cell plane are well defined and neighbouring cells share
 *    their boundary parameters bit for bit;
 *  - in Revelles' mirrored space (an axis whose direction has its sign bit set,
 *    -0 included, is flipped: its near plane is the high one) the parameters
 *    t0 <= tm <= t1 of each axis are monotone, so the children of a node tile
 *    its parameter interval with closed intervals, none of them empty;
 *  - the builder inserts a primitive into every cell its exact shape meets
 *    after the cell is grown by a small epsilon, which covers the rounding of
 *    these parameters;
 *  - hits are kept across leaves: a primitive stored in several leaves may be
 *    hit beyond the current leaf's exit; the search stops only when the
 *    closest hit so far lies within the current cell (t <= its exit).
 * With CR_OCTREE_MAILBOX_ON in the header's flags (--octree-mailbox on) the
 * walk keeps a per-ray mailbox, as the hierarchical grid's (kernels/hgrid.h;
 * Amanatides & Woo 1987): a direct-mapped table of CR_OCTREE_MAILBOX entries
 * holds the last primitive tested in each slot, and a reference found there
 * is skipped. Exact: the same ray against the same primitive gives the same
 * answer, which the hit already holds (a hit beyond an earlier leaf is
 * kept), so the answers are the classic walk's with fewer tests (nIT). Off
 * by default: the classic octree is the baseline the study measures.
 * Layout: OctreeHeader and OctreeNode in types.h. Iterative with an explicit
 * stack (OpenCL has no recursion). */
#ifndef CELLRAY_KERNELS_OCTREE_H
#define CELLRAY_KERNELS_OCTREE_H
#include "intersect.h"

/* Compiled unless the build is for one other structure (CR_ACCEL_ONE, see
 * trace.cl); CR_WITH_OCTREE tells the generated dispatch (CR_IF_WITH). */
#if !defined(CR_ACCEL_ONE) || defined(CR_ACCEL_OCTREE)
#define CR_WITH_OCTREE 1
#else
#define CR_WITH_OCTREE 0
#endif
#if CR_WITH_OCTREE

/* Deepest level the builder may create (host/accel/octree_builder.cpp checks
 * --octree-depth against it). Interior nodes lie at levels < this, so it also
 * bounds the traversal stack. Beyond 20 levels a cell (2^-20 of the root) is
 * about as small as the float spacing of the coordinates: deeper cells could
 * not separate anything. */
#define CR_OCTREE_MAX_DEPTH 20

/* Whether the walk keeps its mailbox: the header's flag in C++ (the scalar
 * backend); in OpenCL fixed when the program is built
 * (CR_OCTREE_MAILBOX_BUILD, host/cl/cl_options.cpp, 0 where unset), so the
 * classic walk's programs hold no mailbox (no private array to keep in
 * registers or scratch). */
#if defined(CR_OPENCL)
#ifndef CR_OCTREE_MAILBOX_BUILD
#define CR_OCTREE_MAILBOX_BUILD 0
#endif
#define CR_OCTREE_USE_MAILBOX(hdr) CR_OCTREE_MAILBOX_BUILD
#ifndef CR_OCTREE_MARGIN_BUILD
#define CR_OCTREE_MARGIN_BUILD 0
#endif
#define CR_OCTREE_USE_RAY_MARGIN(hdr) CR_OCTREE_MARGIN_BUILD
/* Leaf boxes come only with the ray's margins: the classic walk's programs
 * hold no box test. */
#define CR_OCTREE_USE_LEAF_BOXES(hdr) (CR_OCTREE_MARGIN_BUILD && ((hdr)->flags & CR_OCTREE_LEAF_BOXES) != 0u)
/* Whether Octree_TraceRay keeps each level's parameters in private arrays
 * (1: the host's choice on a CPU device) or recomputes them from the planes
 * when it climbs back (0: on a GPU, where those arrays are scratch). */
#ifndef CR_OCTREE_KEEP_FRAMES
#define CR_OCTREE_KEEP_FRAMES 1
#endif
#else
/* The scalar backend recomputes (the GPU's form; PoCL's programs keep them,
 * and the tests compare the two bit for bit). */
#ifndef CR_OCTREE_KEEP_FRAMES
#define CR_OCTREE_KEEP_FRAMES 0
#endif
#define CR_OCTREE_USE_MAILBOX(hdr) (((hdr)->flags & CR_OCTREE_MAILBOX_ON) != 0u)
#define CR_OCTREE_USE_RAY_MARGIN(hdr) (((hdr)->flags & CR_OCTREE_MARGIN_RAY) != 0u)
#define CR_OCTREE_USE_LEAF_BOXES(hdr) (((hdr)->flags & CR_OCTREE_LEAF_BOXES) != 0u)
#endif

/* Plane i (0 <= i <= 2^level) of `level` on `axis`:
 * rootMin + i * (rootSize * 2^-level). rootSize * 2^-level is exact, and
 * i * that is the same real number as 2i * (rootSize * 2^-(level+1)), rounded
 * once in both cases, so plane i of a level is plane 2i of the next, bit for
 * bit. Always float, whatever `real` is: the builder and every precision mode
 * see the same planes. */
CR_FUNC float Octree_Plane(CR_GLOBAL const OctreeHeader* hdr, int axis, uint level, uint i)
{
  const float cell = hdr->rootSize * cr_bits_float((127u - level) << 23);
  return hdr->rootMin[axis] + (float)i * cell;
}

/* Mirrored near (t0), mid (tm) and far (t1) parameters, per axis, of the cell
 * at `level` with integer coordinates c. */
CR_FUNC void Octree_CellT(CR_GLOBAL const OctreeHeader* hdr, const Ray* ray, uint signMask, uint level, const uint c[3],
                          real t0[3], real tm[3], real t1[3])
{
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    const real lo = Ray_PlaneT(ray, a, (real)Octree_Plane(hdr, a, level, c[a]));
    const real hi = Ray_PlaneT(ray, a, (real)Octree_Plane(hdr, a, level, c[a] + 1u));
    tm[a] = Ray_PlaneT(ray, a, (real)Octree_Plane(hdr, a, level + 1u, 2u * c[a] + 1u));
    const int neg = (int)((signMask >> a) & 1u);
    t0[a] = neg ? hi : lo;
    t1[a] = neg ? lo : hi;
  }
}

/* Entry and exit parameters of mirrored child m of a node with mirrored
 * parameters t0, tm, t1: bit a of m picks the lower or upper half of axis a. */
CR_FUNC real Octree_ChildEntry(uint m, const real t0[3], const real tm[3])
{
  return fmax(fmax((m & 1u) ? tm[0] : t0[0], (m & 2u) ? tm[1] : t0[1]), (m & 4u) ? tm[2] : t0[2]);
}
CR_FUNC real Octree_ChildExit(uint m, const real tm[3], const real t1[3])
{
  return fmin(fmin((m & 1u) ? t1[0] : tm[0], (m & 2u) ? t1[1] : tm[1]), (m & 4u) ? t1[2] : tm[2]);
}

/* Revelles' first child (mirrored octant) of a node entered at tStart: the
 * bit of an axis is set when its mid plane lies before tStart. */
CR_FUNC uint Octree_FirstChild(const real tm[3], real tStart)
{
  return (tm[0] < tStart ? 1u : 0u) | (tm[1] < tStart ? 2u : 0u) | (tm[2] < tStart ? 4u : 0u);
}

/* The ray's own margin (--octree-margin ray): each parameter Ray_PlaneT
 * computes, (p - o) * inv with p a float plane, lies within 3 roundings of
 * the exact (p - o) / d (4 where a device's 1 / d errs by 2.5 ulps, as
 * OpenCL allows), relative to itself, so the exact parameter lies in
 * [Octree_Lo(t), Octree_Hi(t)]: t moved outward by 8 ulps of float
 * (generous in fp64, where the parameters are doubles) and by the smallest
 * normal float (a parameter that underflows). The bound is the ray's, not
 * the scene's: a ray that starts near a small object gets margins as small
 * as its own rounding there. */
#define CR_OCTREE_WIDEN 0x1.0p-20f
CR_FUNC real Octree_Lo(real t)
{
  return t * (t > (real)0.0f ? (real)(1.0f - CR_OCTREE_WIDEN) : (real)(1.0f + CR_OCTREE_WIDEN)) - (real)0x1.0p-126f;
}
CR_FUNC real Octree_Hi(real t)
{
  return t * (t > (real)0.0f ? (real)(1.0f + CR_OCTREE_WIDEN) : (real)(1.0f - CR_OCTREE_WIDEN)) + (real)0x1.0p-126f;
}

/* Whether the ray enters the box of leaf n (CR_OCTREE_LEAF_BOXES: the union
 * of its primitives' bounds clipped to the cell, in the references before
 * its own) within [tmin, Cull_Distance(hit t)], by the BVH's conservative
 * slab test: a hit on one of the leaf's primitives inside the cell lies in
 * the box, so a ray that misses the box has nothing to find there. */
CR_FUNC int Octree_LeafBoxHit(CR_GLOBAL const OctreeNode* n, CR_GLOBAL const uint* refs, const Ray* ray, real hitT)
{
  real lo[3], hi[3];
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    lo[a] = (real)cr_bits_float(refs[n->first - CR_OCTREE_BOX_WORDS + (uint)a]);
    hi[a] = (real)cr_bits_float(refs[n->first - 3u + (uint)a]);
  }
  real tEnter;
  return Box_Slabs(lo, hi, ray, ray->tmin, Cull_Distance(hitT), &tEnter);
}

/* Tests a leaf's references. Returns 1 when the query is answered: any hit
 * (anyHit), or a closest hit so far that lies within the leaf (t <= tExit).
 * A hit beyond tExit is kept, but a nearer one may lie in a later cell.
 * leafBox: the leaf has a box (CR_OCTREE_LEAF_BOXES), and a ray that misses
 * it tests none of the references (the leaf still counts as visited). */
CR_FUNC int Octree_Leaf(CR_GLOBAL const OctreeNode* n, CR_GLOBAL const uint* refs, const PrimView* pv, const Ray* ray,
                        Hit* hit, int anyHit, real tExit, uint* mailbox, int useMailbox, int leafBox, TraceStats* st)
{
  CR_COUNT(st, nLeaves);
  if (n->count == 0u) CR_COUNT(st, nEmptyLeaves);
  if (leafBox && n->count != 0u && !Octree_LeafBoxHit(n, refs, ray, hit->t)) return hit->t <= tExit ? 1 : 0;
  const uint end = n->first + n->count;
  for (uint i = n->first; i < end; ++i) {
    const uint prim = refs[i];
    if (useMailbox) {
      const uint slot = prim & (CR_OCTREE_MAILBOX - 1u);
      if (mailbox[slot] == prim) continue; /* tested already: same ray, same answer */
      mailbox[slot] = prim;
    }
    CR_COUNT(st, nIT);
    if (Prim_Intersect(pv, prim, ray, hit) && anyHit) return 1;
  }
  return hit->t <= tExit ? 1 : 0;
}

/* The walk with the ray's own margins (--octree-margin ray; the builder
 * then grows cells only by the rounding of its own double tests). The
 * classic walk's sequence of cells relies on the order of the float
 * parameters, which near a cell's edge or corner may differ from the exact
 * order by a sliver; the builder's padding, a part of the scene's size,
 * covers that for every ray, and also stops the subdivision where cells
 * come near the padding's size (a teapot in a stadium). Here every cell
 * takes the interval [Octree_Lo(entry), Octree_Hi(exit)], which holds the
 * exact ray's interval in it whatever the rounding, so no cell the exact
 * ray crosses is skipped, whatever the cells' size. The walk is then a
 * search of the tree, as a BVH's: at each interior node the children whose
 * widened intervals meet [tmin, hit t] (empty octants are not stored and
 * not visited), in increasing mirrored octant, the order in which a ray
 * crosses them (Revelles': each step sets a bit), each child dropped when
 * the closest hit so far lies before its widened entry. Any order would
 * give the same closest hit (a dropped child holds nothing nearer), this
 * one finds it soonest; the SIMD packet walk (simd/octree_packet.h) keeps
 * it lane by lane, so its answers and counts are these. A hit beyond a leaf
 * is kept, as in the classic walk.
 * Counts: nTS nodes visited, nLeaves the leaves among them (empty octants
 * are not visited), nIT primitive tests. Called by Octree_Trace below the
 * root (an interior node), with the root's parameters t0, tm, t1. */
CR_FUNC void Octree_TraceRay(CR_GLOBAL const OctreeHeader* hdr, CR_GLOBAL const OctreeNode* nodes,
                             CR_GLOBAL const uint* refs, const PrimView* pv, const Ray* ray, Hit* hit, int anyHit,
                             uint signMask, real t0[3], real tm[3], real t1[3], uint* mailbox, int useMailbox,
                             TraceStats* st)
{
  const int leafBox = CR_OCTREE_USE_LEAF_BOXES(hdr);
  uint c[3] = {0u, 0u, 0u};
  /* Frame of level L: the node and the children still to visit. With
   * CR_OCTREE_KEEP_FRAMES also the node's parameters fT[9L ..] (t0, tm, t1)
   * and each child's widened entry fEnter[8L + m], kept rather than
   * recomputed from the planes on the way back up (the same values, bit for
   * bit): on PoCL the stadium's primary rays take 35 ms with them, 58
   * without; on a GPU they would be 1.4 KB of scratch per ray (gfx906:
   * 1712-1728 bytes against 336-352), so a GPU's programs recompute. */
  uint fNode[CR_OCTREE_MAX_DEPTH], fTodo[CR_OCTREE_MAX_DEPTH];
#if CR_OCTREE_KEEP_FRAMES
  real fT[9 * CR_OCTREE_MAX_DEPTH], fEnter[8 * CR_OCTREE_MAX_DEPTH];
#endif
  int level = 0;
  uint ni = 0u;
  for (;;) {
    /* Node ni at `level` (coordinates c) with parameters t0, tm, t1. */
    {
#if CR_OCTREE_KEEP_FRAMES
      CR_UNROLL for (int a = 0; a < 3; ++a) {
        fT[9 * level + a] = t0[a];
        fT[9 * level + 3 + a] = tm[a];
        fT[9 * level + 6 + a] = t1[a];
      }
#endif
      CR_GLOBAL const OctreeNode* n = nodes + ni;
      uint todo = 0u;
      CR_UNROLL for (uint m = 0u; m < 8u; ++m) {
        if (((n->childMask >> (m ^ signMask)) & 1u) == 0u) continue;
        const real ce = Octree_Lo(Octree_ChildEntry(m, t0, tm));
        const real cx = Octree_Hi(Octree_ChildExit(m, tm, t1));
        if (fmax(ce, ray->tmin) <= fmin(cx, hit->t)) {
          todo |= 1u << m;
#if CR_OCTREE_KEEP_FRAMES
          fEnter[8 * level + (int)m] = ce;
#endif
        }
      }
      fNode[level] = ni;
      fTodo[level] = todo;
    }
    /* The next child to visit, climbing out of finished nodes. */
    for (;;) {
      const uint todo = fTodo[level];
      if (todo == 0u) {
        if (level == 0) return;
        --level;
        c[0] >>= 1;
        c[1] >>= 1;
        c[2] >>= 1;
#if CR_OCTREE_KEEP_FRAMES
        CR_UNROLL for (int a = 0; a < 3; ++a) {
          t0[a] = fT[9 * level + a];
          tm[a] = fT[9 * level + 3 + a];
          t1[a] = fT[9 * level + 6 + a];
        }
#else
        /* The parameters serve only a level with a child left to visit:
         * climb past the finished ones without them. */
        while (level > 0 && fTodo[level] == 0u) {
          --level;
          c[0] >>= 1;
          c[1] >>= 1;
          c[2] >>= 1;
        }
        if (fTodo[level] == 0u) return;
        Octree_CellT(hdr, ray, signMask, (uint)level, c, t0, tm, t1);
#endif
        continue;
      }
      const uint m = cr_popcount((todo & (0u - todo)) - 1u); /* the lowest: Revelles' order */
      fTodo[level] = todo & (todo - 1u);
      /* Dropped when the closest hit lies before the child's entry. */
#if CR_OCTREE_KEEP_FRAMES
      const real ce = fEnter[8 * level + (int)m];
#else
      const real ce = Octree_Lo(Octree_ChildEntry(m, t0, tm));
#endif
      if (ce > hit->t) continue;
      const uint o = m ^ signMask;
      CR_GLOBAL const OctreeNode* n = nodes + fNode[level];
      const uint ci = n->first + cr_popcount(n->childMask & ((1u << o) - 1u));
      CR_COUNT(st, nTS);
      if (nodes[ci].childMask == 0u) {
        if (Octree_Leaf(nodes + ci, refs, pv, ray, hit, anyHit, -(real)CR_INF, mailbox, useMailbox, leafBox, st))
          return;
        continue;
      }
      /* Descend: the child's near and far planes are the node's. */
      CR_ASSERT(level + 1 < CR_OCTREE_MAX_DEPTH);
      ++level;
      CR_UNROLL for (int a = 0; a < 3; ++a) {
        if ((m >> a) & 1u)
          t0[a] = tm[a];
        else
          t1[a] = tm[a];
        c[a] = 2u * c[a] + ((o >> a) & 1u);
        tm[a] = Ray_PlaneT(ray, a, (real)Octree_Plane(hdr, a, (uint)level + 1u, 2u * c[a] + 1u));
      }
      ni = ci;
      break;
    }
  }
}

/* Closest hit (anyHit = 0) or any hit (anyHit = 1) of the ray against the
 * octree; `hit` must come from Hit_Init. Counts (CR_STATS): nTS nodes visited
 * (interior, leaf and empty octant), nLeaves leaf cells visited (empty
 * octants included), nEmptyLeaves empty ones, nIT primitive tests. */
CR_FUNC void Octree_Trace(CR_GLOBAL const OctreeHeader* hdr, CR_GLOBAL const OctreeNode* nodes,
                          CR_GLOBAL const uint* refs, const PrimView* pv, const Ray* ray, Hit* hit, int anyHit,
                          TraceStats* st)
{
  /* inv = 1/dir keeps the sign bit of dir: -0 gives -inf, so it is mirrored. */
  uint signMask = 0u;
  for (int a = 0; a < 3; ++a)
    if (ray->inv[a] < (real)0.0f) signMask |= 1u << a;

  /* The current interior node: index, level, integer coordinates, and its
   * mirrored plane parameters. The stack holds the ancestors' indices and
   * current children; their coordinates are c >> 1 and their parameters are
   * recomputed from the planes when the traversal climbs back. */
  uint c[3] = {0u, 0u, 0u};
  uint level = 0u;
  real t0[3], tm[3], t1[3];
  Octree_CellT(hdr, ray, signMask, 0u, c, t0, tm, t1);
  const int rayMargin = CR_OCTREE_USE_RAY_MARGIN(hdr);
  real rootEnter = fmax(fmax(t0[0], t0[1]), t0[2]);
  real rootExit = fmin(fmin(t1[0], t1[1]), t1[2]);
  if (rayMargin) {
    rootEnter = Octree_Lo(rootEnter);
    rootExit = Octree_Hi(rootExit);
  }
  if (!(fmax(rootEnter, ray->tmin) <= fmin(rootExit, hit->t))) return;
  CR_COUNT(st, nTS);
  const int useMailbox = CR_OCTREE_USE_MAILBOX(hdr);
  uint mailbox[CR_OCTREE_MAILBOX]; /* read only where useMailbox */
  if (useMailbox)
    CR_UNROLL for (int k = 0; k < CR_OCTREE_MAILBOX; ++k) mailbox[k] = CR_NO_HIT;
  if (nodes[0].childMask == 0u) {
    Octree_Leaf(nodes, refs, pv, ray, hit, anyHit, rayMargin ? -(real)CR_INF : rootExit, mailbox, useMailbox,
                CR_OCTREE_USE_LEAF_BOXES(hdr), st);
    return;
  }
  if (rayMargin) {
    Octree_TraceRay(hdr, nodes, refs, pv, ray, hit, anyHit, signMask, t0, tm, t1, mailbox, useMailbox, st);
    return;
  }
  uint stackNode[CR_OCTREE_MAX_DEPTH];
  uint stackChild[CR_OCTREE_MAX_DEPTH];
  int sp = 0;
  uint ni = 0u;
  uint m = Octree_FirstChild(tm, fmax(rootEnter, ray->tmin)); /* current child, mirrored octant */
  for (;;) {
    /* Child m of node ni spans [ce, cx]. */
    const real ce = Octree_ChildEntry(m, t0, tm);
    const real cx = Octree_ChildExit(m, tm, t1);
    /* Front to back: every later cell starts at or after ce. */
    if (ce > hit->t) return;
    if (ce <= cx && cx >= ray->tmin) {
      const uint o = m ^ signMask;
      CR_GLOBAL const OctreeNode* n = nodes + ni;
      CR_COUNT(st, nTS);
      if (((n->childMask >> o) & 1u) == 0u) {
        /* An empty octant: an empty leaf that is not stored. */
        CR_COUNT(st, nLeaves);
        CR_COUNT(st, nEmptyLeaves);
        if (hit->t <= cx) return;
      } else {
        const uint ci = n->first + cr_popcount(n->childMask & ((1u << o) - 1u));
        if (nodes[ci].childMask == 0u) {
          if (Octree_Leaf(nodes + ci, refs, pv, ray, hit, anyHit, cx, mailbox, useMailbox, 0, st)) return;
        } else {
          /* Descend. The child's near and far planes are planes of the
           * parent (same values, bit for bit); only its mid planes are new. */
          CR_ASSERT(sp < CR_OCTREE_MAX_DEPTH);
          stackNode[sp] = ni;
          stackChild[sp] = m;
          ++sp;
          ++level;
          for (int a = 0; a < 3; ++a) {
            c[a] = 2u * c[a] + ((o >> a) & 1u);
            if ((m >> a) & 1u)
              t0[a] = tm[a];
            else
              t1[a] = tm[a];
            tm[a] = Ray_PlaneT(ray, a, (real)Octree_Plane(hdr, a, level + 1u, 2u * c[a] + 1u));
          }
          ni = ci;
          m = Octree_FirstChild(tm, fmax(ce, ray->tmin));
          continue;
        }
      }
    }
    /* Next child: across the exit plane of child m (the axis of its smallest
     * far parameter). If that bit is already set, the exit plane is the
     * node's own far plane: the ray leaves the node; climb and repeat. */
    for (;;) {
      const real fx = (m & 1u) ? t1[0] : tm[0];
      const real fy = (m & 2u) ? t1[1] : tm[1];
      const real fz = (m & 4u) ? t1[2] : tm[2];
      const uint bit = (fx <= fy) ? (fx <= fz ? 1u : 4u) : (fy <= fz ? 2u : 4u);
      if ((m & bit) == 0u) {
        m |= bit;
        break;
      }
      if (sp == 0) return;
      --sp;
      ni = stackNode[sp];
      m = stackChild[sp];
      --level;
      c[0] >>= 1;
      c[1] >>= 1;
      c[2] >>= 1;
      Octree_CellT(hdr, ray, signMask, level, c, t0, tm, t1);
    }
  }
}

#endif /* CR_WITH_OCTREE */
#endif /* CELLRAY_KERNELS_OCTREE_H */
