// Subcommands of the `cellray` binary. Each Register* adds its subcommand to
// the app and returns the function that runs it after parsing.
#pragma once

#include <functional>
#include <string>

#include <CLI/CLI.hpp>

#include "host/trace/tracer.h"

namespace cr::cli {

using Run = std::function<int()>;

// The options every command that builds a tracer shares (TracerOptions,
// host/trace/tracer.h, which the Python API fills too).
// The structures' parameters (CR_ACCEL_PARAMS) as options of cmd.
void AddAccelParamOptions(CLI::App* cmd, AccelParams& params);
void AddTracerOptions(CLI::App* cmd, TracerOptions& o);

// Parses "WxH" (InputError on anything else).
void ParseSize(const std::string& s, int& w, int& h);

Run RegisterInfo(CLI::App& app);
Run RegisterRays(CLI::App& app);
Run RegisterTrace(CLI::App& app);
Run RegisterCheck(CLI::App& app);
Run RegisterRender(CLI::App& app);
Run RegisterGen(CLI::App& app);
Run RegisterHard(CLI::App& app);
Run RegisterBench(CLI::App& app);

// The program's command line, as typed (recorded by bench in results.json).
void SetCommandLine(int argc, char** argv);
const std::string& CommandLine();

}  // namespace cr::cli
