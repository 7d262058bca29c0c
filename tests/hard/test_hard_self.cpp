// Hard cases, self-intersection (tests/hard/gen/hard_gen_self.cpp): secondary rays
// from scene/surface.h OffsetRayOrigin must not find their own surface.
#include <cmath>

#include "tests/hard/gen/hard_cases.h"
#include "host/reference/reference.h"
#include "tests/hard/hard_test_util.h"

using namespace cr;

TEST_CASE("hard: secondary rays never re-hit their own surface near the origin")
{
  hard_test::RunAndCheck("self/");
}

TEST_CASE("hard: offset origins are off the surface they leave, in exact arithmetic")
{
  hard::GenOptions quick;
  quick.quick = true;
  for (const hard::CaseSpec& spec : hard::CaseSpecs()) {
    if (spec.family != "self") continue;
    const hard::HardCase c = spec.make(AccelKind::BVH, quick);
    INFO(c.name);
    REQUIRE(c.rays.size() == 3000);
    const ref::ReferenceTracer tr(*c.scene);
    std::size_t convex = 0;
    for (std::size_t i = 0; i < c.rays.size(); ++i) {
      const RayRecord& r = c.rays[i];
      // OffsetRayOrigin moves the point by at least 2^-19 S along the normal.
      const double dist = tr.DistanceToPrim(c.target[i], glm::dvec3(r.org[0], r.org[1], r.org[2]));
      CHECK(dist >= 0x1p-20 * tr.PrimScale(c.target[i]));
      convex += std::isinf(c.ownT[i]);
    }
    // Most rays leave a convex or flat surface on its outer side: their own
    // primitive must never be reported.
    CHECK(convex > c.rays.size() / 2);
  }
}
