#include "host/scene/area_light.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "host/core/error.h"
#include "host/scene/nff.h"
#include "host/scene/scene.h"

namespace cr {

namespace {

constexpr double kPi = 3.14159265358979323846;

// An orthonormal basis around unit w (Duff et al. 2017).
void Basis(const glm::dvec3& w, glm::dvec3& a, glm::dvec3& b)
{
  const double sign = std::copysign(1.0, w.z);
  const double p = -1.0 / (sign + w.z), q = w.x * w.y * p;
  a = glm::dvec3(1.0 + sign * w.x * w.x * p, sign * q, -sign * w.x);
  b = glm::dvec3(q, sign + w.y * w.y * p, -w.y);
}

// 1 - cos(theta_max) of the cone a sphere of radius r subtends at distance
// dc > r, without cancellation: sin^2 / (1 + cos).
double OneMinusCosMax(double r, double dc)
{
  const double s2 = (r / dc) * (r / dc);
  return s2 / (1.0 + std::sqrt(std::max(0.0, 1.0 - s2)));
}

std::uint32_t AddLightMaterial(Scene& scene, const glm::vec3& radiance, std::size_t light)
{
  Material m;
  m.color = glm::vec3(0.0f);
  m.kd = 0.0f;
  m.emission = radiance;
  m.light = static_cast<int>(light);
  scene.materials.push_back(m);
  return static_cast<std::uint32_t>(scene.materials.size() - 1);
}

glm::vec3 ReadRadiance(NffStatement& st)
{
  const glm::dvec3 r = st.Vec("a radiance component");
  if (!(r.x >= 0.0 && r.y >= 0.0 && r.z >= 0.0))
    st.Fail(fmt::format("'{}': radiance {} {} {} has a negative component", st.keyword, r.x, r.y, r.z));
  return glm::vec3(r);
}

void AddSphereLight(Scene& scene, const glm::dvec3& c, double radius, const glm::vec3& radiance, std::uint32_t line)
{
  AreaLight l = SphereLight(c, radius, radiance);
  l.prim = scene.NumPrims();
  PrimInfo info;
  info.kind = PrimKind::kShape;
  info.type = CR_PRIM_SPHERE;
  info.material = AddLightMaterial(scene, radiance, scene.areaLights.size());
  info.line = line;
  info.firstPiece = scene.AddPiece(Sphere{{float(c.x), float(c.y), float(c.z)}, float(radius)}, l.prim);
  info.nPieces = 1;
  scene.prims.push_back(info);
  scene.areaLights.push_back(l);
}

}  // namespace

AreaLight SphereLight(const glm::dvec3& c, double radius, const glm::vec3& radiance)
{
  AreaLight l;
  l.kind = AreaLightKind::kSphere;
  l.c = glm::dvec3(glm::vec3(c));  // the traced sphere's float centre and radius
  l.radius = double(float(radius));
  l.area = 4.0 * kPi * l.radius * l.radius;
  l.scale = std::max({std::fabs(l.c.x), std::fabs(l.c.y), std::fabs(l.c.z)}) + l.radius;
  l.radiance = radiance;
  return l;
}

LightSample SampleAreaLight(const AreaLight& l, const glm::dvec3& x, double s1, double s2)
{
  LightSample s;
  if (l.kind == AreaLightKind::kParallelogram) {
    s.p = l.c + s1 * l.u + s2 * l.v;
    s.n = l.n;
    const glm::dvec3 w = x - s.p;
    const double d2 = glm::dot(w, w);
    const double cosl = glm::dot(w, l.n);
    if (!(cosl > 0.0) || !(d2 > 0.0)) return s;
    s.pdf = d2 * std::sqrt(d2) / (l.area * cosl);  // d^2 / (A cos), cos = cosl / d
    s.radiance = l.radiance;
    return s;
  }
  // Sphere: uniform in the cone of directions it subtends at x.
  const glm::dvec3 toC = l.c - x;
  const double dc = glm::length(toC);
  if (!(dc > l.radius)) return s;
  const glm::dvec3 w = toC / dc;
  glm::dvec3 a, b;
  Basis(w, a, b);
  const double omc = OneMinusCosMax(l.radius, dc);
  const double oneMinusCos = s1 * omc;
  const double cosT = 1.0 - oneMinusCos;
  const double sinT = std::sqrt(std::max(0.0, oneMinusCos * (2.0 - oneMinusCos)));
  const double phi = 2.0 * kPi * s2;
  const glm::dvec3 dir = cosT * w + sinT * (std::cos(phi) * a + std::sin(phi) * b);
  // The near root of |x + t dir - c| = r: t = dc cos - sqrt(r^2 - dc^2 sin^2).
  const double disc = std::max(0.0, l.radius * l.radius - dc * dc * sinT * sinT);
  const double t = dc * cosT - std::sqrt(disc);
  s.p = x + t * dir;
  s.n = glm::normalize(s.p - l.c);
  s.pdf = 1.0 / (2.0 * kPi * omc);
  s.radiance = l.radiance;
  return s;
}

double AreaLightPdf(const AreaLight& l, const glm::dvec3& x, const glm::dvec3& p)
{
  if (l.kind == AreaLightKind::kParallelogram) {
    const glm::dvec3 w = x - p;
    const double d2 = glm::dot(w, w);
    const double cosl = glm::dot(w, l.n);
    if (!(cosl > 0.0) || !(d2 > 0.0)) return 0.0;
    return d2 * std::sqrt(d2) / (l.area * cosl);
  }
  const double dc = glm::length(l.c - x);
  if (!(dc > l.radius)) return 0.0;
  return 1.0 / (2.0 * kPi * OneMinusCosMax(l.radius, dc));
}

glm::vec3 AreaLightEmission(const AreaLight& l, const glm::dvec3& dir)
{
  if (l.kind == AreaLightKind::kParallelogram && !(glm::dot(dir, l.n) < 0.0)) return glm::vec3(0.0f);
  return l.radiance;
}

bool ParseAreaLight(NffStatement& st, Scene& scene)
{
  if (st.keyword == "la") {
    AreaLight l;
    l.kind = AreaLightKind::kParallelogram;
    l.c = st.Vec("a corner coordinate");
    l.u = st.Vec("an edge (u) coordinate");
    l.v = st.Vec("an edge (v) coordinate");
    l.radiance = ReadRadiance(st);
    const glm::dvec3 uv = glm::cross(l.u, l.v);
    l.area = glm::length(uv);
    if (!(l.area > 0.0) || !std::isfinite(l.area))
      st.Fail("'la': edges u and v are zero or parallel: the light has no area");
    l.n = uv / l.area;
    for (const glm::dvec3& q : {l.c, l.c + l.u, l.c + l.v, l.c + l.u + l.v})
      l.scale = std::max({l.scale, std::fabs(q.x), std::fabs(q.y), std::fabs(q.z)});
    l.prim = scene.NumPrims();
    const std::uint32_t m = AddLightMaterial(scene, l.radiance, scene.areaLights.size());
    if (!AddPolygon(scene, PrimKind::kPolygon, {l.c, l.c + l.u, l.c + l.u + l.v, l.c + l.v}, nullptr, m,
                    static_cast<std::uint32_t>(st.line), st.file))
      st.Fail("'la': the parallelogram is degenerate in float");
    scene.areaLights.push_back(l);
    return true;
  }
  if (st.keyword == "ls") {
    const glm::dvec3 c = st.Vec("a centre coordinate");
    const double r = st.Number("the radius");
    const glm::vec3 radiance = ReadRadiance(st);
    if (!(r > 0.0) || !std::isfinite(r) || float(r) == 0.0f) st.Fail(fmt::format("'ls': radius {} is not > 0", r));
    AddSphereLight(scene, c, r, radiance, static_cast<std::uint32_t>(st.line));
    return true;
  }
  return false;
}

double SpdLightIntensity(std::size_t nLights)
{
  const double nl = double(std::max<std::size_t>(1, nLights));
  return std::sqrt(nl) / (2.0 * nl);
}

glm::dvec3 LightMatchPoint(const Scene& scene)
{
  const Bounds b = scene.WorldBounds();
  return b.Empty() ? glm::dvec3(scene.camera.at) : 0.5 * (glm::dvec3(b.lo) + glm::dvec3(b.hi));
}

void PointLightsToSpheres(Scene& scene, double radius)
{
  if (!(radius > 0.0)) throw InputError(fmt::format("--area-lights {}: the radius must be > 0", radius));
  if (scene.lights.empty()) return;
  const glm::dvec3 mid = LightMatchPoint(scene);
  const double intensity = SpdLightIntensity(scene.lights.size());
  for (const Light& pl : scene.lights) {
    // Irradiance of a sphere light of radiance L at distance d: L pi r^2 / d^2;
    // a diffuse surface reflects Kd c L r^2 / d^2, the SPD shading Kd c I.
    const double d = std::max(glm::length(glm::dvec3(pl.position) - mid), 2.0 * radius);
    const glm::vec3 radiance = pl.color * float(intensity * d * d / (radius * radius));
    AddSphereLight(scene, glm::dvec3(pl.position), radius, radiance, 0);
  }
  scene.lights.clear();
}

}  // namespace cr
