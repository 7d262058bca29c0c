// CSG solids (NFF extension `csg`, kernels/csg.h): coincident faces and
// the rims where two leaves' surfaces meet. A union of two cubes sharing a
// face (boxes), a cube with a flush cut (a difference whose subtrahend
// shares four faces with it), a polyhedron cube joined to boxes on its x and
// y faces (leaves of two types in one plane: their crossings there must be
// equal to the bit for the shared face to vanish), a die's pip (a box minus
// a sphere centred on its face: the rim circle) and a lens (two spheres
// intersected: its edge circle), near the origin and the same 1e6 away.
// Rays along and across the shared faces, at the rims (off by 1e-7 to 1e-3
// of the radius), and from points on the surfaces outward.
//
// Expectation: the reference's answer (the leaves' exact spans classified
// by kernels/csg_sweep.h's rule) under check.h's tolerance; a hit on an
// internal face (a shared face that did not cancel) is no intersection of
// the solid (RefPartDistance, host/prims/csg.cpp) and counts as wrong.
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "tests/hard/gen/hard_gen.h"

namespace cr::hard {

namespace {


// The solids about centre c.
std::string Solids(const glm::dvec3& c)
{
  auto at = [&](double x, double y, double z) { return fmt::format("{} {} {}", c.x + x, c.y + y, c.z + z); };
  std::string s;
  // Two cubes sharing x = 1 (relative), union.
  s += fmt::format("csg union\n  box {} {}\n  box {} {}\ncsg end\n", at(0, 0, 0), at(1, 1, 1), at(1, 0, 0), at(2, 1, 1));
  // A flush cut: [0, 2] x [3, 4] x [0, 1] minus [1, 2] x [3, 4] x [0, 1].
  s += fmt::format("csg difference\n  box {} {}\n  box {} {}\ncsg end\n", at(0, 3, 0), at(2, 4, 1), at(1, 3, 0),
                   at(2, 4, 1));
  // A polyhedron cube [-1, 1]^3 about (0, 7, 0) and boxes on its x = 1 and
  // y = 8 faces.
  s += "csg union\n  polyhedron 6\n";
  for (int a = 0; a < 3; ++a)
    for (double sgn : {1.0, -1.0}) {
      glm::dvec3 nrm(0.0);
      nrm[a] = sgn;
      const glm::dvec3 centre = c + glm::dvec3(0, 7, 0);
      s += fmt::format("    {} {} {} {}\n", nrm.x, nrm.y, nrm.z, -(glm::dot(nrm, centre) + 1.0));
    }
  s += fmt::format("  box {} {}\n  box {} {}\ncsg end\n", at(1, 6, -1), at(2, 8, 1), at(-1, 8, -1), at(1, 9, 1));
  // A die's pip: [-1, 1]^3 about (0, -4, 0) minus the sphere of radius 0.4
  // about the face centre (1, -4, 0).
  s += fmt::format("csg difference\n  box {} {}\n  s {} 0.4\ncsg end\n", at(-1, -5, -1), at(1, -3, 1), at(1, -4, 0));
  // A lens: spheres of radius 1 about (+-0.6, -8, 0); its edge is the
  // circle of radius 0.8 in x = 0.
  s += fmt::format("csg intersection\n  s {} 1\n  s {} 1\ncsg end\n", at(-0.6, -8, 0), at(0.6, -8, 0));
  return s;
}

HardCase CsgCoincident(const GenOptions& o)
{
  Rng rng(1901);
  SceneBuilder b;
  const glm::dvec3 centres[2] = {{0.0, 0.0, 0.0}, {1e6, 0.0, -1e6}};
  for (const glm::dvec3& c : centres) ParseNFF(Solids(c), "hard-csg", b.Get());
  HardCase hc;
  hc.name = "csg/coincident";
  hc.scene = b.Finish();
  hc.expect = Expect::Reference;
  const std::size_t n = o.quick ? 1200 : 12000;
  auto off = [&]() { return std::exp(rng.Uniform(std::log(1e-7), std::log(1e-3))) * (rng.Below(2) ? 1.0 : -1.0); };
  for (std::size_t k = 0; k < n; ++k) {
    const glm::dvec3& c = centres[k % 2];
    const glm::dvec3 away = rng.UnitVector();
    const double dist = std::exp(rng.Uniform(std::log(3.0), std::log(30.0)));
    switch (k % 6) {
      case 0: {  // through the shared face of the two cubes, or along it
        const glm::dvec3 p = c + glm::dvec3(1.0, rng.Uniform(0.0, 1.0), rng.Uniform(0.0, 1.0));
        glm::dvec3 dir = away;
        if (k % 12 == 0) dir = glm::normalize(glm::dvec3(0.0, dir.y, dir.z));  // in the plane x = 1
        hc.rays.push_back(Rec(p - dist * dir, dir));
        break;
      }
      case 1: {  // at the flush cut's faces (x = 1) and shared faces
        const glm::dvec3 p = c + glm::dvec3(rng.Uniform(0.5, 1.5), rng.Uniform(3.0, 4.0), rng.Uniform(0.0, 1.0));
        const glm::dvec3 q = rng.Below(2) ? glm::dvec3(1.0, p.y - c.y, p.z - c.z) : p - c;
        hc.rays.push_back(Rec(c + q - dist * away, away));
        break;
      }
      case 2: {  // across the faces the polyhedron shares with the boxes
        const bool xface = rng.Below(2) == 0;
        const glm::dvec3 p = c + (xface ? glm::dvec3(1.0, 7.0 + rng.Uniform(-1, 1), rng.Uniform(-1, 1))
                                        : glm::dvec3(rng.Uniform(-1, 1), 8.0, rng.Uniform(-1, 1)));
        hc.rays.push_back(Rec(p - dist * away, away));
        break;
      }
      case 3: {  // at the pip's rim, from outside the face x = 1
        const double a = rng.Uniform(0.0, 2 * kPi), r = 0.4 * (1.0 + off());
        const glm::dvec3 p = c + glm::dvec3(1.0, -4.0 + r * std::cos(a), r * std::sin(a));
        glm::dvec3 dir = away;
        if (dir.x > 0.0) dir.x = -dir.x;
        hc.rays.push_back(Rec(p - dist * dir, dir));
        break;
      }
      case 4: {  // at the lens's edge
        const double a = rng.Uniform(0.0, 2 * kPi), r = 0.8 * (1.0 + off());
        const glm::dvec3 p = c + glm::dvec3(0.0, -8.0 + r * std::cos(a), r * std::sin(a));
        hc.rays.push_back(Rec(p - dist * away, away));
        break;
      }
      default: {  // from a point on a face (the die's, the cubes', the cut's), outward or along it
        glm::dvec3 p, normal;
        switch (rng.Below(3)) {
          case 0: p = c + glm::dvec3(1.0, -4.0 + rng.Uniform(-1, 1), rng.Uniform(-1, 1)); normal = {1, 0, 0}; break;
          case 1: p = c + glm::dvec3(rng.Uniform(0, 2), 1.0, rng.Uniform(0, 1)); normal = {0, 1, 0}; break;
          default: p = c + glm::dvec3(1.0, rng.Uniform(3, 4), rng.Uniform(0, 1)); normal = {1, 0, 0}; break;
        }
        glm::dvec3 dir = rng.UnitVector();
        if (glm::dot(dir, normal) < 0.0) dir -= 2.0 * glm::dot(dir, normal) * normal;
        if (k % 12 == 5) dir = glm::normalize(dir - glm::dot(dir, normal) * normal + 0.01 * normal);
        hc.rays.push_back(Rec(glm::dvec3(glm::vec3(p)), dir, 1e-4f));
        break;
      }
    }
  }
  return hc;
}

}  // namespace

void AddCsgCases(std::vector<CaseSpec>& specs)
{
  specs.push_back({"csg/coincident", "csg",
                   "CSG solids near the origin and 1e6 away: two cubes sharing a face (union), a flush cut (a "
                   "difference sharing four faces), a polyhedron cube with boxes on two of its faces (union across "
                   "leaf types), a die's pip (box minus a sphere on its face) and a lens (two spheres intersected); "
                   "rays through and along the shared faces, at the pip's rim and the lens's edge off by 1e-7..1e-3 "
                   "of the radius, and rays leaving the faces (a twelfth nearly along them). Expect: the reference's "
                   "answer; a hit on an internal (shared) face is wrong.",
                   false, [](AccelKind, const GenOptions& o) { return CsgCoincident(o); }});
}

}  // namespace cr::hard
