// The interface between cellray_core and its image module
// (libcellray_image.so, host/render/image_oiio.cpp), the one place that
// links OpenImageIO. OpenImageIO pulls in about 260 shared libraries and
// costs every process 0.2 s to load, so the core opens the module with
// dlopen on the first image call (host/render/image_io.cpp): trace, check,
// rays, bench and the tests that write no image never load it.
//
// Both sides are built together by the same compiler, so the table passes
// C++ types; errors come back as messages (never exceptions across the
// boundary), and the version guards against a stale module beside a newer
// binary.
#pragma once

#include <string>
#include <vector>

#include "host/render/image_io.h"

namespace cr {

inline constexpr int kImageModuleVersion = 1;
inline constexpr const char* kImageModuleFile = "libcellray_image.so";
inline constexpr const char* kImageModuleEntry = "cellray_image_module";

// Each function returns an empty string on success, else what went wrong.
struct ImageModule {
  int version;
  // Writes `rgb` (linear) to `path` as `format` ("png": 8-bit sRGB, "exr":
  // float linear); the caller renames it into place.
  std::string (*write)(const std::string& path, const std::string& format, int width, int height,
                       const std::vector<float>& rgb);
  std::string (*compare)(int width, int height, const std::vector<float>& a, const std::vector<float>& b,
                         ImageDiff& out);
  // `linear`: the file holds linear values (EXR); otherwise sRGB-decoded.
  std::string (*read)(const std::string& path, bool linear, int& width, int& height, std::vector<float>& rgb);
};

}  // namespace cr

// The module's one exported symbol.
extern "C" const cr::ImageModule* cellray_image_module();
