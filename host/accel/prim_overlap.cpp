#include "host/accel/prim_overlap.h"

#include <algorithm>
#include <cmath>

namespace cr {

namespace {

glm::dvec3 D3(const float* p) { return {p[0], p[1], p[2]}; }

// Is the projection of the triangle (vertices relative to the box centre) on
// `axis` disjoint from the projection of the box of half size h?
bool Separated(const glm::dvec3& axis, const glm::dvec3& v0, const glm::dvec3& v1, const glm::dvec3& v2,
               const glm::dvec3& h)
{
  const double p0 = glm::dot(axis, v0), p1 = glm::dot(axis, v1), p2 = glm::dot(axis, v2);
  const double r = h.x * std::fabs(axis.x) + h.y * std::fabs(axis.y) + h.z * std::fabs(axis.z);
  return std::min(p0, std::min(p1, p2)) > r || std::max(p0, std::max(p1, p2)) < -r;
}

}  // namespace

bool TriangleOverlapsBox(const Triangle& tri, const glm::dvec3& lo, const glm::dvec3& hi)
{
  const glm::dvec3 c = 0.5 * (lo + hi);
  const glm::dvec3 h = 0.5 * (hi - lo);
  const glm::dvec3 v0 = D3(tri.v0) - c, v1 = D3(tri.v1) - c, v2 = D3(tri.v2) - c;
  // Box normals: the triangle's bounding box against the box.
  for (int a = 0; a < 3; ++a) {
    if (std::min(v0[a], std::min(v1[a], v2[a])) > h[a]) return false;
    if (std::max(v0[a], std::max(v1[a], v2[a])) < -h[a]) return false;
  }
  const glm::dvec3 e[3] = {v1 - v0, v2 - v1, v0 - v2};
  // Triangle normal (a zero normal separates nothing).
  if (Separated(glm::cross(e[0], e[1]), v0, v1, v2, h)) return false;
  // Edge x box-axis cross products.
  for (int a = 0; a < 3; ++a) {
    glm::dvec3 unit(0.0);
    unit[a] = 1.0;
    for (int k = 0; k < 3; ++k)
      if (Separated(glm::cross(unit, e[k]), v0, v1, v2, h)) return false;
  }
  return true;
}

bool SphereOverlapsBox(const Sphere& s, const glm::dvec3& lo, const glm::dvec3& hi)
{
  const glm::dvec3 c = D3(s.center);
  const double r = std::fabs(double(s.radius));
  double dMin = 0.0, dMax = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double below = lo[a] - c[a], above = c[a] - hi[a];
    if (below > 0.0) dMin += below * below;
    if (above > 0.0) dMin += above * above;
    const double far = std::max(std::fabs(c[a] - lo[a]), std::fabs(c[a] - hi[a]));
    dMax += far * far;
  }
  return dMin <= r * r && r * r <= dMax;
}

bool ConeOverlapsBox(const Cone& cn, const glm::dvec3& lo, const glm::dvec3& hi)
{
  const glm::dvec3 p0 = D3(cn.base), p1 = D3(cn.apex);
  glm::dvec3 w = p1 - p0;
  const double H = glm::length(w);
  if (!(H > 0.0)) return true;  // never hit (Cone_Intersect); keep the box answer
  w /= H;
  const glm::dvec3 c = 0.5 * (lo + hi);
  const glm::dvec3 h = 0.5 * (hi - lo);
  // Axial slab: the box projects onto the axis as sc +- sr.
  const double sc = glm::dot(c - p0, w);
  const double sr = h.x * std::fabs(w.x) + h.y * std::fabs(w.y) + h.z * std::fabs(w.z);
  if (sc + sr < 0.0 || sc - sr > H) return false;
  // Radial shell around the axis segment.
  const double R = glm::length(h);
  const double d = glm::length(c - (p0 + std::clamp(sc, 0.0, H) * w));
  const double r0 = double(cn.baseRadius), r1 = double(cn.apexRadius);
  const double rMin = std::min(r0, r1), rMax = std::max(r0, r1);
  return d <= rMax + R && d >= rMin - R;
}

bool PrimOverlapsBox(const Scene& scene, std::uint32_t g, const glm::dvec3& lo, const glm::dvec3& hi)
{
  const auto nS = static_cast<std::uint32_t>(scene.spheres.size());
  const auto nT = static_cast<std::uint32_t>(scene.triangles.size());
  if (g < nS) return SphereOverlapsBox(scene.spheres[g], lo, hi);
  if (g < nS + nT) return TriangleOverlapsBox(scene.triangles[g - nS], lo, hi);
  return ConeOverlapsBox(scene.cones[g - nS - nT], lo, hi);
}

}  // namespace cr
