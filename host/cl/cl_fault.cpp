#include "host/cl/cl_fault.h"

#include <cstdlib>
#include <string_view>

#include <fmt/format.h>

#include "host/core/error.h"

namespace cr {

namespace {

struct FaultName {
  ClFault fault;
  const char* name;
};
constexpr FaultName kFaults[] = {{ClFault::Build, "build"},   {ClFault::Kernel, "kernel"},
                                 {ClFault::Alloc, "alloc"},   {ClFault::Launch, "launch"},
                                 {ClFault::Device, "device"}, {ClFault::Limits, "limits"},
                                 {ClFault::LocalMem, "localmem"}};

const char* Name(ClFault f)
{
  for (const auto& e : kFaults)
    if (e.fault == f) return e.name;
  return "?";
}

}  // namespace

bool ClFaultInjected(ClFault f)
{
  const char* env = std::getenv("CELLRAY_CL_FAULT");
  if (!env || !*env) return false;
  bool found = false;
  std::string_view rest(env);
  while (!rest.empty()) {
    const auto comma = rest.find(',');
    const std::string_view item = rest.substr(0, comma);
    rest = comma == std::string_view::npos ? std::string_view() : rest.substr(comma + 1);
    if (item.empty()) continue;
    bool known = false;
    for (const auto& e : kFaults)
      if (item == e.name) {
        known = true;
        found = found || e.fault == f;
      }
    if (!known)
      throw InputError(fmt::format("CELLRAY_CL_FAULT '{}': unknown fault '{}' (expected a comma-separated list of "
                                   "build, kernel, alloc, launch, device, limits, localmem)",
                                   env, item));
  }
  return found;
}

std::string ClFaultNote(ClFault f) { return fmt::format(" [injected: CELLRAY_CL_FAULT={}]", Name(f)); }

}  // namespace cr
