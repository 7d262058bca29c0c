// The OpenCL C++ bindings as every file of host/cl/ uses them: OpenCL 1.2 API
// only, no binding exceptions (every call's status is checked with CR_CL_CHECK,
// which names the call site and the error).
#pragma once

#ifndef CL_HPP_TARGET_OPENCL_VERSION
#define CL_HPP_TARGET_OPENCL_VERSION 120
#endif
#ifndef CL_HPP_MINIMUM_OPENCL_VERSION
#define CL_HPP_MINIMUM_OPENCL_VERSION 120
#endif
#include <CL/opencl.hpp>

#include "host/cl/cl_error.h"
