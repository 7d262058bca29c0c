#include <charconv>
#include <type_traits>

#include <fmt/format.h>

#include "host/cli/commands.h"
#include "host/core/error.h"

namespace cr::cli {

void AddAccelParamOptions(CLI::App* cmd, AccelParams& params)
{
#define CR_CLI_ACCEL_PARAM(f, T, opt, help)                                                        \
  if constexpr (std::is_arithmetic_v<T>)                                                          \
    cmd->add_option(opt, params.f, std::string(help) + " (0: default)")->check(CLI::NonNegativeNumber); \
  else                                                                                            \
    cmd->add_option(opt, params.f, std::string(help) + " (default: the first)");
  CR_ACCEL_PARAMS(CR_CLI_ACCEL_PARAM)
#undef CR_CLI_ACCEL_PARAM
}

void AddTracerOptions(CLI::App* cmd, TracerOptions& o)
{
  cmd->add_option("--accel", o.accel, "Acceleration structure: " + AccelKindNames())->capture_default_str();
  cmd->add_option("--backend", o.backend,
                  "Backend: auto (an OpenCL GPU if present, else simd), reference, scalar, simd, opencl, or embree "
                  "(when built with Embree)")
      ->capture_default_str();
  cmd->add_option("--precision", o.precision, "Precision mode: fast, robust or fp64")->capture_default_str();
  cmd->add_option("--threads", o.threads, "CPU threads (0: all cores)")->check(CLI::NonNegativeNumber);
  AddAccelParamOptions(cmd, o.params);
  cmd->add_option("--isa", o.isa, "SIMD instruction set: avx512, avx2, sse4 or scalar (default: best available)");
  cmd->add_option("--device", o.device, "OpenCL device: N or platform:device (default: $CELLRAY_DEVICE, first GPU, else CPU); all, or a list "
                 "N,M: every device named traces, sharing each batch");
  cmd->add_option("--variant", o.variant, "Traversal variant: simd: packet, single (ray) or auto; opencl: ray (the BVH with a stack), stackless, wide or wide-packet (bvh: 8-wide nodes with float8, for CPU devices; wide is the BVH's default on a CPU device, ray elsewhere), or packet; embree: single, packet8 or packet16 (AVX-512) (-robust: RTC_SCENE_FLAG_ROBUST); default: the backend's choice");
}

namespace {
std::string& CommandLineStore()
{
  static std::string s;
  return s;
}
}  // namespace

void SetCommandLine(int argc, char** argv)
{
  std::string s;
  for (int i = 0; i < argc; ++i) {
    std::string a = argv[i];
    if (i == 0) a = "cellray";  // not the path the binary was run from
    if (a.find_first_of(" \t'\"") != std::string::npos) a = "'" + a + "'";
    s += (i ? " " : "") + a;
  }
  CommandLineStore() = s;
}

const std::string& CommandLine() { return CommandLineStore(); }

void ParseSize(const std::string& s, int& w, int& h)
{
  auto x = s.find('x');
  auto num = [&](std::string_view t, int& v) {
    auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    return ec == std::errc() && p == t.data() + t.size() && v >= 1 && v <= 65536;
  };
  if (x == std::string::npos || !num(std::string_view(s).substr(0, x), w) || !num(std::string_view(s).substr(x + 1), h))
    throw InputError(fmt::format("--size '{}': expected WIDTHxHEIGHT, each 1..65536", s));
}

}  // namespace cr::cli
