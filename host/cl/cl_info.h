// OpenCL platform and device discovery for `cellray info`.
#pragma once

#include <nlohmann/json.hpp>

namespace cr {

// One entry per platform with its devices (name, version, compute units,
// memory); an empty array when no platform is installed.
nlohmann::json OpenCLInventory();

}  // namespace cr
