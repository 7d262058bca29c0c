// One device with its context and in-order queue, and the buffer helpers that
// check the device's limits before allocating (CL_DEVICE_MAX_MEM_ALLOC_SIZE):
// a structure too large for the device fails clearly instead of paging.
#pragma once

#include <cstddef>
#include <string>

#include "host/cl/cl_api.h"
#include "host/cl/cl_device.h"

namespace cr {

struct ClContext {
  ClDevice dev;
  cl::Context context;
  cl::CommandQueue queue;
};

// The device `spec` names (cl_device.h) with a context and queue.
ClContext CreateClContext(const std::string& spec);

// A read-only buffer holding a copy of `bytes` bytes at `data` (a 16-byte
// placeholder when bytes is 0, zeros, as large as any record: kernels take every argument, used or not).
// RuntimeError naming `what` when the device cannot hold it.
cl::Buffer ClUpload(const ClContext& c, const char* what, const void* data, std::size_t bytes);

// A buffer over the host's own `bytes` bytes at `data` (CL_MEM_USE_HOST_PTR | flags): a CPU device
// reads and writes them in place. `data` must outlive the buffer's use.
cl::Buffer ClWrapHost(const ClContext& c, const char* what, void* data, std::size_t bytes, cl_mem_flags flags);

// An uninitialised buffer of `bytes` bytes with `flags`.
cl::Buffer ClAlloc(const ClContext& c, const char* what, std::size_t bytes, cl_mem_flags flags);

// RuntimeError when `bytes` exceeds the device's single-allocation limit.
void ClCheckAllocation(const ClDevice& dev, const char* what, std::size_t bytes);

}  // namespace cr
