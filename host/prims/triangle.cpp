// Triangle (every piece of an NFF `p` polygon or `pp` patch, and of an OBJ
// face): the host functions of host/prims/prim_host.h.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "host/prims/prim_host.h"
#include "host/scene/nff.h"

namespace cr {

using ref::D3;

namespace {

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

const char* PrimTypeName(PrimTag<Triangle>) { return "triangle"; }

Bounds FloatBounds(const Triangle& t)
{
  Bounds b;
  b.Extend(glm::vec3(t.v0[0], t.v0[1], t.v0[2]));
  b.Extend(glm::vec3(t.v1[0], t.v1[1], t.v1[2]));
  b.Extend(glm::vec3(t.v2[0], t.v2[1], t.v2[2]));
  return b;
}

// The triangle's two sides of the plane (Embree's splitTriangle): each
// vertex goes to its side (both when on the plane), each edge that crosses
// the plane adds its crossing point, computed in double, to both; each side's
// box is widened by 2^-48 of the triangle's largest coordinate on the axis
// (far above the crossing's double error), rounded outward to float, and
// intersected with the box, whose own part of the triangle lies within.
void SplitBounds(const Triangle& t, const Bounds& box, int axis, float pos, Bounds& left, Bounds& right)
{
  const glm::dvec3 v[3] = {D3(t.v0), D3(t.v1), D3(t.v2)};
  const double p = pos;
  glm::dvec3 lo[2] = {glm::dvec3(INFINITY), glm::dvec3(INFINITY)};
  glm::dvec3 hi[2] = {glm::dvec3(-INFINITY), glm::dvec3(-INFINITY)};
  const auto add = [&](int side, const glm::dvec3& x) {
    lo[side] = glm::min(lo[side], x);
    hi[side] = glm::max(hi[side], x);
  };
  for (int i = 0; i < 3; ++i) {
    const glm::dvec3& a = v[i];
    const glm::dvec3& b = v[(i + 1) % 3];
    if (a[axis] <= p) add(0, a);
    if (a[axis] >= p) add(1, a);
    if ((a[axis] < p && b[axis] > p) || (a[axis] > p && b[axis] < p)) {
      glm::dvec3 x = a + (b - a) * ((p - a[axis]) / (b[axis] - a[axis]));
      x[axis] = p;
      add(0, x);
      add(1, x);
    }
  }
  const glm::dvec3 m = glm::max(glm::abs(v[0]), glm::max(glm::abs(v[1]), glm::abs(v[2]))) * 0x1.0p-48;
  Bounds side[2];
  for (int s = 0; s < 2; ++s) {
    if (!(lo[s].x <= hi[s].x)) continue;  // no vertex or crossing on this side
    for (int a = 0; a < 3; ++a) {
      side[s].lo[a] = FloatDown(lo[s][a] - m[a]);
      side[s].hi[a] = FloatUp(hi[s][a] + m[a]);
    }
  }
  Bounds l, r;
  SplitBox(box, axis, pos, l, r);
  left = Intersect(side[0], l);
  right = Intersect(side[1], r);
}

// Separating axis test (Akenine-Moller 2001, "Fast 3D triangle-box overlap
// testing"): the 3 box normals, the triangle normal and the 9 edge cross
// products. Degenerate triangles are tested against the axes that remain.
bool OverlapsBox(const Triangle& tri, const glm::dvec3& lo, const glm::dvec3& hi)
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

double Scale(const Triangle& t) { return std::max(MaxAbs(D3(t.v0)), std::max(MaxAbs(D3(t.v1)), MaxAbs(D3(t.v2)))); }

// Barycentric interpolation; patch pieces interpolate their vertex normals.
LocalSurface SurfaceAt(const Scene& scene, const Triangle& t, std::uint32_t local, const glm::dvec3&, double u, double v)
{
  LocalSurface ls;
  const glm::dvec3 a = D3(t.v0), b = D3(t.v1), c = D3(t.v2);
  ls.p = (1.0 - u - v) * a + u * b + v * c;
  ls.ng = glm::normalize(glm::cross(b - a, c - a));
  ls.ns = ls.ng;
  if (scene.HasPatchNormals()) {
    const TriNormals& n = scene.triNormals[local];
    const glm::dvec3 s = (1.0 - u - v) * glm::dvec3(n[0]) + u * glm::dvec3(n[1]) + v * glm::dvec3(n[2]);
    if (glm::dot(s, s) > 0.0) ls.ns = glm::normalize(s);
  }
  return ls;
}

void RefBounds(const Triangle& t, glm::dvec3& lo, glm::dvec3& hi)
{
  lo = glm::min(D3(t.v0), glm::min(D3(t.v1), D3(t.v2)));
  hi = glm::max(D3(t.v0), glm::max(D3(t.v1), D3(t.v2)));
}

// Woop, Benthin & Wald 2013 in double.
int RefRoots(const ref::DRay& r, const Triangle& tri, double t[2], double* u, double* v)
{
  const glm::dvec3 A = D3(tri.v0) - r.o, B = D3(tri.v1) - r.o, C = D3(tri.v2) - r.o;
  const double Ax = A[r.kx] - r.sx * A[r.kz], Ay = A[r.ky] - r.sy * A[r.kz];
  const double Bx = B[r.kx] - r.sx * B[r.kz], By = B[r.ky] - r.sy * B[r.kz];
  const double Cx = C[r.kx] - r.sx * C[r.kz], Cy = C[r.ky] - r.sy * C[r.kz];
  const double U = Cx * By - Cy * Bx, V = Ax * Cy - Ay * Cx, W = Bx * Ay - By * Ax;
  if ((U < 0 || V < 0 || W < 0) && (U > 0 || V > 0 || W > 0)) return 0;
  const double det = U + V + W;
  if (det == 0.0) return 0;
  const double T = U * (r.sz * A[r.kz]) + V * (r.sz * B[r.kz]) + W * (r.sz * C[r.kz]);
  const double tt = T / det;
  if (!(tt >= r.tmin && tt <= r.tmax)) return 0;
  t[0] = tt;
  if (u) *u = V / det;
  if (v) *v = W / det;
  return 1;
}

// Closest point on a triangle (Ericson, Real-Time Collision Detection 5.1.5).
double RefDistance(const Triangle& tri, const glm::dvec3& p)
{
  const glm::dvec3 a = D3(tri.v0), b = D3(tri.v1), c = D3(tri.v2);
  const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return glm::length(p - a);
  const glm::dvec3 bp = p - b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return glm::length(p - b);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return glm::length(p - (a + ab * (d1 / (d1 - d3))));
  const glm::dvec3 cp = p - c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return glm::length(p - c);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return glm::length(p - (a + ac * (d2 / (d2 - d6))));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
    return glm::length(p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
  const double denom = 1.0 / (va + vb + vc);
  return glm::length(p - (a + ab * (vb * denom) + ac * (vc * denom)));
}

glm::dvec3 RefNormal(const Triangle& tri, const glm::dvec3&)
{
  return glm::normalize(glm::cross(D3(tri.v1) - D3(tri.v0), D3(tri.v2) - D3(tri.v0)));
}

void RefBall(const Triangle& t, glm::dvec3& mid, double& reach)
{
  const glm::dvec3 pts[3] = {D3(t.v0), D3(t.v1), D3(t.v2)};
  ref::BallOf(pts, 3, 0.0, mid, reach);
}

// The closest approaches to the three edges.
void RefNearTimes(const Triangle& t, const ref::DRay& r, double t0, double t1, std::vector<double>& ts)
{
  const glm::dvec3 pts[3] = {D3(t.v0), D3(t.v1), D3(t.v2)};
  const glm::dvec3 a = r.o + t0 * r.d, b = r.o + t1 * r.d;
  for (int k = 0; k < 3; ++k) ts.push_back(t0 + (t1 - t0) * ref::ClosestOnSegment(a, b, pts[k], pts[(k + 1) % 3]));
}

// p n x1 y1 z1 ... (polygon) and pp n x1 y1 z1 nx1 ny1 nz1 ... (patch).
bool ParseNff(PrimTag<Triangle>, NffStatement& st, Scene& scene)
{
  const bool patch = st.keyword == "pp";
  if (!patch && st.keyword != "p") return false;
  const long n = st.Integer("the vertex count");
  if (n < 0) st.Fail(fmt::format("'{}': negative vertex count {}", st.keyword, n));
  std::vector<glm::dvec3> verts;
  std::vector<glm::vec3> normals;
  for (long i = 0; i < n; ++i) {
    verts.push_back(st.Vec("a vertex coordinate"));
    if (patch) normals.push_back(glm::vec3(st.Vec("a vertex normal component")));
  }
  AddPolygon(scene, patch ? PrimKind::kPatch : PrimKind::kPolygon, verts, patch ? &normals : nullptr, st.material,
             static_cast<std::uint32_t>(st.line), st.file);
  return true;
}

}  // namespace cr
