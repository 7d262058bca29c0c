#include "cl/cl_program.h"

#include <chrono>

#include <fmt/format.h>

#include "cl/cl_program_cache.h"
#include "core/error.h"

extern const char* const kCellrayKernelSource;
extern const std::size_t kCellrayKernelSourceLength;

namespace cr {

namespace {

std::string BuildLogs(const cl::Program& program)
{
  std::string out;
  std::vector<cl::Device> devices;
  if (program.getInfo(CL_PROGRAM_DEVICES, &devices) != CL_SUCCESS) return "(no device list: no build log)";
  for (const auto& d : devices) {
    std::string name, log;
    d.getInfo(CL_DEVICE_NAME, &name);
    if (program.getBuildInfo(d, CL_PROGRAM_BUILD_LOG, &log) != CL_SUCCESS) log = "(build log unavailable)";
    out += fmt::format("\n--- build log of {} ---\n{}", name.c_str(), log.c_str());
  }
  return out;
}

// Builds an already created program; returns the status (the caller decides
// whether a failure is fatal).
cl_int Build(cl::Program& program, const ClDevice& dev, const std::string& options)
{
  return program.build(std::vector<cl::Device>{dev.device}, options.c_str());
}

std::vector<unsigned char> Binary(const cl::Program& program)
{
  std::vector<std::size_t> sizes;
  CR_CL_CHECK(program.getInfo(CL_PROGRAM_BINARY_SIZES, &sizes), "clGetProgramInfo(CL_PROGRAM_BINARY_SIZES)");
  if (sizes.size() != 1 || sizes[0] == 0) return {};
  std::vector<unsigned char> bin(sizes[0]);
  unsigned char* ptr = bin.data();
  CR_CL_CHECK(clGetProgramInfo(program(), CL_PROGRAM_BINARIES, sizeof(ptr), &ptr, nullptr),
              "clGetProgramInfo(CL_PROGRAM_BINARIES)");
  return bin;
}

}  // namespace

const std::string& ClKernelSource()
{
  static const std::string source(kCellrayKernelSource, kCellrayKernelSourceLength);
  return source;
}

ClProgram BuildClProgram(const cl::Context& context, const ClDevice& dev, const std::string& source,
                         const std::string& options)
{
  const auto t0 = std::chrono::steady_clock::now();
  ClProgram out;
  out.options = options;
  const ClCacheKey key =
      MakeClCacheKey(ClCacheDir(), source, dev.name, dev.driverVersion, dev.platformVersion, options);
  ClCacheLookup cached = LoadClCache(key);
  if (cached.binary) {
    cl_int err = CL_SUCCESS;
    std::vector<cl_int> binaryStatus;
    cl::Program::Binaries bins{*cached.binary};
    cl::Program p(context, std::vector<cl::Device>{dev.device}, bins, &binaryStatus, &err);
    if (err == CL_SUCCESS && Build(p, dev, options) == CL_SUCCESS) {
      out.program = p;
      out.cacheHit = true;
      out.binaryBytes = cached.binary->size();
    } else {
      cached.why = fmt::format("the driver rejected the cached binary ({})", ClErrorName(err != CL_SUCCESS ? err : CL_BUILD_PROGRAM_FAILURE));
      cached.corrupt = true;
    }
  }
  if (!out.cacheHit) {
    if (cached.corrupt) Warn(fmt::format("OpenCL program cache: {}: {}; rebuilding from source", key.file, cached.why));
    out.cacheNote = cached.why;
    cl_int err = CL_SUCCESS;
    cl::Program p(context, source, false, &err);
    CR_CL_CHECK(err, "clCreateProgramWithSource");
    const cl_int status = Build(p, dev, options);
    if (status != CL_SUCCESS)
      throw RuntimeError(fmt::format("OpenCL: clBuildProgram failed: {} ({}) on {} with options '{}'{}",
                                     ClErrorName(status), status, dev.name, options, BuildLogs(p)));
    out.program = p;
    std::vector<unsigned char> bin = Binary(p);
    out.binaryBytes = bin.size();
    std::string why;
    if (!bin.empty() && !StoreClCache(key, bin, &why) && !key.file.empty())
      Warn(fmt::format("OpenCL program cache: cannot store {}: {}", key.file, why));
  }
  out.buildMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace cr
