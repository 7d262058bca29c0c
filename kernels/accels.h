/* The structures' traversals, one header each, in CR_ACCEL_TYPES order
 * (kernels/types.h): the per-ray traversals for every build, and in an
 * OpenCL build of packet kernels their work-group traversals. A header
 * compiles nothing for a structure the build leaves out (CR_WITH_<UPPER>). */
#ifndef CELLRAY_KERNELS_ACCELS_H
#define CELLRAY_KERNELS_ACCELS_H
#include "grid.h"
#include "octree.h"
#include "bvh.h"
#include "hgrid.h"
#if defined(CR_OPENCL) && !defined(CR_VARIANT_RAY)
#include "grid_packet.cl"
#include "octree_packet.cl"
#include "bvh_packet.cl"
#include "hgrid_packet.cl"
#endif
#endif /* CELLRAY_KERNELS_ACCELS_H */
