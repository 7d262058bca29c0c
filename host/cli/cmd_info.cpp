#include <iostream>

#include <nlohmann/json.hpp>
#include <tbb/info.h>

#include "cl/cl_info.h"
#include "cli/commands.h"

namespace cr::cli {

static std::string DetectIsa()
{
#if defined(__x86_64__) || defined(__i386__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return "avx2";
  if (__builtin_cpu_supports("sse4.1")) return "sse4";
#endif
  return "scalar";
}

Run RegisterInfo(CLI::App& app)
{
  auto* cmd = app.add_subcommand("info", "OpenCL platforms and devices, SIMD ISA, build type (JSON)");
  return [cmd]() {
    (void)cmd;
    nlohmann::json j;
    j["opencl_platforms"] = OpenCLInventory();
    j["simd_isa"] = DetectIsa();
    j["cpu_threads"] = tbb::info::default_concurrency();
#ifdef NDEBUG
    j["build_type"] = "release";
#else
    j["build_type"] = "debug";
#endif
    std::cout << j.dump(2) << std::endl;
    return 0;
  };
}

}  // namespace cr::cli
