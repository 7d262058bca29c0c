/* Octree traversal: placeholder until the accel issue lands. */
#ifndef CELLRAY_KERNELS_OCTREE_H
#define CELLRAY_KERNELS_OCTREE_H
#include "intersect.h"

CR_FUNC void Octree_Trace(CR_GLOBAL const OctreeHeader* hdr, CR_GLOBAL const OctreeNode* nodes,
                          CR_GLOBAL const uint* refs, const PrimView* pv, const Ray* ray, Hit* hit, int anyHit,
                          TraceStats* st)
{
}

#endif /* CELLRAY_KERNELS_OCTREE_H */
