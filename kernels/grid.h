/* Uniform grid traversal: 3D-DDA (Amanatides & Woo 1987, "A Fast Voxel
 * Traversal Algorithm for Ray Tracing"; Hearn & Baker, Computer Graphics,
 * section 14-6, cell entry and exit). Layout: GridHeader in types.h.
 *
 * Robustness rules, which keep it exact in float:
 *  - the crossing parameter of a cell plane is recomputed from the plane
 *    (Grid_Plane) at every step, never accumulated, so a long walk does not
 *    drift, and the builder inserted primitives against the same planes;
 *  - the first cell is corrected until its entry planes lie at or before the
 *    entry parameter and its exit planes at or after it, so the walk agrees
 *    with the plane parameters from the start;
 *  - a direction component +-0 gives inv = +-inf: the ray never crosses that
 *    axis's planes, except a plane it lies in, which Ray_PlaneT puts at t = 0
 *    (the walk then steps off it at once, towards the sign of the zero);
 *  - hits: the closest hit over all cells so far is kept (Prim_Intersect),
 *    and the walk stops only when it is at or before the current cell's exit
 *    parameter; a hit beyond the exit (a primitive spanning several cells)
 *    is kept while the walk goes on, since a later cell may hold a nearer one.
 * Steps in x, y, z are monotone, so the walk ends after at most
 * res[0] + res[1] + res[2] cells. */
#ifndef CELLRAY_KERNELS_GRID_H
#define CELLRAY_KERNELS_GRID_H
#include "intersect.h"

/* Compiled unless the build is for one other structure (CR_ACCEL_ONE, see
 * trace.cl); CR_WITH_GRID tells the generated dispatch (CR_IF_WITH). */
#if !defined(CR_ACCEL_ONE) || defined(CR_ACCEL_GRID)
#define CR_WITH_GRID 1
#else
#define CR_WITH_GRID 0
#endif
/* The walk's pieces (Grid_Plane .. Grid_Step) also serve every level of the
 * hierarchical grid (kernels/hgrid.h); Grid_Next and Grid_Walk are the
 * uniform grid's own. */
#if CR_WITH_GRID || defined(CR_ACCEL_HGRID)

/* Plane i (0..res[axis]) of the grid along `axis`. Computed in float in every
 * precision mode: the builder (host/accel/grid_builder.cpp) and the fp32 and
 * fp64 traversals all see the same planes, to the bit. The grid box is
 * [Grid_Plane(0), Grid_Plane(res)] on each axis (the builder stores it as
 * bmin, bmax). */
CR_FUNC real Grid_Plane(CR_GLOBAL const GridHeader* g, int axis, int i)
{
  const float p = g->bmin[axis] + (float)i * g->cellSize[axis];
  return (real)p;
}

/* The cell of the grid the ray is in at parameter tEnter, a parameter at
 * which it lies in the grid box (up to rounding): the first guess from the
 * point there, then corrected until it is consistent with the plane
 * parameters the walk uses (its entry planes at or before tEnter, its exit
 * planes at or after it, where the grid's bounds allow). */
CR_FUNC void Grid_EnterAt(CR_GLOBAL const GridHeader* grid, const Ray* ray, real tEnter, int cell[3])
{
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    const int res = (int)grid->res[a];
    /* First guess from the entry point (the conservative box test may put it
     * slightly outside the box: clamp before converting to int). */
    const real p = ray->org[a] + tEnter * ray->dir[a];
    real rel = (p - Grid_Plane(grid, a, 0)) / (real)grid->cellSize[a];
    rel = fmin(fmax(rel, (real)0.0f), (real)(res - 1));
    int c = (int)floor(rel);
    /* Then make it consistent with the plane parameters the walk uses. The
     * sign of inv, not of dir, so that -0 steps down and +0 up, as the NaN
     * rule of Ray_PlaneT assumes. */
    if (!(ray->inv[a] < (real)0.0f)) {
      while (c > 0 && Ray_PlaneT(ray, a, Grid_Plane(grid, a, c)) > tEnter) --c;
      while (c < res - 1 && Ray_PlaneT(ray, a, Grid_Plane(grid, a, c + 1)) < tEnter) ++c;
    } else {
      while (c < res - 1 && Ray_PlaneT(ray, a, Grid_Plane(grid, a, c + 1)) > tEnter) ++c;
      while (c > 0 && Ray_PlaneT(ray, a, Grid_Plane(grid, a, c)) < tEnter) --c;
    }
    cell[a] = c;
  }
}

/* The walk's first cell: 0 when the ray misses the grid box within
 * [tmin, tMax], else 1 with the cell the ray enters the box in and its
 * entry parameter. */
CR_FUNC int Grid_EnterT(CR_GLOBAL const GridHeader* grid, const Ray* ray, real tMax, int cell[3], real* tEnter)
{
  if (!Box_Intersect(grid->bmin, grid->bmax, ray, ray->tmin, tMax, tEnter)) return 0;
  Grid_EnterAt(grid, ray, *tEnter, cell);
  return 1;
}
CR_FUNC int Grid_Enter(CR_GLOBAL const GridHeader* grid, const Ray* ray, real tMax, int cell[3])
{
  real tEnter;
  return Grid_EnterT(grid, ray, tMax, cell, &tEnter);
}

