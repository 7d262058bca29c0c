// Hard cases on input: degenerate primitives and extreme structure
// parameters (tests/hard/gen/hard_gen_input.cpp).
#include "tests/hard/gen/hard_cases.h"
#include "tests/hard/hard_test_util.h"

using namespace cr;

TEST_CASE("hard: degenerate input (zero-area, repeated and collinear vertices, zero radii)")
{
  const auto results = hard_test::RunAndCheck("degenerate/");
  hard::GenOptions quick;
  quick.quick = true;
  for (const hard::CaseSpec& s : hard::CaseSpecs()) {
    if (s.name != "degenerate/loader") continue;
    SetWarningsQuiet(true);
    const hard::HardCase c = s.make(AccelKind::BVH, quick);
    SetWarningsQuiet(false);
    // Statements 1..7 are degenerate: skipped with a warning each, ids kept.
    CHECK(c.generatorWarnings >= 7);
    REQUIRE(c.scene->NumPrims() == 13 + 6);
    for (std::uint32_t id = 1; id <= 7; ++id) CHECK(c.scene->prims[id].nPieces == 0);
    for (std::uint32_t id : {0u, 8u, 9u, 10u, 11u, 12u}) CHECK(c.scene->prims[id].nPieces > 0);
  }
}

TEST_CASE("hard: extreme parameters give a clear error or a clamp with a warning, never a crash")
{
  const auto results = hard_test::RunAndCheck("extreme/");
  std::size_t expectedErrors = 0, clamped = 0;
  for (const auto& r : results) {
    if (r.skipped) continue;
    INFO(r.caseName, " ", std::string(AccelKindName(r.accel)), " ", std::string(BackendName(r.backend)), ": ", r.note);
    if (r.caseName == "extreme/grid-density-1e6") {
      CHECK(r.accel == AccelKind::Grid);
      CHECK(r.note.find("clamped with a warning") == 0);
      ++clamped;
    }
    if (r.caseName == "extreme/grid-density-nan" || r.caseName == "extreme/octree-depth-21" ||
        r.caseName == "extreme/bvh-leaf-1000") {
      CHECK(r.note.find("InputError as expected") == 0);
      ++expectedErrors;
    }
  }
  CHECK(expectedErrors >= 9);  // 3 cases x 3 precisions, scalar at least
  CHECK(clamped >= 3);
}
