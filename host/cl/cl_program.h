// Building the kernel program for one device, through the on-disk binary
// cache (cl_program_cache.h). A failed build reports the build log of each
// device.
#pragma once

#include <string>

#include "cl/cl_api.h"
#include "cl/cl_device.h"

namespace cr {

struct ClProgram {
  cl::Program program;
  double buildMs = 0.0;         // from the cache lookup to a built program (binary stored, on a miss)
  bool cacheHit = false;
  std::string cacheNote;        // why it missed ("absent", "bad payload checksum", ...)
  std::size_t binaryBytes = 0;  // size of the device binary (CL_PROGRAM_BINARY_SIZES)
  std::string options;
};

// The embedded kernel source (kernels/trace.cl and what it includes),
// generated into the build directory by cmake/EmbedKernels.cmake.
const std::string& ClKernelSource();

// Builds `source` for `dev` with `options`, loading the binary from the cache
// when a trustworthy entry exists and storing it after a build from source.
// RuntimeError (with the build logs) when the compiler rejects the source.
ClProgram BuildClProgram(const cl::Context& context, const ClDevice& dev, const std::string& source,
                         const std::string& options);

}  // namespace cr
