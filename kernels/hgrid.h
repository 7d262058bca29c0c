/* Hierarchical grid (Jevans & Wyvill 1989, "Adaptive voxel subdivision for
 * ray tracing"; its two-level form: Kalojanov, Billeter & Slusallek 2011,
 * "Two-Level Grids for Ray Tracing on GPUs"): a uniform grid whose crowded
 * cells hold uniform grids of their own, sized by their reference counts,
 * down to CR_HGRID_MAX_DEPTH levels below the root
 * (host/accel/hgrid_builder.cpp). Empty space costs one coarse step; a
 * teapot in a stadium gets fine cells only where the teapot is.
 *
 * Layout (kernels/types.h CR_ACCEL_TYPES: header GridHeader, nodes
 * GridHeader):
 *  - the header is the root grid, the nodes the child grids, each a
 *    GridHeader with res, planes and box as a uniform grid's, nRefs the
 *    references below it (the header's 0: nothing to trace), `first` the
 *    index in refs of its nCells + 1 cell offsets (absolute indices into
 *    refs), and `margin` the distance by which its cells took their
 *    references;
 *  - a cell holds either references (sorted ascending), or a child marker
 *    CR_HGRID_CHILD | k, the number n of the cell's references, those n
 *    (ascending), then the cell's large references (ascending, some of the
 *    n): the cell holds child grid nodes[k], over the box of the cell's
 *    other references within the cell grown by half the cell's margin (a
 *    teapot's box in the cell of a stadium that also holds its ground), with
 *    the large ones (a ground, a wall: the builder's IsLargeIn) left to the
 *    cell, or over all the n where that is cheaper
 *    (host/accel/hgrid_builder.cpp).
 *
 * Every level is walked by the 3D-DDA of kernels/grid.h with its robustness
 * rules (planes recomputed, never accumulated; first cell corrected to the
 * plane parameters). Near an edge or corner of a cell, the float crossing
 * parameters may order two planes wrongly, and the walk then skips a sliver
 * of a neighbour that the exact ray crosses. Each crossing parameter
 * (p - o) * inv is within 3 ulps of the exact one, so the sliver lies
 * within 6 ulps of the distance travelled, t * max|d|, of the cells the walk
 * visits: a walk is conservative where the cells took their references
 * with a margin at least that (HGrid_Reach, with 8 ulps). That is a bound
 * of the ray, not of the scene: a ray traced from near a teapot strays by
 * a millionth of the teapot, one from across the stadium by a millionth of
 * the stadium. So the root takes its references with the uniform grid's
 * epsilon (relative to the scene's size: every ray that starts within a few
 * scene sizes), and each child grid with a margin of its own, a small part
 * of its cells (host/accel/hgrid_builder.cpp): the walk descends into a
 * child only where the ray's reach at the cell's exit is within the
 * child's margin, and otherwise tests the cell's own references, which the
 * parent took with its larger margin. Fine cells serve the rays that come
 * near, and no ray walks cells finer than its own precision.
 *
 * A ray precise enough for a child tests the cell's large references, then
 * meets the child's box by the conservative slab test (Box_Intersect, from
 * the cell's entry up to the closest hit's Cull_Distance) and walks the
 * child from where it enters the box (Grid_EnterAt at that parameter,
 * clamped to the child's cells); a ray that misses the box skips the child.
 * When the walk steps out of the child, the parent's walk goes on from the
 * cell. The walk ends when the closest hit so far lies at or before the
 * current cell's exit (at any level: a child's box reaches beyond its cell
 * by less than the parent's margin, by which the parent's cell took its
 * references, and the cell's large references were tested before, so
 * nothing beyond the cell is missed; the child took every other reference
 * of the cell within its box, and those lie in the box wherever they meet
 * the cell grown by the child's margin, which is at most half the
 * parent's), or when it leaves the root. A hit beyond the cell (a
 * primitive spanning cells) is kept while the walk goes on, as in the
 * uniform grid.
 *
 * Empty space is skipped by distance (Cohen & Sheffer 1994, "Proximity
 * clouds"; the macro-regions of Devillers 1989): after each grid's cell
 * offsets, one byte per cell (four to a uint, the first cell in the lowest
 * byte) holds an empty cell's distance d to the nearest cell that is not
 * (child cells count as full), in cells, max norm, at most 255; 0 in a full
 * cell. Every cell within d - 1 of an empty cell is empty, so where d >= 2
 * the walk jumps to where the ray leaves that box of (2d - 1)^3 cells: the
 * smallest of its three exit planes' parameters, T, each computed as the
 * walk computes it (Grid_Plane, Ray_PlaneT), so the cells the DDA would
 * visit before T are the box's, all empty. The walk goes on in the cell
 * across that plane (on the other two axes, Grid_EnterAt's cell at T), or
 * leaves the grid there, or ends when the closest hit so far lies at or
 * before T, exactly as the DDA reaching T would. Where T is not past the
 * cell's entry (a ray lying in a plane), it takes the ordinary step. A
 * builder that skips nothing writes 0 or 1 everywhere (--hgrid-skip off).
 *
 * A primitive that spans cells is tested once per ray, not once per cell
 * (mailboxing: Amanatides & Woo 1987, "A fast voxel traversal algorithm";
 * here per ray, as Kalojanov et al. do on GPUs): a direct-mapped table of
 * CR_HGRID_MAILBOX entries keeps the last primitive tested in each slot
 * (index = primitive & (CR_HGRID_MAILBOX - 1)), and a reference found there
 * is skipped. Skipping is exact: the same ray against the same primitive
 * gives the same answer, which the hit already holds (a hit beyond the
 * cell is kept). The SIMD walks filter each cell's references through the
 * same table before testing them (4 at a time, or one primitive on the
 * packet's lanes that stand in the cell), so all test the same primitives
 * and count the same nIT. On the teapot in a stadium it cuts the
 * tests per ray from 8.4 to 5.0 (primary) and from 12.3 to 4.8 (diffuse):
 * its ground and walls lie in many cells.
 *
 * Counts (CR_STATS): nTS cells visited at every level, nLeaves cells whose
 * references the walk tests (or that hold none; a child cell where the ray
 * descends counts where it has large references), nEmptyLeaves the empty
 * ones, nIT primitive tests. */
