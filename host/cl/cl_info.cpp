#include "host/cl/cl_info.h"

#include "host/cl/cl_device.h"

namespace cr {

nlohmann::json OpenCLInventory()
{
  nlohmann::json out = nlohmann::json::array();
  std::vector<ClDevice> devices;
  try {
    devices = ListClDevices();
  } catch (const std::exception&) {
    return out;  // no platform (or an unusable one): nothing to list
  }
  // Platforms without a device are not listed.
  for (const auto& d : devices) {
    if (out.empty() || out.back()["index"] != d.platformIndex)
      out.push_back({{"index", d.platformIndex},
                     {"name", d.platformName},
                     {"version", d.platformVersion},
                     {"devices", nlohmann::json::array()}});
    out.back()["devices"].push_back({{"device", std::to_string(d.flatIndex)},
                                     {"platform:device", std::to_string(d.platformIndex) + ":" +
                                                             std::to_string(d.deviceIndex)},
                                     {"name", d.name},
                                     {"type", d.type},
                                     {"version", d.version},
                                     {"driver", d.driverVersion},
                                     {"compute_units", d.computeUnits},
                                     {"global_mem_bytes", d.globalMemBytes},
                                     {"max_alloc_bytes", d.maxAllocBytes},
                                     {"local_mem_bytes", d.localMemBytes},
                                     {"max_work_group_size", d.maxWorkGroupSize},
                                     {"fp64", d.fp64},
                                     {"available", d.available},
                                     {"simulator", d.simulator}});
  }
  return out;
}

}  // namespace cr
