#include <iostream>

#include <nlohmann/json.hpp>
#include <tbb/info.h>

#include "host/cl/cl_info.h"
#include "host/cli/commands.h"
#include "simd/isa.h"

namespace cr::cli {

Run RegisterInfo(CLI::App& app)
{
  auto* cmd = app.add_subcommand("info", "OpenCL platforms and devices, SIMD ISA, build type (JSON)");
  return [cmd]() {
    (void)cmd;
    nlohmann::json j;
    j["opencl_platforms"] = OpenCLInventory();
    j["simd_isa"] = simd::IsaName(simd::BestIsa());
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
