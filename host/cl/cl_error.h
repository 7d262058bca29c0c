// OpenCL status codes as names, and the check every OpenCL call goes through
// (LuxCore's CHECK_OCL_ERROR): a failure becomes a cr::RuntimeError that names
// the call, the error (e.g. CL_INVALID_KERNEL_ARGS) and the source location.
#pragma once

#include <string>

namespace cr {

// "CL_INVALID_KERNEL_ARGS" for -52; "unknown OpenCL error -1234" otherwise.
std::string ClErrorName(int status);

// Throws RuntimeError "OpenCL: <call> failed: <NAME> (<code>) [what] at <file>:<line>".
[[noreturn]] void ThrowClError(int status, const char* call, const char* file, int line, const std::string& what = {});

}  // namespace cr

// Checks the status of one OpenCL call; `call` names it in the message.
#define CR_CL_CHECK(status, call)                                            \
  do {                                                                       \
    const int crClStatus_ = (status);                                        \
    if (crClStatus_ != 0) ::cr::ThrowClError(crClStatus_, call, __FILE__, __LINE__); \
  } while (0)

// As CR_CL_CHECK with a detail (buffer name, kernel name, ...).
#define CR_CL_CHECK_WHAT(status, call, what)                                       \
  do {                                                                             \
    const int crClStatus_ = (status);                                              \
    if (crClStatus_ != 0) ::cr::ThrowClError(crClStatus_, call, __FILE__, __LINE__, what); \
  } while (0)
