// Tiny and far: spheres of radius 1e-4 at distance 1e4 from the camera
// (Hearn & Baker's example of catastrophic cancellation: the textbook
// discriminant b^2 - 4ac subtracts two numbers near 4e16 whose difference is
// about 4), and the same scene translated by 1e5 and 1e7, camera included.
//
// What float32 can resolve. Every tracer, fp64 included, gets float data:
// the scene's centres and the rays' origins and directions. At 1e7 the
// float spacing is 1 (ulp(1e7) = 1) and at 1e5 it is 2^-7, both far above
// the radius: an intended centre at 1e7 + 7001.3 is stored as 1e7 + 7001,
// and no origin offset finer than 1 can be written. The generator therefore
// places camera and centres on float values and aims with directions that
// float represents (a sphere's direction component that is 0 can carry an
// offset of 1e-5); expectations are computed from the stored data, the only
// data anyone traces. Translation then costs the robust kernel nothing:
// o - c is exact (Sterbenz) when o and c are floats within a factor 2, so
// shift-1e5 and shift-1e7 must pass exactly like at-origin.
// Two cases ask for more than plain float arithmetic resolves: origins
// jittered by less than ulp(|c|) / 2 (o - c in float loses the jitter), and
// two spheres whose surfaces are closer along the ray than one ulp of t
// (float t cannot order them). Robust mode resolves both with error-free
// transformations (kernels/intersect.h: Sphere_IntersectDf where the float
// discriminant is undecided, Sphere_TieOrder at an exact tie of t), so they
// are held to 0 like every other case.
#include <cmath>

#include "tests/hard/gen/hard_gen.h"

