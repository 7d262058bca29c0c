// Building the kernel program for one device, through the on-disk binary
// cache (cl_program_cache.h), and creating its kernels. A failed build
// reports the build log of each device. The cache stores a program only after
// it built and every kernel asked for was created from it: a driver that
// compiles a program it cannot run (Oclgrind 21.10 on an intrinsic it does
// not know: CL_INVALID_KERNEL_NAME at clCreateKernel) must not leave a
// program in the cache that every later run would load and fail on.
#pragma once

#include <string>
#include <vector>

#include "host/cl/cl_api.h"
#include "host/cl/cl_device.h"

namespace cr {

struct ClProgram {
  cl::Program program;
  std::vector<cl::Kernel> kernels;  // one per name asked for, in that order
  double buildMs = 0.0;         // from the cache lookup to a built program (binary stored, on a miss)
  bool cacheHit = false;
  std::string cacheNote;        // why it missed ("absent", "bad payload checksum", ...)
  std::size_t binaryBytes = 0;  // size of the device binary (CL_PROGRAM_BINARY_SIZES)
  std::string options;
};

// The embedded kernel source (kernels/trace.cl and what it includes),
// generated into the build directory by cmake/EmbedKernels.cmake.
const std::string& ClKernelSource();

// Builds `source` for `dev` with `options` and creates the kernels named
// `kernelNames`, loading the binary from the cache when a trustworthy entry
// exists (one whose kernels cannot be created is not: it is removed and the
// program rebuilt) and storing it after a build from source whose kernels
// were all created. RuntimeError (with the build logs) when the compiler
// rejects the source or a kernel cannot be created; nothing is stored then.
// With a build or kernel fault injected (cl_fault.h) the cache is not used.
ClProgram BuildClProgram(const cl::Context& context, const ClDevice& dev, const std::string& source,
                         const std::string& options, const std::vector<std::string>& kernelNames);

}  // namespace cr
