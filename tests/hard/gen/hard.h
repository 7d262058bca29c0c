// The numerically hard cases (tests/hard/): generated scenes and ray sets,
// each with exact expectations, run for every structure x backend x precision
// mode. `cellray bench --hard` prints how many rays each combination gets
// wrong; the test suite asserts 0 for robust and fp64.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "host/accel/accel.h"
#include "host/trace/tracer.h"

namespace cr {

struct HardCaseResult;

struct HardOptions {
  std::vector<Backend> backends;      // empty: every backend available here
  std::vector<AccelKind> accels;      // empty: grid, octree, bvh
  std::vector<Precision> precisions;  // empty: fast, robust, fp64
  bool quick = false;                 // reduced ray counts (CI)
  std::vector<std::string> cases;     // empty: every case; else names or name prefixes ("leaks/")
  std::string simdVariant;            // the SIMD backend's --variant (packet, single; empty: auto)
  AccelParams params;                 // structure parameters for every case, over the case's own (0, empty: the case's)
  std::function<void(const HardCaseResult&)> onResult;  // progress: called after each combination
};

struct HardCaseResult {
  std::string caseName;  // e.g. "leaks/icosphere"
  AccelKind accel = AccelKind::BVH;
  Backend backend = Backend::Scalar;
  Precision precision = Precision::Robust;
  std::uint64_t rays = 0;
  std::uint64_t wrong = 0;  // rays whose answer breaks the case's expectation
  std::string note;         // e.g. "skipped: no OpenCL device"
  bool skipped = false;     // the backend or precision is not available here
  // Held to 0 wrong: robust and fp64; fast never (reported, not asserted).
  bool required = false;
};

std::vector<HardCaseResult> RunHardSuite(const HardOptions& options);

// Markdown table: one row per case, one column per structure x backend x mode,
// then notes (skips, expected errors, the first wrong rays of failures).
std::string HardTableMarkdown(const std::vector<HardCaseResult>& results);

// Markdown list of every case: what it generates and what it expects.
std::string HardCasesMarkdown();

// The whole report (docs/HARD_CASES.md): the case list, the table, the totals;
// `command` is the command line that produced it.
std::string HardReportMarkdown(const std::vector<HardCaseResult>& results, const std::string& command, double seconds);

}  // namespace cr
