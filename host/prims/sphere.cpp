// Sphere (NFF `s`): the host functions of host/prims/prim_host.h.
#include <cmath>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/prims/prim_host.h"
#include "host/scene/nff.h"

namespace cr {
namespace sphere_fp64 {
#define CR_FP64
#include "kernels/ray.h"
#include "kernels/sphere.h"
#undef CR_FP64
}  // namespace sphere_fp64

using ref::D3;

const char* PrimTypeName(PrimTag<Sphere>) { return "sphere"; }

Bounds FloatBounds(const Sphere& s)
{
  Bounds b;
  const glm::vec3 c(s.center[0], s.center[1], s.center[2]);
  // Outward rounding: c +- r may round inward by half an ulp.
  const glm::vec3 r(s.radius);
  b.lo = glm::vec3(std::nextafter(c.x - r.x, -INFINITY), std::nextafter(c.y - r.y, -INFINITY),
                   std::nextafter(c.z - r.z, -INFINITY));
  b.hi = glm::vec3(std::nextafter(c.x + r.x, INFINITY), std::nextafter(c.y + r.y, INFINITY),
                   std::nextafter(c.z + r.z, INFINITY));
  return b;
}

// Its box's two sides (the sphere itself is not cut).
void SplitBounds(const Sphere& p, const Bounds& box, int axis, float pos, Bounds& left, Bounds& right)
{
  SplitBox(Intersect(FloatBounds(p), box), axis, pos, left, right);
}

// Arvo 1990 ("A simple method for box-sphere intersection testing"), hollow
// form: the surface meets the box iff the nearest point of the box is inside
// the sphere and the farthest is not (a box wholly inside the ball holds no
// surface).
bool OverlapsBox(const Sphere& s, const glm::dvec3& lo, const glm::dvec3& hi)
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

double Scale(const Sphere& s) { return MaxAbs(D3(s.center)) + s.radius; }

// Radial projection.
LocalSurface SurfaceAt(const Scene&, const Sphere& s, std::uint32_t, const glm::dvec3& pApprox, double, double)
{
  LocalSurface ls;
  const glm::dvec3 center = D3(s.center);
  const glm::dvec3 rel = pApprox - center;
  const double len = glm::length(rel);
  ls.ng = len > 0.0 ? rel / len : glm::dvec3(0, 0, 1);
  ls.p = center + double(s.radius) * ls.ng;
  ls.ns = ls.ng;
  return ls;
}

void RefBounds(const Sphere& s, glm::dvec3& lo, glm::dvec3& hi)
{
  const glm::dvec3 l = D3(s.center) - double(s.radius), h = D3(s.center) + double(s.radius);
  lo = {std::nextafter(l.x, -INFINITY), std::nextafter(l.y, -INFINITY), std::nextafter(l.z, -INFINITY)};
  hi = {std::nextafter(h.x, INFINITY), std::nextafter(h.y, INFINITY), std::nextafter(h.z, INFINITY)};
}

namespace {

// |o - centre|^2 - r^2 in double without the cancellation of |f|^2 against
// r^2 that a ground sphere seen from just above it makes (r = 1e6, 6e-7
// above: both 1e12, their difference 1.2): the kernels' Sphere_CAccurate
// compiled with real = double (f = o - centre as exact pairs, the squares,
// cross terms and r^2 as exact products, summed by SumK, Ogita, Rump &
// Oishi 2005). The plain double form erred by 2e-4 there, enough to put the
// reference's root 2e-8 (twice the checker's tolerance) from the true one.
double SphereC(const glm::dvec3& o, const Sphere& s)
{
  const double org[3] = {o.x, o.y, o.z};
  return sphere_fp64::Sphere_CAccurate(org, &s);
}

}  // namespace

int RefRoots(const ref::DRay& r, const Sphere& s, double t[2], double*, double*)
{
  const glm::dvec3 f = r.o - D3(s.center);
  const double rad = s.radius;
  const double a = glm::dot(r.d, r.d);
  const double bh = glm::dot(f, r.d);
  const double c = SphereC(r.o, s);
  const glm::dvec3 x = glm::cross(f, r.d);
  const double disc = a * rad * rad - glm::dot(x, x);
  if (ref::Quadratic(a, bh, c, disc, t) == 0) return 0;
  return ref::KeepInRange(t, 2, r.tmin, r.tmax);
}

double RefDistance(const Sphere& s, const glm::dvec3& x) { return std::fabs(glm::length(x - D3(s.center)) - s.radius); }

glm::dvec3 RefNormal(const Sphere& s, const glm::dvec3& x) { return (x - D3(s.center)) / double(s.radius); }

void RefBall(const Sphere& s, glm::dvec3& mid, double& reach)
{
  const glm::dvec3 c = D3(s.center);
  ref::BallOf(&c, 1, s.radius, mid, reach);
}

// The closest approach to the centre.
void RefNearTimes(const Sphere& s, const ref::DRay& r, double t0, double t1, std::vector<double>& ts)
{
  const double dl = glm::length(r.d);
  ts.push_back(std::clamp(glm::dot(D3(s.center) - r.o, r.d) / (dl * dl), t0, t1));
}

// s x y z r: a negative radius makes the inside visible.
bool ParseNff(PrimTag<Sphere>, NffStatement& st, Scene& scene)
{
  if (st.keyword != "s") return false;
  const glm::dvec3 c = st.Vec("a centre coordinate");
  const double r = st.Number("the radius");
  PrimInfo info = st.Info(CR_PRIM_SPHERE);
  info.insideVisible = r < 0.0;
  const auto id = scene.NumPrims();
  const float rf = float(std::fabs(r));
  if (rf == 0.0f) {
    Warn(fmt::format("{}:{}: sphere of radius 0: skipped, id {} kept", st.file, st.line, id));
  } else {
    info.firstPiece = scene.AddPiece(Sphere{{float(c.x), float(c.y), float(c.z)}, rf}, id);
    info.nPieces = 1;
  }
  scene.prims.push_back(info);
  return true;
}

}  // namespace cr
