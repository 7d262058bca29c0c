/* Motion blur (NFF `motion dx dy dz`, docs/FORMATS.md): a moving piece is its
 * static record translated by time * motion at the ray's time in [0, 1]. A
 * translation moves every point alike, so instead of moving the piece the
 * test moves the ray the other way: origin - time * motion, the same
 * direction (and so the same inverse and shear constants). The structures
 * hold each moving piece in the box it sweeps over the shutter
 * (host/scene/scene.cpp UnifiedBounds), so traversal is unchanged and only
 * the piece test shifts. Every type's test, in every precision mode, runs
 * as is on the shifted ray.
 *
 * CR_HAS_MOTION = 0|1 (default 1): an OpenCL program for a static scene is
 * built with 0 and compiles nothing of this. PrimView::motion holds 4 floats
 * per unified piece (dx, dy, dz, 0), or is null for a static scene. */
#ifndef CELLRAY_KERNELS_MOTION_H
#define CELLRAY_KERNELS_MOTION_H
#include "ray.h"

#ifndef CR_HAS_MOTION
#define CR_HAS_MOTION 1
#endif

#if CR_HAS_MOTION
/* The ray as piece g sees it: *moved is r with its origin shifted by
 * -time * motion[g]. Returns 0 (moved untouched) when g does not move or
 * the ray's time is 0. */
CR_FUNC int Motion_Shift(CR_GLOBAL const float* motion, uint g, const Ray* r, Ray* moved)
{
  const real m0 = (real)motion[4u * g], m1 = (real)motion[4u * g + 1u], m2 = (real)motion[4u * g + 2u];
  if ((m0 == (real)0.0f && m1 == (real)0.0f && m2 == (real)0.0f) || r->time == (real)0.0f) return 0;
  *moved = *r;
  moved->org[0] = r->org[0] - r->time * m0;
  moved->org[1] = r->org[1] - r->time * m1;
  moved->org[2] = r->org[2] - r->time * m2;
  return 1;
}
#endif

#endif /* CELLRAY_KERNELS_MOTION_H */
