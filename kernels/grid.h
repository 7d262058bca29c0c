/* Uniform grid traversal (3D-DDA): placeholder until the accel issue lands. */
#ifndef CELLRAY_KERNELS_GRID_H
#define CELLRAY_KERNELS_GRID_H
#include "intersect.h"

CR_FUNC void Grid_Trace(CR_GLOBAL const GridHeader* grid, CR_GLOBAL const uint* cellStart, CR_GLOBAL const uint* refs,
                        const PrimView* pv, const Ray* ray, Hit* hit, int anyHit, TraceStats* st)
{
}

#endif /* CELLRAY_KERNELS_GRID_H */
