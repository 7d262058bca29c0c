/* Two-level grid (Jevans & Wyvill 1989, "Adaptive voxel subdivision for ray
 * tracing"; Kalojanov, Billeter & Slusallek 2011, "Two-Level Grids for Ray
 * Tracing on GPUs"): a coarse uniform grid whose every cell holds a uniform
 * grid of its own, with as many cells as the cell's references ask for
 * (host/accel/grid2_builder.cpp). Empty space costs one coarse step; a
 * teapot in a stadium gets fine cells only where the teapot is.
 *
 * Layout (kernels/types.h CR_ACCEL_TYPES: header GridHeader, nodes
 * GridHeader):
 *  - the header is the top grid: res, planes and box as a uniform grid's,
 *    nCells top cells, nRefs the references of all sub-grids (0: nothing to
 *    trace);
 *  - nodes[i] is top cell i's sub-grid, a GridHeader whose first planes are
 *    the top cell's lower planes, bit for bit, and whose last planes lie at or
 *    just past its upper planes (the builder rounds the cell size up), so the
 *    sub-grids cover the top grid without a gap. nRefs 0 marks an empty top
 *    cell. Its cell offsets are refs[first .. first + nCells], absolute
 *    indices into refs;
 *  - refs holds every sub-grid's cell offsets, then the references, sorted
 *    ascending in each cell.
 *
 * Both levels are walked by the 3D-DDA of kernels/grid.h with its robustness
 * rules (planes recomputed, never accumulated; first cell corrected to the
 * plane parameters); the builder inserts a primitive into every top cell and
 * every sub-cell it meets, each grown by the uniform grid's epsilon. A
 * sub-grid's walk starts at the parameter where the top walk entered its
 * cell (Grid_EnterAt: no second box test) and ends where the ray leaves the
 * sub-grid or where the closest hit so far lies within the current sub-cell;
 * the top walk then goes on unless that hit lies within the top cell. A hit
 * beyond the cell (a primitive spanning cells) is kept while the walk goes
 * on, as in the uniform grid.
 *
 * Counts (CR_STATS): nTS top cells and sub-cells visited, nLeaves sub-cells
 * and empty top cells, nEmptyLeaves the empty ones, nIT primitive tests. */
#ifndef CELLRAY_KERNELS_GRID2_H
#define CELLRAY_KERNELS_GRID2_H
#include "grid.h"

/* Compiled unless the build is for one other structure (CR_ACCEL_ONE, see
 * trace.cl); CR_WITH_GRID2 tells the generated dispatch (CR_IF_WITH). */
#if !defined(CR_ACCEL_ONE) || defined(CR_ACCEL_GRID2)
#define CR_WITH_GRID2 1
#else
#define CR_WITH_GRID2 0
#endif
#if CR_WITH_GRID2

/* Closest hit (anyHit = 0) or any hit (anyHit = 1) of the ray against the
 * two-level grid; `hit` must come from Hit_Init. */
CR_FUNC void Grid2_Trace(CR_GLOBAL const GridHeader* top, CR_GLOBAL const GridHeader* subs, CR_GLOBAL const uint* refs,
                         const PrimView* pv, const Ray* ray, Hit* hit, int anyHit, TraceStats* st)
{
  if (top->nRefs == 0u) return;
  int cell[3];
  real tEnter;
  if (!Grid_EnterT(top, ray, hit->t, cell, &tEnter)) return;
  for (;;) {
    CR_COUNT(st, nTS);
    CR_GLOBAL const GridHeader* sub = subs + Grid_CellIndex(top, cell);
    if (sub->nRefs == 0u) {
      CR_COUNT(st, nLeaves);
      CR_COUNT(st, nEmptyLeaves);
    } else {
      int subCell[3];
      Grid_EnterAt(sub, ray, tEnter, subCell);
      if (Grid_Walk(sub, refs + sub->first, refs, pv, ray, hit, anyHit, subCell, st)) return;
    }
    if (!Grid_Step(top, ray, hit->t, cell, &tEnter)) return;
  }
}

#endif /* CR_WITH_GRID2 */
#endif /* CELLRAY_KERNELS_GRID2_H */
