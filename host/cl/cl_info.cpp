#include "cl/cl_info.h"

#include "cl/cl_api.h"

namespace cr {

nlohmann::json OpenCLInventory()
{
  nlohmann::json out = nlohmann::json::array();
  std::vector<cl::Platform> platforms;
  if (cl::Platform::get(&platforms) != CL_SUCCESS) return out;
  for (const auto& p : platforms) {
    nlohmann::json jp;
    jp["name"] = p.getInfo<CL_PLATFORM_NAME>();
    jp["version"] = p.getInfo<CL_PLATFORM_VERSION>();
    jp["devices"] = nlohmann::json::array();
    std::vector<cl::Device> devices;
    if (p.getDevices(CL_DEVICE_TYPE_ALL, &devices) == CL_SUCCESS) {
      for (const auto& d : devices) {
        cl_device_type type = d.getInfo<CL_DEVICE_TYPE>();
        jp["devices"].push_back({{"name", d.getInfo<CL_DEVICE_NAME>()},
                                 {"type", (type & CL_DEVICE_TYPE_GPU) ? "gpu" : (type & CL_DEVICE_TYPE_CPU) ? "cpu" : "other"},
                                 {"version", d.getInfo<CL_DEVICE_VERSION>()},
                                 {"driver", d.getInfo<CL_DRIVER_VERSION>()},
                                 {"compute_units", d.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>()},
                                 {"global_mem_bytes", d.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>()},
                                 {"max_alloc_bytes", d.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>()}});
      }
    }
    out.push_back(jp);
  }
  return out;
}

}  // namespace cr
