// Surface points of hits and robust origins for the rays that leave them.
//
// The hit point is reprojected onto the surface in double (barycentric
// interpolation on triangles, radial projection on spheres: each type's
// SurfaceAt, host/prims/), so it
// does not inherit the error of the hit's t. The origin of a secondary ray is
// then moved off the surface along the normal by an error bound, in the
// manner of pbrt-v4's OffsetRayOrigin (Pharr, Jakob & Humphreys, 4th ed.,
// 6.8.6): not a fixed epsilon, but the distance within which a float32
// intersector can still find the surface it leaves. That distance scales with
// the primitive's own coordinates (a watertight test on a triangle whose
// vertices lie 5000 units away errs by ~1e-4 even where it is hit near the
// origin), so the bound is
//   error = 2^-19 * S + 2^-22 * |p|_inf,
// S being the largest coordinate magnitude of the primitive's defining points
// (the scale the checker's tolerance used to include too, until it was made
// the ray's own, docs/TOLERANCE.md). Any float intersector needs that much.
// Ours need less in robust and fp64 mode: they recompute in double-float
// what cancels (kernels/intersect.h), so a few ulps of the point itself,
//   robustError = 2^-21 * |p|_inf + 2^-40 * S
// (the second term, far below the first unless p lies near the world
// origin, keeps the move above double-float's own resolution),
// keep them off the surface they leave, and a shadow ray from a ground
// sphere of radius 10^6 starts 10^-5 above it instead of 4 units (which
// would lose the contact shadow of everything smaller than that).
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

#include "host/scene/scene.h"

namespace cr {

struct SurfacePoint {
  glm::vec3 p{0.0f};   // on the surface, rounded to float
  float error = 0.0f;        // how far off the surface a float intersector may place it
  float robustError = 0.0f;  // the same for our robust and fp64 intersectors
  glm::vec3 ng{0.0f};  // outward geometric normal (unit; inward for inside-visible primitives)
  glm::vec3 ns{0.0f};  // shading normal (unit; patch normals interpolated), on ng's side
};

// The surface point of a hit on unified piece g near pApprox, with the hit's
// barycentrics (u weights v1, v weights v2) for triangle pieces, at the
// ray's time (a moving piece lies translated by time * motion, and the
// error bounds grow by the rounding of that shift: kernels/motion.h).
SurfacePoint SurfaceAt(const Scene& scene, std::uint32_t g, const glm::dvec3& pApprox, double u, double v,
                       double time = 0.0);

// Origin for a ray leaving the surface to the side of n (unit, with
// dot(n, ng) != 0): p moved by `error` along n, each component rounded away
// from the surface so the move survives rounding.
glm::vec3 OffsetRayOrigin(const glm::vec3& p, float error, const glm::vec3& n);

// A ray record from o along d over [0, tmax] (the rays the renderer and the
// ray generator spawn).
inline RayRecord MakeRay(const glm::vec3& o, const glm::vec3& d, float tmax)
{
  RayRecord r;
  for (int a = 0; a < 3; ++a) {
    r.org[a] = o[a];
    r.dir[a] = d[a];
  }
  r.tmin = 0.0f;
  r.tmax = tmax;
  return r;
}

// A shadow ray from p (offset by `offset` to the side of unit `side`) to the
// point s sampled on light l, that point moved off the light towards p by
// the float error of l's surface, so that the ray ends before the light.
RayRecord ShadowRayToLight(const glm::vec3& p, float offset, const glm::vec3& side, const AreaLight& l,
                           const LightSample& s);

}  // namespace cr