#ifndef CELLRAY_KERNELS_HGRID_H
#define CELLRAY_KERNELS_HGRID_H
#include "grid.h"

/* Compiled unless the build is for one other structure (CR_ACCEL_ONE, see
 * trace.cl); CR_WITH_HGRID tells the generated dispatch (CR_IF_WITH). */
#if !defined(CR_ACCEL_ONE) || defined(CR_ACCEL_HGRID)
#define CR_WITH_HGRID 1
#else
#define CR_WITH_HGRID 0
#endif

#if CR_WITH_HGRID

/* How far a float walk of the ray may stray from the exact ray up to
 * parameter t: CR_HGRID_RAY_ERR (8 float ulps) of the distance travelled,
 * per coordinate. */
CR_FUNC real HGrid_Reach(const Ray* ray, real t)
{
  const real d = fmax(fabs(ray->dir[0]), fmax(fabs(ray->dir[1]), fabs(ray->dir[2])));
  return (real)CR_HGRID_RAY_ERR * d * t;
}

/* The distance byte of cell idx of a grid whose cell offsets are cellStart. */
CR_FUNC uint HGrid_Distance(CR_GLOBAL const GridHeader* g, CR_GLOBAL const uint* cellStart, uint idx)
{
  return (cellStart[g->nCells + 1u + (idx >> 2)] >> ((idx & 3u) * 8u)) & 0xffu;
}

/* The jump from empty cell `cell`, entered at *tEnter, whose cells within
 * d - 1 are all empty (d >= 2): 2 where the ray's box exit is not past
 * *tEnter (take the ordinary step), else *tEnter = the exit T and 1 with
 * `cell` moved across the exit plane, or 0 where the walk of this grid ends
 * there (the closest hit so far at or before T, or the grid's face). */
CR_FUNC int HGrid_Skip(CR_GLOBAL const GridHeader* g, const Ray* ray, real hitT, int d, int cell[3], real* tEnter)
{
  int axis = 0;
  int last = 0;
  real t = (real)CR_INF;
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    const int res = (int)g->res[a];
    const int up = ray->inv[a] < (real)0.0f ? 0 : 1;
    const int b = up ? cr_min(cell[a] + d - 1, res - 1) : cr_max(cell[a] - d + 1, 0);
    const real ta = Ray_PlaneT(ray, a, Grid_Plane(g, a, up ? b + 1 : b));
    if (ta < t) {
      t = ta;
      axis = a;
      last = b;
    }
  }
  if (!(t > *tEnter)) return 2;
  *tEnter = t;
  if (hitT <= t) return 0;
  const int next = last + (CR_PICK3(ray->inv, axis) < (real)0.0f ? -1 : 1);
  if (next < 0 || next >= (int)CR_PICK3(g->res, axis)) return 0;
  Grid_EnterAt(g, ray, t, cell);
  CR_UNROLL for (int a = 0; a < 3; ++a) if (a == axis) cell[a] = next;
  return 1;
}

