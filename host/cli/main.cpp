// cellray: one binary, subcommands info, rays, trace, check, render, gen, hard, bench.
// Errors are caught here, once: bad input exits 2, runtime failures exit 1,
// each reported as one line `cellray: <what>` on stderr.
#include <cstdio>
#include <exception>
#include <map>
#include <new>

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include "host/cli/commands.h"
#include "host/core/error.h"

int main(int argc, char** argv)
{
  const std::string about =
      "cellray: ray tracing with " + cr::AccelKindNames() + " on CPU SIMD and OpenCL, checked against an fp64 reference";
  CLI::App app{about};
  app.require_subcommand(1);
  app.set_version_flag("--version", "cellray 0.1.0");
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
    std::fprintf(stderr, "cellray: %s\n", e.what());
    std::fprintf(stderr, "cellray: run 'cellray --help' or 'cellray <command> --help' for usage\n");
    return cr::kExitBadInput;
  }

  try {
    for (auto& [cmd, run] : runs)
      if (cmd->parsed()) return run();
    return cr::kExitBadInput;
  } catch (const cr::InputError& e) {
    std::fprintf(stderr, "cellray: %s\n", e.what());
    return cr::kExitBadInput;
  } catch (const cr::RuntimeError& e) {
    std::fprintf(stderr, "cellray: %s\n", e.what());
    return cr::kExitRuntime;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "cellray: out of memory\n");
    return cr::kExitRuntime;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cellray: %s\n", e.what());
    return cr::kExitRuntime;
  }
}
