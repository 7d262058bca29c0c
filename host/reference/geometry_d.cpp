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

double ClosestOnSegment(const glm::dvec3& p1, const glm::dvec3& q1, const glm::dvec3& p2, const glm::dvec3& q2)
{
  const glm::dvec3 d1 = q1 - p1, d2 = q2 - p2, rr = p1 - p2;
  const double a = glm::dot(d1, d1), e = glm::dot(d2, d2), f = glm::dot(d2, rr);
  if (a <= 0.0) return 0.0;
  const double c = glm::dot(d1, rr);
  if (e <= 0.0) return std::clamp(-c / a, 0.0, 1.0);
  const double b = glm::dot(d1, d2), denom = a * e - b * b;
  double s = denom > 0.0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
  const double t = (b * s + f) / e;
  if (t < 0.0) s = std::clamp(-c / a, 0.0, 1.0);
  else if (t > 1.0) s = std::clamp((b - c) / a, 0.0, 1.0);
  return s;
}

void BallOf(const glm::dvec3* pts, int n, double rad, glm::dvec3& mid, double& reach)
{
  mid = glm::dvec3(0.0);
  for (int k = 0; k < n; ++k) mid += pts[k] / double(n);
  reach = rad;
  for (int k = 0; k < n; ++k) reach = std::max(reach, glm::length(pts[k] - mid) + rad);
}

}  // namespace cr::ref