/* Closest hit (anyHit = 0) or any hit (anyHit = 1) of the ray against the
 * hierarchical grid; `hit` must come from Hit_Init. */
CR_FUNC void HGrid_Trace(CR_GLOBAL const GridHeader* root, CR_GLOBAL const GridHeader* subs, CR_GLOBAL const uint* refs,
                         const PrimView* pv, const Ray* ray, Hit* hit, int anyHit, TraceStats* st)
{
  if (root->nRefs == 0u) return;
  int cell[3];
  real tEnter;
  if (!Grid_EnterT(root, ray, hit->t, cell, &tEnter)) return;
  /* The ancestors of the grid walked: their grids (node index, or
   * CR_NO_HIT for the root) and current cells. */
  uint stackGrid[CR_HGRID_MAX_DEPTH];
  int stackCell[3 * CR_HGRID_MAX_DEPTH];
  int sp = 0;
  uint gi = CR_NO_HIT;
  CR_GLOBAL const GridHeader* g = root;
  uint mailbox[CR_HGRID_MAILBOX];
  CR_UNROLL for (int k = 0; k < CR_HGRID_MAILBOX; ++k) mailbox[k] = CR_NO_HIT;
  for (;;) {
    /* Cell `cell` of grid g, entered at tEnter. */
    CR_COUNT(st, nTS);
    CR_GLOBAL const uint* cellStart = refs + g->first;
    const uint idx = Grid_CellIndex(g, cell);
    uint begin = cellStart[idx];
    uint end = cellStart[idx + 1u];
    uint child = CR_NO_HIT; /* the child grid the walk descends into after the cell's large references */
    if (begin != end && (refs[begin] & CR_HGRID_CHILD) != 0u) {
      const uint k = refs[begin] & ~CR_HGRID_CHILD;
      const uint nAll = refs[begin + 1u];
      int exitAxis;
      begin += 2u;
      if (HGrid_Reach(ray, Grid_CellExit(g, ray, cell, &exitAxis)) <= (real)subs[k].margin) {
        child = k;
        begin += nAll; /* the large references */
      } else {
        end = begin + nAll; /* the child is finer than the ray's precision: all the cell's references */
      }
    }
    int moved = 2;
    if (child == CR_NO_HIT || begin != end) {
      CR_COUNT(st, nLeaves);
      if (begin == end) {
        CR_COUNT(st, nEmptyLeaves);
        const uint d = HGrid_Distance(g, cellStart, idx);
        if (d >= (uint)CR_HGRID_SKIP_MIN) moved = HGrid_Skip(g, ray, hit->t, (int)d, cell, &tEnter);
      }
      for (uint i = begin; i < end; ++i) {
        const uint prim = refs[i];
        if (mailbox[prim & (CR_HGRID_MAILBOX - 1u)] == prim) continue; /* tested already: same ray, same answer */
        mailbox[prim & (CR_HGRID_MAILBOX - 1u)] = prim;
        CR_COUNT(st, nIT);
        if (Prim_Intersect(pv, prim, ray, hit) && anyHit) return;
      }
    }
    /* Into the child where the ray meets its box (the conservative slab
     * test, up to the closest hit's Cull_Distance), from where it enters. */
    real tBox;
    if (child != CR_NO_HIT &&
        Box_Intersect(subs[child].bmin, subs[child].bmax, ray, tEnter, Cull_Distance(hit->t), &tBox)) {
      CR_ASSERT(sp < CR_HGRID_MAX_DEPTH);
      stackGrid[sp] = gi;
      CR_UNROLL for (int a = 0; a < 3; ++a) stackCell[3 * sp + a] = cell[a];
      ++sp;
      gi = child;
      g = subs + gi;
      tEnter = tBox;
      Grid_EnterAt(g, ray, tEnter, cell);
      continue;
    }
    /* On to the next cell: of this grid, or, where the walk leaves it, of
     * the nearest ancestor it does not leave. */
    if (moved == 2) moved = Grid_Step(g, ray, hit->t, cell, &tEnter);
    while (!moved) {
      if (hit->t <= tEnter || sp == 0) return;
      --sp;
      gi = stackGrid[sp];
      g = gi == CR_NO_HIT ? root : subs + gi;
      CR_UNROLL for (int a = 0; a < 3; ++a) cell[a] = stackCell[3 * sp + a];
      moved = Grid_Step(g, ray, hit->t, cell, &tEnter);
    }
  }
}

#endif /* CR_WITH_HGRID */
#endif /* CELLRAY_KERNELS_HGRID_H */
