// The hard-case suite itself: its expectations hold for the fp64 reference,
// it does see the fast mode fail, and its report lists every case.
#include <string>

#include "tests/hard/gen/hard_cases.h"
#include "tests/hard/hard_test_util.h"
#include "tests/test_util.h"

using namespace cr;

namespace {

// Runs the suite as `o` says, warnings quiet, and checks that every row
// answers with 0 wrong (and, with mustRun, that none was skipped); returns
// the rays judged.
std::uint64_t RunAllRight(const HardOptions& o, bool mustRun = false)
{
  SetWarningsQuiet(true);
  const auto results = RunHardSuite(o);
  SetWarningsQuiet(false);
  std::uint64_t judged = 0;
  for (const auto& r : results) {
    INFO(o.simdVariant, " ", r.caseName, " ", std::string(AccelKindName(r.accel)), " ",
         std::string(PrecisionName(r.precision)), ": ", r.wrong, " wrong of ", r.rays, " ", r.note);
    if (mustRun) CHECK(!r.skipped);
    CHECK(r.wrong == 0);
    judged += r.rays;
  }
  return judged;
}

}  // namespace

TEST_CASE("hard: every case's expectation holds for the fp64 reference tracer")
{
  HardOptions o;
  o.quick = true;
  o.backends = {Backend::Reference};
  o.precisions = {Precision::Fp64};
  CHECK(RunAllRight(o, true) > 100000);
}

TEST_CASE("hard: the suite sees the fast mode fail (textbook quadratic, Moller-Trumbore at edges)")
{
  HardOptions o;
  o.quick = true;
  o.backends = {Backend::Scalar};
  o.precisions = {Precision::Fast};
  o.accels = {AccelKind::Grid};
  o.cases = {"tiny-far/at-origin", "leaks/icosphere"};
  const auto results = RunHardSuite(o);
  REQUIRE(results.size() == 2);
  for (const auto& r : results) {
    INFO(r.caseName, ": ", r.wrong, " wrong of ", r.rays);
    CHECK(!r.required);
    CHECK(r.wrong > r.rays / 100);
  }
}

TEST_CASE("hard: the report has a row per case and a column per structure x backend x precision")
{
  std::vector<HardCaseResult> results;
  for (const char* name : {"a/one", "b/two"})
    for (AccelKind a : {AccelKind::Grid, AccelKind::BVH})
      for (Precision p : {Precision::Fast, Precision::Robust}) {
        HardCaseResult r;
        r.caseName = name;
        r.accel = a;
        r.backend = Backend::Scalar;
        r.precision = p;
        r.rays = 10;
        r.wrong = p == Precision::Fast ? 3 : 0;
        r.required = p == Precision::Robust;
        results.push_back(r);
      }
  results[1].wrong = 2;  // a/one grid robust fails
  const std::string md = HardTableMarkdown(results);
  CHECK(md.find("| case | rays | grid scalar fast | grid scalar robust | bvh scalar fast | bvh scalar robust |") == 0);
  CHECK(md.find("| a/one | 10 | 3 | **2** | 3 | 0 |") != std::string::npos);
  CHECK(md.find("| b/two | 10 | 3 | 0 | 3 | 0 |") != std::string::npos);
  const std::string cases = HardCasesMarkdown();
  for (const hard::CaseSpec& s : hard::CaseSpecs()) CHECK(cases.find("**" + s.name + "**") != std::string::npos);
}

TEST_CASE("hard: a --case filter that names no case is bad input")
{
  HardOptions o;
  o.quick = true;
  o.cases = {"no-such-family/"};
  CHECK_THROWS_AS(RunHardSuite(o), InputError);
  o.cases = {"leaks/", "no-such-case"};
  CHECK_THROWS_AS(RunHardSuite(o), InputError);
}

TEST_CASE("hard: the SIMD hierarchical grid's packet walk answers every case, robust and fp64")
{
  // The default variant picks one walk per ray set; the suite's other tests
  // run the default, this one holds the packet walk to 0 wrong on every case
  // (`cellray hard --simd-variant single` runs the other at full size).
  for (const char* variant : {"packet"}) {
    HardOptions o;
    o.quick = true;
    o.backends = {Backend::Simd};
    o.accels = {AccelKind::HGrid};
    o.precisions = {Precision::Robust, Precision::Fp64};
    o.simdVariant = variant;
    CHECK(RunAllRight(o) > 100000);
  }
}

TEST_CASE("hard: the SIMD ray-margin octree's lazy packet search answers every case, robust and fp64")
{
  // The tracer searches lazily only in trees with a long chain (the teapot in
  // a stadium, tests/test_octree.cpp); here it is made to everywhere, on every
  // case's cell planes and corners.
  const test::ScopedEnv lazy("CELLRAY_OCTREE_LAZY", "on");
  HardOptions o;
  o.quick = true;
  o.backends = {Backend::Simd};
  o.accels = {AccelKind::Octree};
  o.params.octreeMargin = "ray";
  o.precisions = {Precision::Robust, Precision::Fp64};
  o.simdVariant = "packet";
  CHECK(RunAllRight(o) > 100000);
  // A bad value is an input error.
  const test::ScopedEnv bad("CELLRAY_OCTREE_LAZY", "sometimes");
  TraceConfig cfg;
  cfg.backend = Backend::Simd;
  cfg.accel = AccelKind::Octree;
  cfg.params.octreeMargin = "ray";
  CHECK_THROWS_AS(CreateTracer(test::CachedScene(test::SpdPath("tetra")), cfg), InputError);
}
