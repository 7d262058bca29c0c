#include "host/scene/surface.h"

#include <algorithm>
#include <cmath>

#include "host/prims/prim_host.h"

namespace cr {

SurfacePoint SurfaceAt(const Scene& scene, std::uint32_t g, const glm::dvec3& pApprox, double u, double v,
                       double time)
{
  SurfacePoint sp;
  double scale = 0.0;
  // A moving piece: found at rest, then moved to where it is at `time`.
  const glm::dvec3 shift = time != 0.0 && scene.hasMotion ? time * glm::dvec3(scene.MotionOfUnified(g)) : glm::dvec3(0.0);
  const LocalSurface ls = scene.Visit(g, [&](const auto& piece, std::uint32_t local) {
    scale = Scale(piece);
    return SurfaceAt(scene, piece, local, pApprox - shift, u, v);
  });
  const glm::dvec3 p = ls.p + shift;
  scale += MaxAbs(shift);
  glm::dvec3 ng = ls.ng, ns = ls.ns;
  if (glm::dot(ns, ng) < 0.0) ns = -ns;  // patch normals follow the winding
  const std::uint32_t id = scene.IdOfUnified(g);
  if (scene.prims[id].insideVisible) {
    ng = -ng;
    ns = -ns;
  }
  sp.p = glm::vec3(p);
  sp.error = float(0x1p-19 * scale + 0x1p-22 * MaxAbs(p));
  sp.robustError = float(0x1p-21 * MaxAbs(p) + 0x1p-40 * scale);
  sp.ng = glm::vec3(ng);
  sp.ns = glm::vec3(ns);
  return sp;
}

glm::vec3 OffsetRayOrigin(const glm::vec3& p, float error, const glm::vec3& n)
{
  glm::vec3 o;
  for (int a = 0; a < 3; ++a) {
    const double target = double(p[a]) + double(error) * double(n[a]);
    float f = static_cast<float>(target);
    // Round away from the surface: never fall short of the bound.
    if (n[a] > 0.0f && double(f) < target) f = std::nextafter(f, INFINITY);
    if (n[a] < 0.0f && double(f) > target) f = std::nextafter(f, -INFINITY);
    if (n[a] > 0.0f && f <= p[a]) f = std::nextafter(p[a], INFINITY);
    if (n[a] < 0.0f && f >= p[a]) f = std::nextafter(p[a], -INFINITY);
    o[a] = f;
  }
  return o;
}

RayRecord ShadowRayToLight(const glm::vec3& p, float offset, const glm::vec3& side, const AreaLight& l,
                           const LightSample& s)
{
  const glm::vec3 o = OffsetRayOrigin(p, offset, side);
  // The light's float surface lies within SurfacePoint::error of s.p.
  const glm::vec3 q(s.p);
  const double qn = std::max({std::fabs(q.x), std::fabs(q.y), std::fabs(q.z)});
  const float err = float(0x1p-19 * l.scale + 0x1p-22 * qn) * 2.0f;
  const glm::vec3 toward = glm::dot(glm::dvec3(o) - s.p, s.n) >= 0.0 ? glm::vec3(s.n) : -glm::vec3(s.n);
  const glm::vec3 end = OffsetRayOrigin(q, err, toward);
  return MakeRay(o, end - o, 1.0f);
}

}  // namespace cr
