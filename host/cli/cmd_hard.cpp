// hard: runs the hard-case suite (tests/hard/gen/hard.h) and writes its report, the
// case list and the table of wrong rays, as Markdown (docs/HARD_CASES.md is
// made with `cellray hard -o docs/HARD_CASES.md`). A stopgap until
// `cellray bench --hard` reports the same table.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "tests/hard/gen/hard.h"
#include "host/cli/commands.h"
#include "host/core/error.h"
#include "host/core/file_util.h"

namespace cr::cli {

Run RegisterHard(CLI::App& app)
{
  struct O {
    bool quick = false;
    std::vector<std::string> backends, accels, precisions, cases;
    std::string out, simdVariant;
    AccelParams params;
  };
  auto o = std::make_shared<O>();
  auto* cmd = app.add_subcommand("hard", "Run the numerically hard cases on every structure x backend x precision");
  cmd->add_flag("--quick", o->quick, "Reduced ray counts (the CI size)");
  cmd->add_option("--backend", o->backends, "Backends (default: scalar, simd, opencl where available)");
  cmd->add_option("--accel", o->accels, "Structures (default: " + AccelKindNames() + ")");
  cmd->add_option("--precision", o->precisions, "Precision modes (default: fast, robust, fp64)");
  cmd->add_option("--case", o->cases, "Case names or prefixes (default: all), e.g. leaks/");
  cmd->add_option("--simd-variant", o->simdVariant, "The SIMD backend's traversal variant: packet, single or auto")
      ->check(CLI::IsMember({"packet", "single", "ray", "auto"}));
  // Structure parameters (--octree-mailbox on, --octree-margin ray, ...) for
  // every case, over the case's own.
  AddAccelParamOptions(cmd, o->params);
  cmd->add_option("-o,--output", o->out, "Write the Markdown report here (default: stdout)");
  return [o]() {
    HardOptions opt;
    opt.quick = o->quick;
    for (const auto& b : o->backends) opt.backends.push_back(ParseBackend(b));
    for (const auto& a : o->accels) opt.accels.push_back(ParseAccelKind(a));
    for (const auto& p : o->precisions) opt.precisions.push_back(ParsePrecision(p));
    opt.cases = o->cases;
    opt.simdVariant = o->simdVariant;
    opt.params = o->params;
    opt.onResult = [](const HardCaseResult& r) {
      std::fprintf(stderr, "%-36s %-6s %-6s %-6s %s\n", r.caseName.c_str(), AccelKindName(r.accel), BackendName(r.backend),
                   PrecisionName(r.precision),
                   r.skipped ? "skip" : fmt::format("{} wrong of {}", r.wrong, r.rays).c_str());
      // A required combination that failed: its first wrong rays.
      if (r.required && r.wrong > 0 && !r.note.empty()) std::fprintf(stderr, "    %s\n", r.note.c_str());
    };
    SetWarningsQuiet(true);
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<HardCaseResult> results = RunHardSuite(opt);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    SetWarningsQuiet(false);
    std::uint64_t failures = 0;
    for (const auto& r : results)
      if (r.required && r.wrong > 0) ++failures;
    const std::string md = HardReportMarkdown(results, CommandLine(), seconds);
    if (o->out.empty())
      std::cout << md;
    else
      WriteFileAtomically(o->out, md.data(), md.size());
    std::fprintf(stderr, "cellray hard: %llu required combinations failed (%.0f s)\n",
                 static_cast<unsigned long long>(failures), seconds);
    return failures == 0 ? 0 : 1;
  };
}

}  // namespace cr::cli
