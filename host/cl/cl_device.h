// OpenCL platform and device discovery and choice.
//
// A device is named by its flat index over all devices of all platforms
// ("2"), or by "platform:device" ("0:1"). Platforms come in the ICD loader's
// order, except that simulators (Oclgrind, when its ICD is registered) come
// after all others. The choice comes from --device, else $CELLRAY_DEVICE,
// else the first GPU, else the first CPU device, else the first device of any
// kind, a simulator only when it is the only device there is (as under the
// `oclgrind` wrapper, which replaces the OpenCL library).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "host/cl/cl_api.h"

namespace cr {

struct ClDevice {
  cl::Platform platform;
  cl::Device device;
  int platformIndex = 0;
  int deviceIndex = 0;   // within its platform
  int flatIndex = 0;     // over all platforms
  std::string name;
  std::string platformName;
  std::string platformVersion;
  std::string driverVersion;
  std::string version;   // CL_DEVICE_VERSION
  std::string type;      // "gpu", "cpu", "accelerator" or "other"
  std::uint64_t maxAllocBytes = 0;
  std::uint64_t globalMemBytes = 0;
  std::uint64_t localMemBytes = 0;
  std::size_t maxWorkGroupSize = 0;
  std::uint32_t computeUnits = 0;
  bool simulator = false;                    // Oclgrind: never chosen by default while another device exists
  bool available = true;                     // CL_DEVICE_AVAILABLE
  bool fp64 = false;                         // cl_khr_fp64
  bool correctlyRoundedDivideSqrt = false;   // CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT
};

// Every device of every platform. Throws RuntimeError when no OpenCL platform
// is installed; returns an empty list when platforms exist but hold no device.
std::vector<ClDevice> ListClDevices();

// The device that `spec` names (empty: $CELLRAY_DEVICE, then the default
// rule above). InputError for a malformed spec; RuntimeError when there is no
// platform or no device at all, when the spec names no device here
// (CL_DEVICE_NOT_FOUND), or when the device is not available
// (CL_DEVICE_NOT_AVAILABLE; injectable, cl_fault.h).
ClDevice SelectClDevice(const std::string& spec);

}  // namespace cr
