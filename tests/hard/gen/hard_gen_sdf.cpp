// SDF blocks (NFF extension `sdf`, kernels/sdf.h): rays that graze their
// surfaces (their closest approach within a few eps of a ball, a torus and a
// smoothly joined blob), rays that start on the surfaces (the shadow and
// reflection rays of a renderer: they must not find the surface they leave),
// the same blocks 1e6 from the origin seen from nearby (the block keeps its
// coordinates about its own centre), and relaxed marches that overshoot
// thin features (a torus tube of 0.02 and a capsule of 0.01 behind a
// bound's far side).
//
// Expectation: the reference's answer under check.h's tolerance, which
// allows a hit on a block to lie within 2 eps of the reference's surface
// (HitSlack, docs/TOLERANCE.md); a grazing ray that one side finds within eps
// and the other passes is a flip explained by that slack, never wrong.
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "tests/hard/gen/hard_gen.h"

namespace cr::hard {

namespace {


// The blocks about centre c: a ball, a torus (about y) and a blob (two balls
// in a smooth union with a capsule), then a thin torus and a thin capsule;
// eps 1e-3, budget 512, relaxation 1.8 (the strongest over-relaxation).
std::string Blocks(const glm::dvec3& c)
{
  auto at = [&](double x, double y, double z) { return fmt::format("{} {} {}", c.x + x, c.y + y, c.z + z); };
  std::string s;
  s += fmt::format("sdf {} {} 0.001 512 1.8\n  sphere {} 1\nsdf end\n", at(-1.2, -1.2, -1.2), at(1.2, 1.2, 1.2),
                   at(0, 0, 0));
  s += fmt::format("sdf {} {} 0.001 512 1.8\n  torus {} 1 0.3\nsdf end\n", at(2.6, -0.5, -1.5), at(5.4, 0.5, 1.5),
                   at(4, 0, 0));
  s += fmt::format("sdf {} {} 0.001 512 1.8\n  sphere {} 0.6\n  sphere {} 0.5\n  smooth 0.3\n"
                   "  capsule {} {} 0.15\n  union\nsdf end\n",
                   at(-5.6, -1.2, -1.2), at(-2.4, 1.2, 1.2), at(-4.4, 0, 0), at(-3.6, 0.3, 0), at(-5.2, -0.6, 0),
                   at(-2.8, -0.6, 0.5));
  s += fmt::format("sdf {} {} 0.001 512 1.8\n  torus {} 0.8 0.02\n  capsule {} {} 0.01\n  union\nsdf end\n",
                   at(-1, -1, 3), at(1, 1, 5), at(0, 0, 4), at(-0.9, 0.5, 4), at(0.9, -0.5, 4.2));
  return s;
}

HardCase Grazing(const GenOptions& o)
{
  Rng rng(601);
  SceneBuilder b;
  const glm::dvec3 centres[2] = {{0.0, 0.0, 0.0}, {1e6, 0.0, -1e6}};
  for (const glm::dvec3& c : centres) ParseNFF(Blocks(c), "hard-sdf", b.Get());
  HardCase hc;
  hc.name = "sdf/grazing";
  hc.scene = b.Finish();
  hc.expect = Expect::Reference;
  const std::size_t n = o.quick ? 1200 : 12000;
  for (std::size_t k = 0; k < n; ++k) {
    const glm::dvec3& c = centres[k % 2];
    const glm::dvec3 away = rng.UnitVector();
    const double dist = std::exp(rng.Uniform(std::log(4.0), std::log(40.0)));
    switch (k % 4) {
      case 0: {  // tangent to the ball, off by 0..+-3 eps
        const glm::dvec3 dir = rng.UnitVector();
        glm::dvec3 side = glm::normalize(glm::cross(dir, away));
        const double off = 1.0 + 0.001 * rng.Uniform(-3.0, 3.0);
        const glm::dvec3 touch = c + off * side;
        hc.rays.push_back(Rec(touch - dist * dir, dir));
        break;
      }
      case 1: {  // grazing the torus tube's top (y = 0.3) or the blob's waist
        const bool torus = rng.Below(2) == 0;
        const glm::dvec3 p = torus ? c + glm::dvec3(4.0 + rng.Uniform(-1.3, 1.3), 0.3 + 0.001 * rng.Uniform(-3.0, 3.0),
                                                    rng.Uniform(-1.3, 1.3))
                                   : c + glm::dvec3(rng.Uniform(-4.8, -3.2), rng.Uniform(-0.7, 0.7), rng.Uniform(-0.7, 0.7));
        glm::dvec3 dir(std::cos(rng.Uniform(0.0, 2 * kPi)), 0.0, std::sin(rng.Uniform(0.0, 2 * kPi)));
        if (!torus) dir = rng.UnitVector();
        hc.rays.push_back(Rec(p - dist * dir, dir));
        break;
      }
      case 2: {  // from a point on the ball or the torus, outward or along the surface
        const glm::dvec3 nrm = rng.UnitVector();
        const bool torus = rng.Below(2) == 0;
        glm::dvec3 p, normal;
        if (torus) {
          const double a = rng.Uniform(0.0, 2 * kPi), bb = rng.Uniform(0.0, 2 * kPi);
          const glm::dvec3 ring(std::cos(a), 0.0, std::sin(a));
          normal = std::cos(bb) * ring + glm::dvec3(0.0, std::sin(bb), 0.0);
          p = c + glm::dvec3(4.0, 0.0, 0.0) + ring + 0.3 * normal;
        } else {
          normal = nrm;
          p = c + nrm;
        }
        glm::dvec3 dir = rng.UnitVector();
        if (glm::dot(dir, normal) < 0.0) dir -= 2.0 * glm::dot(dir, normal) * normal;  // leaving the surface
        if (k % 8 == 2) dir = glm::normalize(dir - glm::dot(dir, normal) * normal + 0.01 * normal);  // nearly along it
        hc.rays.push_back(Rec(glm::dvec3(glm::vec3(p)), dir, 1e-4f));
        break;
      }
      default: {  // at the thin torus and capsule, from any side
        const glm::dvec3 target = c + glm::dvec3(rng.Uniform(-0.9, 0.9), rng.Uniform(-0.5, 0.5), 4.0 + rng.Uniform(-0.2, 0.4));
        hc.rays.push_back(Rec(target - dist * away, away));
        break;
      }
    }
  }
  return hc;
}

}  // namespace

void AddSdfCases(std::vector<CaseSpec>& specs)
{
  specs.push_back({"sdf/grazing", "sdf",
                   "SDF blocks (eps 1e-3, 512 steps, relaxation 1.8): a ball, a torus, a blob of a smooth union and "
                   "a capsule, a thin torus (tube 0.02) with a thin capsule (0.01), near the origin and the same 1e6 "
                   "away; rays 4..40 away tangent to the ball within 3 eps, grazing the torus's top and the blob, "
                   "rays starting on the ball and the torus leaving them (a tenth nearly along the surface), and "
                   "rays at the thin features. Expect: the reference's answer under check.h's tolerance plus the "
                   "block's 2 eps (HitSlack).",
                   false, [](AccelKind, const GenOptions& o) { return Grazing(o); }});
}

}  // namespace cr::hard
