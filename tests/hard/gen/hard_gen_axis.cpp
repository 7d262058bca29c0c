// Axis-parallel and near-axis rays: direction components +0, -0, +-1e-30
// and +-1e-7 beside a main component +-1 (the slab tests' 0 * inf, the
// shear constants of the watertight test, the cone quadric with a vanishing
// leading coefficient), through the centres, rims, vertices, edge midpoints
// and axes of spheres, triangles and cones, and from random origins. A
// second case uses subnormal components (1e-40, 1.4e-45: 1/d overflows to
// inf in float, and a device may flush them to zero); a third scales whole
// directions to lengths from 1e-30 to 1e30.
#include <cmath>

#include "tests/hard/gen/hard_gen.h"

namespace cr::hard {

namespace {

// Spheres, triangles (random and in axis planes), cones (random axes and
// along the axes) in [-4, 4]^3, with the points rays aim at.
std::shared_ptr<const Scene> AxisScene(std::vector<glm::dvec3>& aims)
{
  Rng rng(301);
  SceneBuilder b;
  auto box = [&] { return rng.InBox(glm::dvec3(-3.5), glm::dvec3(3.5)); };
  for (int i = 0; i < 10; ++i) {
    const glm::dvec3 c = i == 0 ? glm::dvec3(0.0) : box();
    const double r = rng.Uniform(0.15, 0.6);
    b.Sphere(c, r);
    aims.push_back(c);
    for (int a = 0; a < 3; ++a) {
      glm::dvec3 e(0.0);
      e[a] = r;
      aims.push_back(c + e);
      aims.push_back(c - e);
    }
  }
  for (int i = 0; i < 10; ++i) {
    const glm::dvec3 c = box();
    glm::dvec3 v[3];
    for (auto& p : v) p = c + 0.8 * rng.UnitVector();
    if (i % 2) {  // in an axis plane
      const int a = i % 3;
      for (auto& p : v) p[a] = c[a];
    }
    b.Triangle(v[0], v[1], v[2]);
    glm::dvec3 vf[3];
    for (int k = 0; k < 3; ++k) vf[k] = glm::dvec3(glm::vec3(v[k]));
    for (int k = 0; k < 3; ++k) {
      aims.push_back(vf[k]);
      aims.push_back(0.5 * (vf[k] + vf[(k + 1) % 3]));
    }
    aims.push_back((vf[0] + vf[1] + vf[2]) / 3.0);
  }
  for (int i = 0; i < 8; ++i) {
    const glm::dvec3 c = box();
    glm::dvec3 axis = rng.UnitVector();
    if (i < 3) axis = glm::dvec3(i == 0, i == 1, i == 2);  // along x, y, z
    const double r0 = rng.Uniform(0.2, 0.5), r1 = i % 2 ? r0 : rng.Uniform(0.0, 0.4);
    b.Cone(c, r0, c + 1.2 * axis, r1);
    aims.push_back(c);
    aims.push_back(c + 1.2 * axis);
    aims.push_back(c + 0.6 * axis);
  }
  return b.Finish();
}

std::vector<RayRecord> AxisRays(const std::vector<glm::dvec3>& aims, const std::vector<float>& tiny, std::size_t count,
                                std::uint64_t seed)
{
  Rng rng(seed);
  std::vector<RayRecord> rays;
  rays.reserve(count);
  while (rays.size() < count) {
    const int k = int(rng.Below(3)), u = (k + 1) % 3, w = (k + 2) % 3;
    const float s = rng.Uniform() < 0.5 ? 1.0f : -1.0f;
    glm::vec3 o;
    if (rng.Uniform() < 0.75) {
      // Through an aim point: its other two coordinates exactly.
      o = glm::vec3(aims[rng.Below(std::uint32_t(aims.size()))]);
      o[k] -= s * 6.0f;
    } else {
      o = glm::vec3(rng.InBox(glm::dvec3(-5), glm::dvec3(5)));
    }
    glm::vec3 d;
    d[k] = s;
    d[u] = tiny[rng.Below(std::uint32_t(tiny.size()))];
    d[w] = tiny[rng.Below(std::uint32_t(tiny.size()))];
    rays.push_back(RecF(o, d));
  }
  return rays;
}

HardCase AxisCase(const char* name, const std::vector<float>& tiny, const GenOptions& o, std::uint64_t seed)
{
  std::vector<glm::dvec3> aims;
  HardCase c;
  c.name = name;
  c.scene = AxisScene(aims);
  c.rays = AxisRays(aims, tiny, o.quick ? 6000 : 60000, seed);
  c.expect = Expect::Reference;
  return c;
}

// AxisCase's rays with each whole direction multiplied by one of `factors`
// in turn: directions of length 1e-30 (d.d is 0 in float) up to 1e30 (d.d
// overflows).
HardCase ScaledAxisCase(const char* name, const std::vector<float>& factors, const GenOptions& o, std::uint64_t seed)
{
  HardCase c = AxisCase(name, {0.0f, -0.0f, 1e-7f, -1e-7f}, o, seed);
  for (std::size_t i = 0; i < c.rays.size(); ++i)
    for (float& d : c.rays[i].dir) d *= factors[i % factors.size()];
  return c;
}

}  // namespace

void AddAxisCases(std::vector<CaseSpec>& specs)
{
  specs.push_back({"axis/zero-and-tiny", "axis",
                   "10 spheres, 10 triangles (half in axis planes), 8 cones (3 along the axes) in [-4,4]^3. Rays "
                   "with a main component +-1 and the other two drawn from {+0, -0, +-1e-30, +-1e-7}, 3/4 through "
                   "exact centres, rims, vertices, edge midpoints and cone axes, 1/4 from random origins. Expect: "
                   "the reference's answer, closest and occlusion.",
                   false, [](AccelKind, const GenOptions& o) {
                     return AxisCase("axis/zero-and-tiny", {0.0f, -0.0f, 1e-30f, -1e-30f, 1e-7f, -1e-7f}, o, 302);
                   }});
  specs.push_back({"axis/subnormal", "axis",
                   "The same scene, the other components drawn from {+-1e-40, +-1.4e-45, +-1e-38}: subnormal or "
                   "near the bottom of the float range, where 1/d overflows to inf and a device may flush to "
                   "zero. Expect: the reference's answer.",
                   false, [](AccelKind, const GenOptions& o) {
                     return AxisCase("axis/subnormal", {1e-40f, -1e-40f, 1.4e-45f, -1.4e-45f, 1e-38f, -1e-38f}, o, 303);
                   }});
  specs.push_back({"axis/scaled-directions", "axis",
                   "The same scene, rays with a main component +-1 and the other two drawn from {+0, -0, +-1e-7}, "
                   "each whole direction then multiplied by one of 1e-30, 1e-20, 1e-12, 1e12, 1e20, 1e30: a "
                   "direction of length 1e-30 has d.d = 0 in float, one of 1e30 d.d = inf (the backends trace "
                   "such rays scaled by a power of two, host/trace/direction_scale.h). Expect: the reference's "
                   "answer.",
                   false, [](AccelKind, const GenOptions& o) {
                     return ScaledAxisCase("axis/scaled-directions", {1e-30f, 1e-20f, 1e-12f, 1e12f, 1e20f, 1e30f}, o,
                                           304);
                   }});
}

}  // namespace cr::hard