/* Index of a cell in cellStart. */
CR_FUNC uint Grid_CellIndex(CR_GLOBAL const GridHeader* grid, const int cell[3])
{
  return (uint)cell[0] + grid->res[0] * ((uint)cell[1] + grid->res[1] * (uint)cell[2]);
}

/* The exit parameter of cell `cell` (the smallest crossing parameter of its
 * three exit planes) and the axis of its exit face (x before y before z on
 * ties). */
CR_FUNC real Grid_CellExit(CR_GLOBAL const GridHeader* grid, const Ray* ray, const int cell[3], int* axisOut)
{
  int axis = 0;
  real tExit = (real)CR_INF;
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    const int plane = ray->inv[a] < (real)0.0f ? cell[a] : cell[a] + 1;
    const real t = Ray_PlaneT(ray, a, Grid_Plane(grid, a, plane));
    if (t < tExit) {
      tExit = t;
      axis = a;
    }
  }
  *axisOut = axis;
  return tExit;
}

/* One step of the walk, after the current cell's references were tested:
 * 0 when the walk ends (the closest hit so far, hitT, or tmax lies at or
 * before the cell's exit, or the exit face is the grid's), else 1 with
 * `cell` moved to the neighbour across the exit face. `cell` is left as it
 * was when the walk ends; *tExitOut is the cell's exit parameter (the next
 * cell's entry) either way. Straight-line code (selects, no indexing by a
 * computed axis) so that a packet's lanes can run it side by side. */
CR_FUNC int Grid_Step(CR_GLOBAL const GridHeader* grid, const Ray* ray, real hitT, int cell[3], real* tExitOut)
{
  int axis;
  const real tExit = Grid_CellExit(grid, ray, cell, &axis);
  /* hitT is the closest hit so far, or tmax: either way nothing farther can
   * beat it once the walk has passed it. */
  *tExitOut = tExit;
  if (hitT <= tExit) return 0;
  int next[3];
  int inside = 1;
  CR_UNROLL for (int a = 0; a < 3; ++a) {
    const int step = a != axis ? 0 : ray->inv[a] < (real)0.0f ? -1 : 1;
    next[a] = cell[a] + step;
    inside &= (next[a] >= 0 && next[a] < (int)grid->res[a]) ? 1 : 0;
  }
  if (!inside) return 0;
  CR_UNROLL for (int a = 0; a < 3; ++a) cell[a] = next[a];
  return 1;
}

#endif /* the walk */
#if CR_WITH_GRID

/* Grid_Step without the exit parameter: the walk of the uniform grid. */
CR_FUNC int Grid_Next(CR_GLOBAL const GridHeader* grid, const Ray* ray, real hitT, int cell[3])
{
  real tExit;
  return Grid_Step(grid, ray, hitT, cell, &tExit);
}

/* The walk from cell `cell` (not yet tested) on, testing each cell's
 * references refs[cellStart[i] .. cellStart[i + 1]); 1 when an any-hit query
 * (anyHit) is answered. */
CR_FUNC int Grid_Walk(CR_GLOBAL const GridHeader* grid, CR_GLOBAL const uint* cellStart, CR_GLOBAL const uint* refs,
                      const PrimView* pv, const Ray* ray, Hit* hit, int anyHit, int cell[3], TraceStats* st)
{
  do {
    CR_COUNT(st, nTS);
    CR_COUNT(st, nLeaves);
    const uint idx = Grid_CellIndex(grid, cell);
    const uint end = cellStart[idx + 1u];
    const uint begin = cellStart[idx];
    if (begin == end) CR_COUNT(st, nEmptyLeaves);
    for (uint i = begin; i < end; ++i) {
      CR_COUNT(st, nIT);
      if (Prim_Intersect(pv, refs[i], ray, hit) && anyHit) return 1;
    }
  } while (Grid_Next(grid, ray, hit->t, cell));
  return 0;
}

/* Closest hit (anyHit = 0) or any hit (anyHit = 1) of the ray against the
 * grid; `hit` must come from Hit_Init. */
CR_FUNC void Grid_Trace(CR_GLOBAL const GridHeader* grid, CR_GLOBAL const uint* cellStart, CR_GLOBAL const uint* refs,
                        const PrimView* pv, const Ray* ray, Hit* hit, int anyHit, TraceStats* st)
{
  if (grid->nRefs == 0u) return;
  int cell[3];
  if (!Grid_Enter(grid, ray, hit->t, cell)) return;
  (void)Grid_Walk(grid, cellStart, refs, pv, ray, hit, anyHit, cell, st);
}

#endif /* CR_WITH_GRID */
#endif /* CELLRAY_KERNELS_GRID_H */
