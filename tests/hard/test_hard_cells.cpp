// Hard cases, cell boundaries (tests/hard/gen/hard_gen_cells.cpp): rays on the cell
// planes of the structure under test.
#include <algorithm>

#include "tests/hard/gen/hard_cases.h"
#include "tests/hard/gen/hard_gen.h"
#include "tests/hard/hard_test_util.h"

using namespace cr;

TEST_CASE("hard: cells, rays along the planes, edges and corners of each structure's cells")
{
  hard_test::RunAndCheck("cells/");
}

TEST_CASE("hard: cell-boundary rays lie on the built structure's own planes")
{
  hard::GenOptions quick;
  quick.quick = true;
  const hard::CaseSpec* spec = nullptr;
  for (const hard::CaseSpec& s : hard::CaseSpecs())
    if (s.name == "cells/planes-edges-corners") spec = &s;
  REQUIRE(spec != nullptr);
  CHECK(spec->perAccel);
  for (AccelKind accel : kAccelKinds) {
    INFO(AccelKindName(accel));
    const hard::HardCase c = spec->make(accel, quick);
    const hard::Planes planes = hard::PlanesOf(BuildAccel(*c.scene, accel, c.params));
    auto onPlane = [&](int a, float x) {
      return std::binary_search(planes.axis[a].begin(), planes.axis[a].end(), x) || x == planes.lo[a] ||
             x == planes.hi[a];
    };
    std::size_t two = 0, one = 0, zeroDir = 0;
    for (const RayRecord& r : c.rays) {
      const int n = int(onPlane(0, r.org[0])) + int(onPlane(1, r.org[1])) + int(onPlane(2, r.org[2]));
      if (n >= 2) ++two;
      if (n >= 1) ++one;
      if (r.dir[0] == 0.0f || r.dir[1] == 0.0f || r.dir[2] == 0.0f) ++zeroDir;
    }
    // Families: edge lines (2 coordinates on planes), in a plane, corners
    // (3), through corners from afar, on the box, on a plane with tmin.
    CHECK(two >= c.rays.size() / 4);
    CHECK(one >= c.rays.size() * 2 / 3);
    CHECK(zeroDir >= c.rays.size() / 4);
    // The primitives placed on planes: axis-aligned quads and triangles
    // whose vertices all lie on one plane of the structure (grid, octree;
    // a BVH's node faces are its primitives' own bounds).
    if (accel != AccelKind::BVH) {
      std::size_t flat = 0;
      for (const Triangle& t : c.scene->triangles)
        for (int a = 0; a < 3; ++a)
          if (t.v0[a] == t.v1[a] && t.v1[a] == t.v2[a] &&
              std::binary_search(planes.axis[a].begin(), planes.axis[a].end(), t.v0[a]))
            ++flat;
      CHECK(flat >= 12);
    }
  }
}
