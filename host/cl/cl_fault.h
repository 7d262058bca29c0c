// Injected OpenCL failures, for tests of the error paths and of the `auto`
// backend's fallback: $CELLRAY_CL_FAULT names one or more faults, comma
// separated, that the OpenCL backend then meets as if the driver had
// reported them (docs/OPENCL.md, "Failures"):
//   build     the program does not compile: a real clBuildProgram failure
//             (an #error line the kernel source compiles under
//             -DCR_INJECT_BUILD_FAULT), with the compiler's build log
//   kernel    the program builds but a kernel cannot be created: a real
//             CL_INVALID_KERNEL_NAME (the kernels are asked for by a name the
//             program lacks), as Oclgrind reports for what it cannot run
//   alloc     clCreateBuffer of the rays and hits returns CL_MEM_OBJECT_ALLOCATION_FAILURE
//   launch    clEnqueueNDRangeKernel returns CL_OUT_OF_RESOURCES (a driver's
//             lazy allocation failing at the launch)
//   device    the device reports CL_DEVICE_AVAILABLE false: CL_DEVICE_NOT_AVAILABLE
//   limits    a kernel's CL_KERNEL_WORK_GROUP_SIZE is 1, below its packet:
//             CL_INVALID_WORK_GROUP_SIZE before any launch
//   localmem  a kernel's CL_KERNEL_LOCAL_MEM_SIZE exceeds CL_DEVICE_LOCAL_MEM_SIZE:
//             CL_OUT_OF_RESOURCES before any launch
// A program from a build with a fault injected is never stored in the
// program cache (the build options or the kernel names differ, and the
// cache stores only programs whose kernels were all created).
#pragma once

#include <string>

namespace cr {

enum class ClFault { Build, Kernel, Alloc, Launch, Device, Limits, LocalMem };

// Whether $CELLRAY_CL_FAULT names `f` (read at each call, so tests may set
// it). InputError for a name not in the list above.
bool ClFaultInjected(ClFault f);

// " [injected: CELLRAY_CL_FAULT=<name>]", appended to the messages of
// injected failures so that no one mistakes them for the driver's.
std::string ClFaultNote(ClFault f);

}  // namespace cr
