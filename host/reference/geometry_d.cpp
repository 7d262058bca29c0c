#include "host/reference/geometry_d.h"

#include <algorithm>
#include <cmath>

namespace cr::ref {

DRay MakeRay(const glm::dvec3& o, const glm::dvec3& d, double tmin, double tmax)
{
  DRay r;
  r.o = o;
  r.d = d;
  r.inv = glm::dvec3(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
  r.tmin = tmin;
  r.tmax = tmax;
  glm::dvec3 a = glm::abs(d);
  r.kz = (a.x > a.y) ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
  r.kx = (r.kz + 1) % 3;
  r.ky = (r.kx + 1) % 3;
  if (d[r.kz] < 0.0) std::swap(r.kx, r.ky);
  r.sx = d[r.kx] / d[r.kz];
  r.sy = d[r.ky] / d[r.kz];
  r.sz = 1.0 / d[r.kz];
  return r;
}

DRay MakeRay(const RayRecord& rec) { return MakeRay(D3(rec.org), D3(rec.dir), rec.tmin, rec.tmax); }

namespace {

// Real roots of a t^2 + 2 bh t + c = 0, ascending, stable (Press et al.).
int Quadratic(double a, double bh, double c, double disc, double t[2])
{
  if (disc < 0.0) return 0;
  double q = -(bh + std::copysign(std::sqrt(disc), bh));
  double r0 = q / a;
  double r1 = q != 0.0 ? c / q : r0;
  t[0] = std::min(r0, r1);
  t[1] = std::max(r0, r1);
  return 2;
}

int KeepInRange(double t[2], int n, double tmin, double tmax)
{
  int k = 0;
  for (int i = 0; i < n; ++i)
    if (t[i] >= tmin && t[i] <= tmax) t[k++] = t[i];
  return k;
}

}  // namespace

int SphereRoots(const DRay& r, const Sphere& s, double t[2])
{
  glm::dvec3 f = r.o - D3(s.center);
  double rad = s.radius;
  double a = glm::dot(r.d, r.d);
  double bh = glm::dot(f, r.d);
  double c = glm::dot(f, f) - rad * rad;
  glm::dvec3 x = glm::cross(f, r.d);
  double disc = a * rad * rad - glm::dot(x, x);
  if (Quadratic(a, bh, c, disc, t) == 0) return 0;
  return KeepInRange(t, 2, r.tmin, r.tmax);
}

int TriangleRoots(const DRay& r, const Triangle& tri, double t[1], double* u, double* v)
{
  // Woop, Benthin & Wald 2013 in double.
  glm::dvec3 A = D3(tri.v0) - r.o, B = D3(tri.v1) - r.o, C = D3(tri.v2) - r.o;
  double Ax = A[r.kx] - r.sx * A[r.kz], Ay = A[r.ky] - r.sy * A[r.kz];
  double Bx = B[r.kx] - r.sx * B[r.kz], By = B[r.ky] - r.sy * B[r.kz];
  double Cx = C[r.kx] - r.sx * C[r.kz], Cy = C[r.ky] - r.sy * C[r.kz];
  double U = Cx * By - Cy * Bx, V = Ax * Cy - Ay * Cx, W = Bx * Ay - By * Ax;
  if ((U < 0 || V < 0 || W < 0) && (U > 0 || V > 0 || W > 0)) return 0;
  double det = U + V + W;
  if (det == 0.0) return 0;
  double T = U * (r.sz * A[r.kz]) + V * (r.sz * B[r.kz]) + W * (r.sz * C[r.kz]);
  double tt = T / det;
  if (!(tt >= r.tmin && tt <= r.tmax)) return 0;
  t[0] = tt;
  if (u) *u = V / det;
  if (v) *v = W / det;
  return 1;
}

int ConeRoots(const DRay& r, const Cone& cn, double t[2])
{
  glm::dvec3 b = D3(cn.base), w = D3(cn.apex) - b;
  double H = glm::length(w);
  if (!(H > 0.0)) return 0;
  w /= H;
  double r0 = cn.baseRadius, k = (double(cn.apexRadius) - r0) / H;
  glm::dvec3 dl = r.o - b;
  double ds = glm::dot(r.d, w), os = glm::dot(dl, w);
  glm::dvec3 dR = r.d - ds * w, oR = dl - os * w;
  double rb = r0 + k * os;
  double A = glm::dot(dR, dR) - k * k * ds * ds;
  double Bh = glm::dot(oR, dR) - k * ds * rb;
  double C = glm::dot(oR, oR) - rb * rb;
  double roots[2];
  int n = 0;
  if (A == 0.0) {
    if (Bh == 0.0) return 0;
    roots[0] = -C / (2.0 * Bh);
    n = 1;
  } else {
    // Bh^2 - A C without cancellation (see kernels/intersect.h).
    glm::dvec3 e = rb * dR - k * ds * oR, x = glm::cross(oR, dR);
    n = Quadratic(A, Bh, C, glm::dot(e, e) - glm::dot(x, x), roots);
  }
  int k2 = 0;
  for (int i = 0; i < n; ++i) {
    double s = os + roots[i] * ds;
    if (roots[i] >= r.tmin && roots[i] <= r.tmax && s >= 0.0 && s <= H) t[k2++] = roots[i];
  }
  return k2;
}

double SphereDistance(const Sphere& s, const glm::dvec3& p) { return std::fabs(glm::length(p - D3(s.center)) - s.radius); }

double TriangleDistance(const Triangle& tri, const glm::dvec3& p)
{
  // Closest point on a triangle (Ericson, Real-Time Collision Detection 5.1.5).
  glm::dvec3 a = D3(tri.v0), b = D3(tri.v1), c = D3(tri.v2);
  glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
  double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return glm::length(p - a);
  glm::dvec3 bp = p - b;
  double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return glm::length(p - b);
  double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return glm::length(p - (a + ab * (d1 / (d1 - d3))));
  glm::dvec3 cp = p - c;
  double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return glm::length(p - c);
  double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return glm::length(p - (a + ac * (d2 / (d2 - d6))));
  double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
    return glm::length(p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
  double denom = 1.0 / (va + vb + vc);
  return glm::length(p - (a + ab * (vb * denom) + ac * (vc * denom)));
}

double ConeDistance(const Cone& cn, const glm::dvec3& p)
{
  // In the half-plane (s, rho) through the axis the surface is the segment
  // (0, r0)-(H, r1).
  glm::dvec3 b = D3(cn.base), w = D3(cn.apex) - b;
  double H = glm::length(w);
  w /= H;
  glm::dvec3 q = p - b;
  double s = glm::dot(q, w);
  double rho = glm::length(q - s * w);
  glm::dvec2 P(s, rho), S0(0.0, cn.baseRadius), S1(H, cn.apexRadius);
  glm::dvec2 e = S1 - S0;
  double u = std::clamp(glm::dot(P - S0, e) / glm::dot(e, e), 0.0, 1.0);
  return glm::length(P - (S0 + u * e));
}

glm::dvec3 SphereNormal(const Sphere& s, const glm::dvec3& p) { return (p - D3(s.center)) / double(s.radius); }

glm::dvec3 TriangleNormal(const Triangle& tri)
{
  return glm::cross(D3(tri.v1) - D3(tri.v0), D3(tri.v2) - D3(tri.v0));
}

glm::dvec3 ConeNormal(const Cone& cn, const glm::dvec3& p)
{
  glm::dvec3 b = D3(cn.base), w = D3(cn.apex) - b;
  double H = glm::length(w);
  w /= H;
  glm::dvec3 q = p - b;
  double s = glm::dot(q, w);
  glm::dvec3 radial = q - s * w;
  double rl = glm::length(radial);
  if (rl == 0.0) return w;
  radial /= rl;
  // The surface line rises by (r1 - r0) over H: the normal tilts back along -w.
  double k = (double(cn.apexRadius) - double(cn.baseRadius)) / H;
  return glm::normalize(radial - k * w);
}

}  // namespace cr::ref