namespace cr::hard {

namespace {

constexpr double kRadius = 1e-4;
constexpr double kTinyFarRelTolT = 0x1p-20;

// Offsets of the sphere centres from the camera, |offset| = 1e4 (the last
// two only up to rounding).
const glm::dvec3 kOffsets[] = {{1e4, 0, 0},     {0, -1e4, 0},          {0, 0, 1e4},          {6e3, 8e3, 0},
                               {0, -6e3, 8e3},  {-8e3, 0, -6e3},       {7001.3, -7141.1, 0}, {0, 5000.25, -8660.3},
                               {-1e4, 0, 0},    {4082.5, 4082.5, 8165.0}};

// Aimed rays from camera T: per sphere, half through the disc of radius
// 0.9 r (hits), half passing at 1.2 r .. 3 r from the centre (misses), the
// offsets carried by the direction components that are 0.
HardCase Aimed(const char* name, const glm::dvec3& T, const GenOptions& o)
{
  Rng rng(401);
  SceneBuilder b;
  std::vector<std::uint32_t> ids;
  for (const glm::dvec3& off : kOffsets) ids.push_back(b.Sphere(T + off, kRadius));
  HardCase c;
  c.name = name;
  c.scene = b.Finish();
  c.expect = Expect::Target;
  c.relTolT = kTinyFarRelTolT;
  const std::size_t perSphere = o.quick ? 200 : 2000;
  const glm::vec3 tf(T);
  for (std::size_t s = 0; s < c.scene->spheres.size(); ++s) {
    const glm::dvec3 centre = D(c.scene->spheres[s].center);
    const glm::dvec3 base = centre - D(tf);  // exact: floats within a factor 2, or T = 0
    int free[3], nFree = 0;
    for (int a = 0; a < 3; ++a)
      if (base[a] == 0.0) free[nFree++] = a;
    for (std::size_t k = 0; k < perSphere; ++k) {
      const bool hit = k % 2 == 0 || nFree == 0;
      glm::dvec3 dir = base;
      if (nFree > 0) {
        const double rho = hit ? 0.9 * kRadius * std::sqrt(rng.Uniform()) : kRadius * rng.Uniform(1.2, 3.0);
        const double phi = rng.Uniform(0.0, 6.283185307179586);
        dir[free[0]] = nFree == 2 ? rho * std::cos(phi) : (rng.Uniform() < 0.5 ? rho : -rho);
        if (nFree == 2) dir[free[1]] = rho * std::sin(phi);
      }
      c.rays.push_back(RecF(tf, glm::vec3(dir)));
      c.target.push_back(hit ? ids[s] : CR_NO_HIT);
    }
  }
  return c;
}

// Origins jittered around the camera at 0, directions exactly to the
// centres: the ray passes at the jitter's distance from the centre, within
// 0.9 r (a hit) or at 1.5 .. 2.4 r (a miss).
HardCase Jittered(const GenOptions& o)
{
  Rng rng(402);
  SceneBuilder b;
  std::vector<std::uint32_t> ids;
  for (const glm::dvec3& off : kOffsets) ids.push_back(b.Sphere(off, kRadius));
  HardCase c;
  c.name = "tiny-far/jittered-origins";
  c.scene = b.Finish();
  c.expect = Expect::Target;
  c.relTolT = kTinyFarRelTolT;
  const std::size_t perSphere = o.quick ? 200 : 2000;
  for (std::size_t s = 0; s < c.scene->spheres.size(); ++s) {
    const glm::dvec3 dir = D(c.scene->spheres[s].center);
    const glm::dvec3 u = glm::normalize(glm::cross(dir, glm::dvec3(0.3, -0.5, 0.7)));
    const glm::dvec3 w = glm::normalize(glm::cross(dir, u));
    for (std::size_t k = 0; k < perSphere; ++k) {
      const bool hit = k % 2 == 0;
      const double rho = hit ? 0.9 * kRadius * std::sqrt(rng.Uniform()) : kRadius * rng.Uniform(1.5, 2.4);
      const double phi = rng.Uniform(0.0, 6.283185307179586);
      const glm::dvec3 jitter = rho * (std::cos(phi) * u + std::sin(phi) * w);
      c.rays.push_back(RecF(glm::vec3(jitter), glm::vec3(dir)));
      c.target.push_back(hit ? ids[s] : CR_NO_HIT);
    }
  }
  return c;
}

// Two spheres on the +x axis: A (radius 1e-4 at 1e4, id 1) in front of B
// (radius 5e-4 at 1e4 + 2^-10, id 0); their front surfaces are 5.8e-4 apart
// along the ray, less than ulp(1e4) = 9.8e-4: float t cannot order them.
HardCase BelowUlp(const GenOptions& o)
{
  Rng rng(403);
  SceneBuilder b;
  b.Sphere({1e4 + 0x1p-10, 0, 0}, 5e-4);
  const std::uint32_t a = b.Sphere({1e4, 0, 0}, kRadius);
  HardCase c;
  c.name = "tiny-far/depth-below-ulp";
  c.scene = b.Finish();
  c.expect = Expect::Target;
  c.relTolT = kTinyFarRelTolT;
  const std::size_t n = o.quick ? 400 : 4000;
  for (std::size_t k = 0; k < n; ++k) {
    const double rho = 0.8 * kRadius * std::sqrt(rng.Uniform()), phi = rng.Uniform(0.0, 6.283185307179586);
    c.rays.push_back(Rec({0, 0, 0}, {1e4, rho * std::cos(phi), rho * std::sin(phi)}));
    c.target.push_back(a);
  }
  return c;
}

}  // namespace

void AddTinyFarCases(std::vector<CaseSpec>& specs)
{
  const char* expect =
      " Expect: the sphere's id, t within 2^-20 relative of the reference's (float t cannot place the hit on a "
      "1e-4 sphere at 1e4 any closer than ~6 radii); rays passing at 1.2..3 radii: a miss.";
  specs.push_back({"tiny-far/at-origin", "tiny-far",
                   std::string("10 spheres of radius 1e-4 at distance 1e4 from the camera at the origin, on the "
                               "axes, in coordinate planes and in general position; rays from the camera.") +
                       expect,
                   false, [](AccelKind, const GenOptions& o) { return Aimed("tiny-far/at-origin", {0, 0, 0}, o); }});
  specs.push_back({"tiny-far/shift-1e5", "tiny-far",
                   std::string("The same scene and camera translated by (1e5, 1e5, -1e5) (float spacing 2^-7: "
                               "centres snapped to it).") +
                       expect,
                   false,
                   [](AccelKind, const GenOptions& o) { return Aimed("tiny-far/shift-1e5", {1e5, 1e5, -1e5}, o); }});
  specs.push_back({"tiny-far/shift-1e7", "tiny-far",
                   std::string("Translated by (1e7, -1e7, 1e7) (float spacing 1: centres snapped to integers; o - c "
                               "stays exact).") +
                       expect,
                   false,
                   [](AccelKind, const GenOptions& o) { return Aimed("tiny-far/shift-1e7", {1e7, -1e7, 1e7}, o); }});
  specs.push_back({"tiny-far/jittered-origins", "tiny-far",
                   "Camera at the origin jittered perpendicular to the line of sight, directions exactly to the "
                   "centres: by up to 0.9 radii (expect the sphere's id, t within 2^-20) or by 1.5..2.4 radii (expect "
                   "a miss). The jitter is below half an ulp of the centres' coordinates: o - c in float loses it "
                   "(robust recovers it exactly).",
                   false, [](AccelKind, const GenOptions& o) { return Jittered(o); }});
  specs.push_back({"tiny-far/depth-below-ulp", "tiny-far",
                   "Two spheres on the x axis whose front surfaces are 5.8e-4 apart at distance 1e4 (less than one "
                   "float ulp of t: their float distances tie); the front one has the higher id. Expect: the front "
                   "sphere (robust orders the tie in double-float).",
                   false, [](AccelKind, const GenOptions& o) { return BelowUlp(o); }});
}

}  // namespace cr::hard
