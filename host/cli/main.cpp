// cellray: one binary, subcommands info, rays, trace, check, render, gen, hard, bench.
// Errors are caught here, once: bad input exits 2, runtime failures exit 1,
// each reported as one line `cellray: <what>` on stderr.
#include <cstdio>
#include <exception>
#include <map>
#include <new>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <tbb/global_control.h>

#include "host/cli/commands.h"
#include "host/core/error.h"
#include "host/core/version.h"
#include "host/mpi/mpi.h"

namespace {

// A failure: one line on stderr, exit code `code`. Across MPI ranks the job
// ends there (mpi::Abort), naming the rank unless it is rank 0.
int Fail(const std::string& what, int code)
{
  if (cr::mpi::Distributed()) cr::mpi::Abort(what, code);
  std::fprintf(stderr, "cellray: %s\n", what.c_str());
  return code;
}

int Main(int argc, char** argv);

}  // namespace

int main(int argc, char** argv)
{
  cr::mpi::Init(&argc, &argv);
  const int rc = Main(argc, argv);
  cr::mpi::Finalize();
  return rc;
}

namespace {

int Main(int argc, char** argv)
{
  const std::string about =
      "cellray: ray tracing with " + cr::AccelKindNames() + " on CPU SIMD and OpenCL, checked against an fp64 reference";
  CLI::App app{about};
  app.require_subcommand(1);
  app.set_version_flag("--version", fmt::format("cellray {} ({})", cr::Version(), cr::BuildCommit()));
  std::map<CLI::App*, cr::cli::Run> runs;
  cr::cli::SetCommandLine(argc, argv);
  try {
    auto add = [&](cr::cli::Run (*reg)(CLI::App&)) {
      std::size_t before = app.get_subcommands({}).size();
      cr::cli::Run run = reg(app);
      auto subs = app.get_subcommands({});
      if (subs.size() > before) runs[subs.back()] = std::move(run);
    };
    add(cr::cli::RegisterInfo);
    add(cr::cli::RegisterRays);
    add(cr::cli::RegisterTrace);
    add(cr::cli::RegisterCheck);
    add(cr::cli::RegisterRender);
    add(cr::cli::RegisterGen);
    add(cr::cli::RegisterHard);
    add(cr::cli::RegisterBench);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cellray: internal error while setting up the command line: %s\n", e.what());
    return cr::kExitRuntime;
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return Fail(std::string(e.what()) + "\ncellray: run 'cellray --help' or 'cellray <command> --help' for usage",
                cr::kExitBadInput);
  }

  try {
    for (auto& [cmd, run] : runs)
      if (cmd->parsed()) return run();
    return cr::kExitBadInput;
  } catch (const cr::InputError& e) {
    return Fail(e.what(), cr::kExitBadInput);
  } catch (const cr::RuntimeError& e) {
    return Fail(e.what(), cr::kExitRuntime);
  } catch (const std::bad_alloc&) {
    return Fail("out of memory", cr::kExitRuntime);
  } catch (const std::exception& e) {
    return Fail(e.what(), cr::kExitRuntime);
  }
}

}  // namespace
