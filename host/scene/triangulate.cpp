#include "host/scene/triangulate.h"

#include <cmath>

namespace cr {

namespace {

struct P2 {
  double x, y;
};

double Orient(const P2& a, const P2& b, const P2& c) { return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x); }

// p inside or on the boundary of the counter-clockwise triangle abc.
bool InTriangle(const P2& p, const P2& a, const P2& b, const P2& c)
{
  return Orient(a, b, p) >= 0.0 && Orient(b, c, p) >= 0.0 && Orient(c, a, p) >= 0.0;
}

bool Same(const P2& a, const P2& b) { return a.x == b.x && a.y == b.y; }

}  // namespace

Triangulation TriangulatePolygon(const std::vector<glm::dvec3>& pts)
{
  Triangulation out;
  const std::size_t n0 = pts.size();
  if (n0 < 3) {
    out.degenerate = true;
    return out;
  }
  // Newell normal: robust for non-convex and slightly non-planar polygons.
  glm::dvec3 nrm(0.0);
  for (std::size_t i = 0; i < n0; ++i) {
    const glm::dvec3& a = pts[i];
    const glm::dvec3& b = pts[(i + 1) % n0];
    nrm.x += (a.y - b.y) * (a.z + b.z);
    nrm.y += (a.z - b.z) * (a.x + b.x);
    nrm.z += (a.x - b.x) * (a.y + b.y);
  }
  out.area = 0.5 * glm::length(nrm);
  if (!(out.area > 0.0)) {
    out.degenerate = true;
    return out;
  }
  if (n0 == 3) {
    out.triangles.push_back({0, 1, 2});
    return out;
  }
  glm::dvec3 an = glm::abs(nrm);
  int drop = (an.x > an.y) ? (an.x > an.z ? 0 : 2) : (an.y > an.z ? 1 : 2);
  int ax = (drop + 1) % 3, ay = (drop + 2) % 3;
  if (nrm[drop] < 0.0) std::swap(ax, ay);  // counter-clockwise in (ax, ay)

  std::vector<P2> p(n0);
  for (std::size_t i = 0; i < n0; ++i) p[i] = {pts[i][ax], pts[i][ay]};

  // Working list without consecutive duplicates.
  std::vector<std::uint32_t> idx;
  idx.reserve(n0);
  for (std::uint32_t i = 0; i < n0; ++i)
    if (idx.empty() || !Same(p[idx.back()], p[i])) idx.push_back(i);
  while (idx.size() > 1 && Same(p[idx.front()], p[idx.back()])) idx.pop_back();

  double polyArea2 = 0.0;  // twice the projected area
  for (std::size_t i = 0; i < idx.size(); ++i) {
    const P2& a = p[idx[i]];
    const P2& b = p[idx[(i + 1) % idx.size()]];
    polyArea2 += a.x * b.y - a.y * b.x;
  }

  double clipped2 = 0.0;
  std::size_t start = 0;
  while (idx.size() > 3) {
    const std::size_t m = idx.size();
    bool found = false;
    for (std::size_t k = 0; k < m && !found; ++k) {
      std::size_t i = (start + k) % m;
      std::uint32_t a = idx[(i + m - 1) % m], b = idx[i], c = idx[(i + 1) % m];
      double o = Orient(p[a], p[b], p[c]);
      if (o < 0.0) continue;  // reflex
      if (o == 0.0) {
        // Collinear (or a zero-width spike): dropping b loses no area.
        idx.erase(idx.begin() + static_cast<std::ptrdiff_t>(i));
        start = i == 0 ? 0 : i - 1;
        found = true;
        break;
      }
      bool ear = true;
      for (std::uint32_t q : idx) {
        if (q == a || q == b || q == c) continue;
        if (Same(p[q], p[a]) || Same(p[q], p[b]) || Same(p[q], p[c])) continue;
        if (InTriangle(p[q], p[a], p[b], p[c])) {
          ear = false;
          break;
        }
      }
      if (!ear) continue;
      out.triangles.push_back({a, b, c});
      clipped2 += o;
      idx.erase(idx.begin() + static_cast<std::ptrdiff_t>(i));
      start = i == 0 ? 0 : i - 1;
      found = true;
    }
    if (!found) {
      // Self-intersecting or numerically hopeless: fan the rest.
      out.nonSimple = true;
      for (std::size_t i = 1; i + 1 < idx.size(); ++i) {
        double o = Orient(p[idx[0]], p[idx[i]], p[idx[i + 1]]);
        if (o != 0.0) out.triangles.push_back({idx[0], idx[i], idx[i + 1]});
        clipped2 += o;
      }
      idx.clear();
    }
  }
  if (idx.size() == 3) {
    double o = Orient(p[idx[0]], p[idx[1]], p[idx[2]]);
    if (o != 0.0) out.triangles.push_back({idx[0], idx[1], idx[2]});
    clipped2 += o;
  }
  if (std::fabs(clipped2 - polyArea2) > 1e-9 * std::fabs(polyArea2) + 1e-300) out.nonSimple = true;
  if (out.triangles.empty()) out.degenerate = true;
  return out;
}

}  // namespace cr
