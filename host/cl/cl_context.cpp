#include "host/cl/cl_context.h"

#include <fmt/format.h>

#include "host/cl/cl_fault.h"
#include "host/core/error.h"

namespace cr {

ClContext CreateClContext(const std::string& spec)
{
  ClContext c;
  c.dev = SelectClDevice(spec);
  cl_int err = CL_SUCCESS;
  c.context = cl::Context(c.dev.device, nullptr, nullptr, nullptr, &err);
  CR_CL_CHECK_WHAT(err, "clCreateContext", c.dev.name);
  // Profiling on: the kernels' device time is reported beside the wall time
  // (Tracer::LastKernelMs); an in-order queue either way.
  c.queue = cl::CommandQueue(c.context, c.dev.device, CL_QUEUE_PROFILING_ENABLE, &err);
  CR_CL_CHECK_WHAT(err, "clCreateCommandQueue", c.dev.name);
  return c;
}

void ClCheckAllocation(const ClDevice& dev, const char* what, std::size_t bytes)
{
  if (bytes > dev.maxAllocBytes)
    throw RuntimeError(fmt::format("OpenCL: {} needs {} bytes, more than one allocation may hold on '{}' "
                                   "(CL_DEVICE_MAX_MEM_ALLOC_SIZE = {} bytes)",
                                   what, bytes, dev.name, dev.maxAllocBytes));
}

cl::Buffer ClUpload(const ClContext& c, const char* what, const void* data, std::size_t bytes)
{
  static const unsigned char kZeros[64] = {};
  if (bytes == 0) {
    data = kZeros;
    bytes = sizeof(kZeros);
  }
  ClCheckAllocation(c.dev, what, bytes);
  cl_int err = CL_SUCCESS;
  cl::Buffer b(c.context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, const_cast<void*>(data), &err);
  CR_CL_CHECK_WHAT(err, "clCreateBuffer", fmt::format("{} ({} bytes)", what, bytes));
  return b;
}

cl::Buffer ClWrapHost(const ClContext& c, const char* what, void* data, std::size_t bytes, cl_mem_flags flags)
{
  ClCheckAllocation(c.dev, what, bytes);
  if (ClFaultInjected(ClFault::Alloc))
    ThrowClError(CL_MEM_OBJECT_ALLOCATION_FAILURE, "clCreateBuffer", __FILE__, __LINE__,
                 fmt::format("{} ({} bytes, in place){}", what, bytes, ClFaultNote(ClFault::Alloc)));
  cl_int err = CL_SUCCESS;
  cl::Buffer b(c.context, flags | CL_MEM_USE_HOST_PTR, bytes, data, &err);
  CR_CL_CHECK_WHAT(err, "clCreateBuffer", fmt::format("{} ({} bytes, in place)", what, bytes));
  return b;
}

cl::Buffer ClAlloc(const ClContext& c, const char* what, std::size_t bytes, cl_mem_flags flags)
{
  if (bytes == 0) bytes = 64;
  ClCheckAllocation(c.dev, what, bytes);
  if (ClFaultInjected(ClFault::Alloc))
    ThrowClError(CL_MEM_OBJECT_ALLOCATION_FAILURE, "clCreateBuffer", __FILE__, __LINE__,
                 fmt::format("{} ({} bytes){}", what, bytes, ClFaultNote(ClFault::Alloc)));
  cl_int err = CL_SUCCESS;
  cl::Buffer b(c.context, flags, bytes, nullptr, &err);
  CR_CL_CHECK_WHAT(err, "clCreateBuffer", fmt::format("{} ({} bytes)", what, bytes));
  return b;
}

}  // namespace cr
