#include "host/scene/surface.h"

#include <algorithm>
#include <cmath>

namespace cr {

namespace {

glm::dvec3 D3(const float* p) { return {p[0], p[1], p[2]}; }
double MaxAbs(const glm::dvec3& v) { return std::max(std::fabs(v.x), std::max(std::fabs(v.y), std::fabs(v.z))); }

}  // namespace

SurfacePoint SurfaceAt(const Scene& scene, std::uint32_t g, const glm::dvec3& pApprox, double u, double v)
{
  const PrimRanges c = scene.Ranges();
  SurfacePoint sp;
  glm::dvec3 p, ng, ns;
  double scale = 0.0;
  if (g < Prim_End(&c, CR_PRIM_SPHERE)) {
    const Sphere& s = scene.spheres[g];
    const glm::dvec3 center = D3(s.center);
    glm::dvec3 rel = pApprox - center;
    double len = glm::length(rel);
    ng = len > 0.0 ? rel / len : glm::dvec3(0, 0, 1);
    p = center + double(s.radius) * ng;
    ns = ng;
    scale = MaxAbs(center) + s.radius;
  } else if (g < Prim_End(&c, CR_PRIM_TRIANGLE)) {
    const std::uint32_t ti = Prim_Local(&c, CR_PRIM_TRIANGLE, g);
    const Triangle& t = scene.triangles[ti];
    const glm::dvec3 a = D3(t.v0), b = D3(t.v1), cc = D3(t.v2);
    p = (1.0 - u - v) * a + u * b + v * cc;
    ng = glm::normalize(glm::cross(b - a, cc - a));
    ns = ng;
    if (scene.HasPatchNormals()) {
      const TriNormals& n = scene.triNormals[ti];
      glm::dvec3 s = (1.0 - u - v) * glm::dvec3(n[0]) + u * glm::dvec3(n[1]) + v * glm::dvec3(n[2]);
      if (glm::dot(s, s) > 0.0) ns = glm::normalize(s);
    }
    scale = std::max(MaxAbs(a), std::max(MaxAbs(b), MaxAbs(cc)));
  } else {
    const Cone& cn = scene.cones[Prim_Local(&c, CR_PRIM_CONE, g)];
    const glm::dvec3 base = D3(cn.base), apex = D3(cn.apex);
    glm::dvec3 w = apex - base;
    const double H = glm::length(w);
    w /= H;
    const double k = (double(cn.apexRadius) - double(cn.baseRadius)) / H;
    glm::dvec3 q = pApprox - base;
    double s = std::clamp(glm::dot(q, w), 0.0, H);
    glm::dvec3 radial = q - glm::dot(q, w) * w;
    double rl = glm::length(radial);
    glm::dvec3 rdir = rl > 0.0 ? radial / rl : glm::normalize(glm::cross(w, std::fabs(w.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0)));
    p = base + s * w + (double(cn.baseRadius) + k * s) * rdir;
    ng = glm::normalize(rdir - k * w);
    ns = ng;
    scale = std::max(MaxAbs(base) + cn.baseRadius, MaxAbs(apex) + cn.apexRadius);
  }
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

}  // namespace cr
