#include "host/cl/cl_device.h"

#include <algorithm>
#include <charconv>
#include <cstdlib>

#include <fmt/format.h>

#include "host/cl/cl_fault.h"
#include "host/core/error.h"

namespace cr {

namespace {

std::string PlatformString(const cl::Platform& p, cl_platform_info what)
{
  std::string s;
  CR_CL_CHECK(p.getInfo(what, &s), "clGetPlatformInfo");
  return s.c_str();  // drop the trailing NUL some drivers include
}

std::string DeviceString(const cl::Device& d, cl_device_info what)
{
  std::string s;
  CR_CL_CHECK(d.getInfo(what, &s), "clGetDeviceInfo");
  return s.c_str();
}

template <typename T>
T DeviceValue(const cl::Device& d, cl_device_info what)
{
  T v{};
  CR_CL_CHECK(d.getInfo(what, &v), "clGetDeviceInfo");
  return v;
}

// Oclgrind, the OpenCL device simulator (tests/test_oclgrind.cpp): a
// "GPU" that runs kernels thousands of times slower than any device, to
// check them. Never a default choice while another device exists.
bool IsSimulator(const std::string& platformName) { return platformName == "Oclgrind"; }

bool ParseIndex(std::string_view s, int& out)
{
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && p == s.data() + s.size() && out >= 0;
}

std::string Listing(const std::vector<ClDevice>& all)
{
  std::string s;
  for (const auto& d : all)
    s += fmt::format("{}{} = {}:{} {} ({})", s.empty() ? "" : ", ", d.flatIndex, d.platformIndex, d.deviceIndex,
                     d.name, d.type);
  return s;
}

// The default rule: the first GPU, else the first CPU device, else the first
// device, simulators only when there is nothing else.
const ClDevice& DefaultDevice(const std::vector<ClDevice>& all)
{
  for (const char* want : {"gpu", "cpu"})
    for (const auto& d : all)
      if (d.type == want && !d.simulator) return d;
  for (const auto& d : all)
    if (!d.simulator) return d;
  return all.front();
}

// The device `spec` names. A malformed spec is bad input (exit 2); a
// well-formed one that names no device here is a runtime error (exit 1,
// CL_DEVICE_NOT_FOUND): the same command line may name a device on another
// machine, and `--backend auto` falls back from it.
const ClDevice& NamedDevice(const std::vector<ClDevice>& all, const std::string& spec, const std::string& from)
{
  const auto colon = spec.find(':');
  int a = 0, b = 0;
  const auto notFound = [&] {
    return RuntimeError(fmt::format("OpenCL: {} '{}': no such device (CL_DEVICE_NOT_FOUND; devices: {})", from, spec,
                                    Listing(all)));
  };
  if (colon == std::string::npos) {
    if (!ParseIndex(spec, a))
      throw InputError(fmt::format("{} '{}': expected N or platform:device (devices: {})", from, spec, Listing(all)));
    if (a >= static_cast<int>(all.size())) throw notFound();
    return all[static_cast<std::size_t>(a)];
  }
  const std::string_view sv(spec);
  if (!ParseIndex(sv.substr(0, colon), a) || !ParseIndex(sv.substr(colon + 1), b))
    throw InputError(fmt::format("{} '{}': expected N or platform:device (devices: {})", from, spec, Listing(all)));
  for (const auto& d : all)
    if (d.platformIndex == a && d.deviceIndex == b) return d;
  throw notFound();
}

// A device that the driver reports unavailable (CL_DEVICE_AVAILABLE false: a
// lost or reset GPU) cannot take a context.
ClDevice CheckAvailable(const ClDevice& d)
{
  const bool injected = ClFaultInjected(ClFault::Device);
  if (!d.available || injected)
    throw RuntimeError(fmt::format("OpenCL: device {} ({}:{} {}) is not available: CL_DEVICE_NOT_AVAILABLE "
                                   "(CL_DEVICE_AVAILABLE is false){}",
                                   d.flatIndex, d.platformIndex, d.deviceIndex, d.name,
                                   injected ? ClFaultNote(ClFault::Device) : ""));
  return d;
}

}  // namespace

std::vector<ClDevice> ListClDevices()
{
  std::vector<cl::Platform> platforms;
  const cl_int status = cl::Platform::get(&platforms);
  if (status == CL_PLATFORM_NOT_FOUND_KHR || (status == CL_SUCCESS && platforms.empty()))
    throw RuntimeError("OpenCL: no platform found (no OpenCL driver is installed or the ICD loader finds none)");
  CR_CL_CHECK(status, "clGetPlatformIDs");
  // Simulators after every real platform (a stable partition of the ICD
  // loader's order), so that registering one never renumbers the others.
  std::stable_partition(platforms.begin(), platforms.end(),
                        [](const cl::Platform& p) { return !IsSimulator(PlatformString(p, CL_PLATFORM_NAME)); });
  std::vector<ClDevice> out;
  for (std::size_t pi = 0; pi < platforms.size(); ++pi) {
    std::vector<cl::Device> devices;
    const cl_int ds = platforms[pi].getDevices(CL_DEVICE_TYPE_ALL, &devices);
    if (ds == CL_DEVICE_NOT_FOUND) continue;
    CR_CL_CHECK(ds, "clGetDeviceIDs");
    for (std::size_t di = 0; di < devices.size(); ++di) {
      ClDevice d;
      d.platform = platforms[pi];
      d.device = devices[di];
      d.platformIndex = static_cast<int>(pi);
      d.deviceIndex = static_cast<int>(di);
      d.flatIndex = static_cast<int>(out.size());
      d.name = DeviceString(d.device, CL_DEVICE_NAME);
      d.platformName = PlatformString(d.platform, CL_PLATFORM_NAME);
      d.simulator = IsSimulator(d.platformName);
      d.available = DeviceValue<cl_bool>(d.device, CL_DEVICE_AVAILABLE) != CL_FALSE;
      d.platformVersion = PlatformString(d.platform, CL_PLATFORM_VERSION);
      d.driverVersion = DeviceString(d.device, CL_DRIVER_VERSION);
      d.version = DeviceString(d.device, CL_DEVICE_VERSION);
      const auto type = DeviceValue<cl_device_type>(d.device, CL_DEVICE_TYPE);
      d.type = (type & CL_DEVICE_TYPE_GPU)           ? "gpu"
               : (type & CL_DEVICE_TYPE_CPU)         ? "cpu"
               : (type & CL_DEVICE_TYPE_ACCELERATOR) ? "accelerator"
                                                     : "other";
      d.maxAllocBytes = DeviceValue<cl_ulong>(d.device, CL_DEVICE_MAX_MEM_ALLOC_SIZE);
      d.globalMemBytes = DeviceValue<cl_ulong>(d.device, CL_DEVICE_GLOBAL_MEM_SIZE);
      d.localMemBytes = DeviceValue<cl_ulong>(d.device, CL_DEVICE_LOCAL_MEM_SIZE);
      d.maxWorkGroupSize = DeviceValue<std::size_t>(d.device, CL_DEVICE_MAX_WORK_GROUP_SIZE);
      d.computeUnits = DeviceValue<cl_uint>(d.device, CL_DEVICE_MAX_COMPUTE_UNITS);
      const std::string ext = DeviceString(d.device, CL_DEVICE_EXTENSIONS);
      d.fp64 = ext.find("cl_khr_fp64") != std::string::npos;
      const auto fp = DeviceValue<cl_device_fp_config>(d.device, CL_DEVICE_SINGLE_FP_CONFIG);
      d.correctlyRoundedDivideSqrt = (fp & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) != 0;
      out.push_back(std::move(d));
    }
  }
  return out;
}

ClDevice SelectClDevice(const std::string& specArg)
{
  std::string spec = specArg;
  std::string from = "--device";
  if (spec.empty()) {
    if (const char* env = std::getenv("CELLRAY_DEVICE"); env && *env) {
      spec = env;
      from = "CELLRAY_DEVICE";
    }
  }
  std::vector<ClDevice> all = ListClDevices();
  if (all.empty()) throw RuntimeError("OpenCL: the installed platforms offer no device");
  return CheckAvailable(spec.empty() ? DefaultDevice(all) : NamedDevice(all, spec, from));
}

}  // namespace cr
