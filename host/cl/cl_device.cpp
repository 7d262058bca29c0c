#include "cl/cl_device.h"

#include <charconv>
#include <cstdlib>

#include <fmt/format.h>

#include "core/error.h"

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

}  // namespace

std::vector<ClDevice> ListClDevices()
{
  std::vector<cl::Platform> platforms;
  const cl_int status = cl::Platform::get(&platforms);
  if (status == CL_PLATFORM_NOT_FOUND_KHR || (status == CL_SUCCESS && platforms.empty()))
    throw RuntimeError("OpenCL: no platform found (no OpenCL driver is installed or the ICD loader finds none)");
  CR_CL_CHECK(status, "clGetPlatformIDs");
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
  if (spec.empty()) {
    for (const char* want : {"gpu", "cpu"})
      for (const auto& d : all)
        if (d.type == want) return d;
    return all.front();
  }
  const auto colon = spec.find(':');
  int a = 0, b = 0;
  if (colon == std::string::npos) {
    if (!ParseIndex(spec, a))
      throw InputError(fmt::format("{} '{}': expected N or platform:device (devices: {})", from, spec, Listing(all)));
    if (a >= static_cast<int>(all.size()))
      throw InputError(fmt::format("{} '{}': no such device (devices: {})", from, spec, Listing(all)));
    return all[static_cast<std::size_t>(a)];
  }
  if (!ParseIndex(std::string_view(spec).substr(0, colon), a) || !ParseIndex(std::string_view(spec).substr(colon + 1), b))
    throw InputError(fmt::format("{} '{}': expected N or platform:device (devices: {})", from, spec, Listing(all)));
  for (const auto& d : all)
    if (d.platformIndex == a && d.deviceIndex == b) return d;
  throw InputError(fmt::format("{} '{}': no such device (devices: {})", from, spec, Listing(all)));
}

}  // namespace cr
