// The one way libkdrt includes the OpenCL C++ bindings: OpenCL 1.2 as both
// the target and the minimum (the kernels are OpenCL C 1.2, and PoCL, NVIDIA,
// AMD and Intel all provide 1.2), with exceptions enabled. Every file that
// talks to OpenCL includes this header instead of <CL/opencl.hpp>, so the
// bindings are configured identically in every translation unit.
//
// cl::Error never crosses libkdrt's edge: code that calls the bindings
// catches it and converts it with to_kdrt_error() / guard_cl() from
// opencl/cl_error.h.
#pragma once

#if defined(CL_HPP_TARGET_OPENCL_VERSION) && CL_HPP_TARGET_OPENCL_VERSION != 120
#error "include opencl/cl.h before anything else that configures the OpenCL C++ bindings"
#endif
#if defined(CL_HPP_MINIMUM_OPENCL_VERSION) && CL_HPP_MINIMUM_OPENCL_VERSION != 120
#error "include opencl/cl.h before anything else that configures the OpenCL C++ bindings"
#endif

#ifndef CL_HPP_TARGET_OPENCL_VERSION
#define CL_HPP_TARGET_OPENCL_VERSION 120
#endif
#ifndef CL_HPP_MINIMUM_OPENCL_VERSION
#define CL_HPP_MINIMUM_OPENCL_VERSION 120
#endif
#ifndef CL_TARGET_OPENCL_VERSION
#define CL_TARGET_OPENCL_VERSION 120
#endif
#ifndef CL_HPP_ENABLE_EXCEPTIONS
#define CL_HPP_ENABLE_EXCEPTIONS
#endif

#include <CL/opencl.hpp>
