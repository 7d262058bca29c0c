// Hard cases, leaks: rays from inside closed meshes (tests/hard/gen/hard_gen_leaks.cpp).
#include <array>
#include <cmath>
#include <set>

#include "tests/hard/gen/hard_cases.h"
#include "tests/hard/hard_test_util.h"

using namespace cr;

TEST_CASE("hard: leaks, rays from inside closed meshes all hit at the first crossing")
{
  const auto results = hard_test::RunAndCheck("leaks/");
  std::set<std::string> names;
  for (const auto& r : results) names.insert(r.caseName);
  CHECK(names == std::set<std::string>{"leaks/icosphere", "leaks/split-cube", "leaks/box-room", "leaks/fan-cone"});
}

TEST_CASE("hard: leak rays aim exactly at vertices (t = 1) and edge points (t = 2^-m) of their mesh")
{
  hard::GenOptions quick;
  quick.quick = true;
  for (const hard::CaseSpec& spec : hard::CaseSpecs()) {
    if (spec.family != "leaks") continue;
    const hard::HardCase c = spec.make(AccelKind::BVH, quick);
    INFO(c.name);
    CHECK(c.rays.size() == 20000);
    if (c.scene->triangles.empty()) {
      // The box room: o + d is exactly one of its corners for about 40%.
      std::size_t atCorner = 0;
      for (const RayRecord& r : c.rays) {
        bool corner = true;
        for (int k = 0; k < 3; ++k) corner = corner && std::fabs(double(r.org[k]) + double(r.dir[k])) == 1.0;
        atCorner += corner;
      }
      CHECK(atCorner >= c.rays.size() / 4);
      continue;
    }
    std::set<std::array<float, 3>> vertices;
    for (const Triangle& t : c.scene->triangles) {
      vertices.insert({t.v0[0], t.v0[1], t.v0[2]});
      vertices.insert({t.v1[0], t.v1[1], t.v1[2]});
      vertices.insert({t.v2[0], t.v2[1], t.v2[2]});
    }
    // o + d is exactly a vertex (computed in double, compared as floats
    // only if exact): the ray passes exactly through it.
    std::size_t atVertex = 0;
    for (const RayRecord& r : c.rays) {
      std::array<double, 3> p{double(r.org[0]) + r.dir[0], double(r.org[1]) + r.dir[1], double(r.org[2]) + r.dir[2]};
      if (float(p[0]) == p[0] && float(p[1]) == p[1] && float(p[2]) == p[2] &&
          vertices.count({float(p[0]), float(p[1]), float(p[2])}))
        ++atVertex;
    }
    CHECK(atVertex >= c.rays.size() / 4);
    // Watertight by construction: each edge in two triangles (checked by the
    // generator, which throws otherwise), so V - E + F = 2.
    const std::size_t F = c.scene->triangles.size(), V = vertices.size();
    CHECK(long(V) - long(3 * F / 2) + long(F) == 2);
  }
}
