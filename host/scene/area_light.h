// Area lights (NFF extensions `la`, `ls`, docs/FORMATS.md): emitters that are
// also visible geometry. A parallelogram `la c u v radiance` is one polygon
// (corner c, edges u and v), one-sided, emitting along u x v; a sphere
// `ls centre radius radiance` is one sphere emitting outward. Each is one
// primitive id, in file order with the geometry, and has its own material
// (black, with Material::emission and Material::light set), so a hit knows it
// met a light and which.
//
// What the integrators need of a light is here: a point sampled on it as
// seen from a shading point, with its solid-angle density (a parallelogram:
// uniform in area; a sphere: uniform in the cone it subtends), the density of
// a direction that was sampled otherwise (multiple importance sampling), and
// the radiance it emits towards a ray.
#pragma once

#include <cstdint>
#include <string>

#include <glm/glm.hpp>

namespace cr {

struct Scene;
class NffStatement;

enum class AreaLightKind : std::uint8_t { kParallelogram, kSphere };

struct AreaLight {
  AreaLightKind kind = AreaLightKind::kParallelogram;
  glm::dvec3 c{0.0};  // corner (parallelogram) or centre (sphere)
  glm::dvec3 u{0.0}, v{0.0};  // edges (parallelogram)
  glm::dvec3 n{0.0};  // unit u x v: the emitting side (parallelogram)
  double radius = 0.0;  // sphere
  double area = 0.0;
  // Largest coordinate magnitude of its defining points (a sphere's centre
  // plus its radius): the scale of a float intersector's error on it.
  double scale = 0.0;
  glm::vec3 radiance{0.0f};
  std::uint32_t prim = 0;  // its primitive id
};

// A point on a light sampled from x: `pdf` is the density of the direction
// x -> p in solid angle (0: nothing to sample, e.g. x behind a parallelogram
// or inside a sphere light); `radiance` what p sends towards x.
struct LightSample {
  glm::dvec3 p{0.0};
  glm::dvec3 n{0.0};  // the light's outward normal at p
  double pdf = 0.0;
  glm::vec3 radiance{0.0f};
};

// (s1, s2) uniform in [0, 1)^2.
LightSample SampleAreaLight(const AreaLight& l, const glm::dvec3& x, double s1, double s2);
// The solid-angle density with which SampleAreaLight(l, x, ...) picks the
// direction towards p (a point of l met from x along dir).
double AreaLightPdf(const AreaLight& l, const glm::dvec3& x, const glm::dvec3& p);
// Radiance a ray of direction dir receives from l where it meets it: the
// light's radiance, or 0 on the back of a parallelogram.
glm::vec3 AreaLightEmission(const AreaLight& l, const glm::dvec3& dir);

// A sphere light's record (centre and radius rounded to the float sphere
// that is traced); its prim is left 0.
AreaLight SphereLight(const glm::dvec3& centre, double radius, const glm::vec3& radiance);

// Reads `la` or `ls` if st is one (returns false if not): the light, its
// primitive and its material. InputError (file:line) for a flat
// parallelogram, a radius <= 0 or a negative radiance.
bool ParseAreaLight(NffStatement& st, Scene& scene);

// The SPD's intensity of each of n point lights, sqrt(n) / (2 n) (n at
// least 1; ../shared/SPD.md), and the point at which a light is matched to
// that shading when it becomes an area light or a path tracer's point
// source: the centre of the scene's bounds (the camera's `at` when empty).
double SpdLightIntensity(std::size_t nLights);
glm::dvec3 LightMatchPoint(const Scene& scene);

// render --area-lights R: every point light becomes a sphere light of radius
// R (appended to the scene, ids after the file's), with the radiance that
// gives a diffuse surface at the centre of the scene's bounds what the point
// light gave it under the SPD's shading (host/render/renderer.h).
void PointLightsToSpheres(Scene& scene, double radius);

}  // namespace cr
