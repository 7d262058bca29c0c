#include "host/cl/cl_program.h"

#include <chrono>
#include <filesystem>

#include <fmt/format.h>

#include "host/cl/cl_fault.h"
#include "host/cl/cl_program_cache.h"
#include "host/core/error.h"

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

// Creates the kernels `names` of a built program; on failure returns the
// status and the name of the kernel that failed.
cl_int CreateKernels(const cl::Program& program, const std::vector<std::string>& names, std::vector<cl::Kernel>& out,
                     std::string& failed)
{
  out.clear();
  for (const std::string& name : names) {
    cl_int err = CL_SUCCESS;
    cl::Kernel k(program, name.c_str(), &err);
    if (err != CL_SUCCESS) {
      failed = name;
      out.clear();
      return err;
    }
    out.push_back(k);
  }
  return CL_SUCCESS;
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
                         const std::string& optionsIn, const std::vector<std::string>& kernelNames)
{
  const auto t0 = std::chrono::steady_clock::now();
  const bool buildFault = ClFaultInjected(ClFault::Build);
  const bool kernelFault = ClFaultInjected(ClFault::Kernel);
  // kernels/trace.cl stops at an #error line under this definition: the
  // compiler itself fails, with its own log.
  const std::string options = buildFault ? optionsIn + " -DCR_INJECT_BUILD_FAULT" : optionsIn;
  std::vector<std::string> names = kernelNames;
  if (kernelFault)
    for (auto& n : names) n += "_InjectedFault";  // a name the program lacks: the driver's CL_INVALID_KERNEL_NAME
  ClProgram out;
  out.options = options;
  // An injected fault never reads or writes the cache: its program is not the
  // one the key names, and a good entry must not be lost to a test.
  const bool useCache = !buildFault && !kernelFault;
  const ClCacheKey key = MakeClCacheKey(useCache ? ClCacheDir() : std::string(), source, dev.name, dev.driverVersion,
                                        dev.platformVersion, options);
  ClCacheLookup cached = LoadClCache(key);
  if (cached.binary) {
    cl_int err = CL_SUCCESS;
    std::vector<cl_int> binaryStatus;
    cl::Program::Binaries bins{*cached.binary};
    cl::Program p(context, std::vector<cl::Device>{dev.device}, bins, &binaryStatus, &err);
    const char* call = "clCreateProgramWithBinary";
    if (err == CL_SUCCESS) {
      call = "clBuildProgram";
      err = Build(p, dev, options);
    }
    std::string failedKernel;
    if (err == CL_SUCCESS) {
      call = "clCreateKernel";
      err = CreateKernels(p, names, out.kernels, failedKernel);
    }
    if (err == CL_SUCCESS) {
      out.program = p;
      out.cacheHit = true;
      out.binaryBytes = cached.binary->size();
    } else {
      out.kernels.clear();
      cached.why = fmt::format("the driver rejected the cached binary ({} at {}{})", ClErrorName(err), call,
                               failedKernel.empty() ? "" : "(" + failedKernel + ")");
      cached.corrupt = true;
      std::error_code ec;
      std::filesystem::remove(key.file, ec);  // never tried again, whatever the rebuild below does
    }
  }
  if (!out.cacheHit) {
    if (cached.corrupt) Warn(fmt::format("OpenCL program cache: {}: {}; rebuilding from source", key.file, cached.why));
    out.cacheNote = useCache ? cached.why : "not used (CELLRAY_CL_FAULT)";
    cl_int err = CL_SUCCESS;
    cl::Program p(context, source, false, &err);
    CR_CL_CHECK(err, "clCreateProgramWithSource");
    const cl_int status = Build(p, dev, options);
    if (status != CL_SUCCESS)
      throw RuntimeError(fmt::format("OpenCL: clBuildProgram failed: {} ({}) on {} with options '{}'{}{}",
                                     ClErrorName(status), status, dev.name, options,
                                     buildFault ? ClFaultNote(ClFault::Build) : "", BuildLogs(p)));
    std::string failedKernel;
    const cl_int kstatus = CreateKernels(p, names, out.kernels, failedKernel);
    if (kstatus != CL_SUCCESS)
      throw RuntimeError(fmt::format("OpenCL: clCreateKernel failed: {} ({}): kernel {} of the program built on {} "
                                     "with options '{}'{} (the program is not cached){}",
                                     ClErrorName(kstatus), kstatus, failedKernel, dev.name, options,
                                     kernelFault ? ClFaultNote(ClFault::Kernel) : "", BuildLogs(p)));
    out.program = p;
    std::vector<unsigned char> bin = Binary(p);
    out.binaryBytes = bin.size();
    std::string why;
    if (useCache && !bin.empty() && !StoreClCache(key, bin, &why) && !key.file.empty())
      Warn(fmt::format("OpenCL program cache: cannot store {}: {}", key.file, why));
  }
  out.buildMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace cr
