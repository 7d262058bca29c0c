// Shared by the hard-case tests: runs cases of the suite (tests/hard/gen/hard.h) on
// every structure x backend available here in robust and fp64 precision and
// asserts 0 wrong rays for every required combination; fast precision runs on
// the scalar backend only, its counts reported without being asserted (the
// SIMD and OpenCL fast kernels answer as the scalar ones: test_simd.cpp and
// the Oclgrind sweeps; `cellray hard` runs fast on every backend). Fast on
// every backend had cost 8 more every-type PoCL programs and their traces in
// CI, for figures no test reads.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "tests/test_util.h"

#include "tests/hard/gen/hard.h"
#include "host/core/error.h"

namespace cr::hard_test {

// OpenCL programs built by the tests persist under the build tree (as in
// test_opencl.cpp), so that only the first test process pays the compiler.
// The hard cases' scenes hold many different sets of primitive types: their
// programs are built with every type (CELLRAY_CL_TYPES=all, unless set), 24
// programs where the specialised ones were 144 (3.7 min of PoCL compiling
// cold, 1.5 min with every type). The specialised programs are checked by
// the conformance and Oclgrind tests; `cellray hard` builds them. Both
// settings hold for the scope of one test and are restored after it: the
// tests that follow build specialised programs, as users' runs do (with
// every type leaking into them, PoCL 3.1's compiler crashed on the robust
// ray-margin octree's packet kernel: docs/OPENCL.md).
class TestProgramCache {
 public:
  TestProgramCache()
      : dir_("CELLRAY_CACHE_DIR",
             (std::filesystem::path(CELLRAY_BINARY).parent_path().parent_path() / "test-cache" / "opencl").string())
  {
    if (std::getenv("CELLRAY_CL_TYPES") == nullptr) types_.emplace("CELLRAY_CL_TYPES", "all");
  }

 private:
  test::ScopedEnv dir_;
  std::optional<test::ScopedEnv> types_;
};

// Runs the cases named by `prefix` (quick size) and checks the results.
inline std::vector<HardCaseResult> RunAndCheck(const std::string& prefix)
{
  const TestProgramCache cache;
  HardOptions o;
  o.quick = true;
  o.cases = {prefix};
  o.precisions = {Precision::Robust, Precision::Fp64};
  HardOptions fast = o;
  fast.precisions = {Precision::Fast};
  fast.backends = {Backend::Scalar};
  SetWarningsQuiet(true);
  std::vector<HardCaseResult> results = RunHardSuite(o);
  for (HardCaseResult& r : RunHardSuite(fast)) results.push_back(std::move(r));
  SetWarningsQuiet(false);
  REQUIRE(!results.empty());
  std::set<std::string> skips;
  for (const HardCaseResult& r : results) {
    const std::string combo = std::string(AccelKindName(r.accel)) + " " + BackendName(r.backend) + " " +
                              PrecisionName(r.precision);
    if (r.skipped) {
      skips.insert(std::string(BackendName(r.backend)) + " " + PrecisionName(r.precision) + ": " + r.note);
      continue;
    }
    if (r.required) {
      INFO(r.caseName, " ", combo, ": ", r.wrong, " wrong of ", r.rays, "; ", r.note);
      CHECK(r.wrong == 0);
    } else if (r.wrong > 0) {
      MESSAGE("reported, not asserted: ", r.caseName, " ", combo, ": ", r.wrong, " wrong of ", r.rays);
    }
  }
  // A combination that cannot run here is said loudly, never passed silently.
  for (const std::string& s : skips) std::fprintf(stderr, "cellray_tests: *** hard cases SKIPPED for %s ***\n", s.c_str());
  return results;
}

}  // namespace cr::hard_test
