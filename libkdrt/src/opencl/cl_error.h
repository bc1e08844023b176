// OpenCL error codes as names, and the conversion of OpenCL failures into
// kdrt::Error(ErrorCode::Device) at libkdrt's edge.
#pragma once

#include "opencl/cl.h"

#include <kdrt/error.h>

#include <string>
#include <utility>

namespace kdrt::detail::ocl {

// The symbolic name of an OpenCL status code: every code of OpenCL 1.0 to 3.0
// ("CL_INVALID_VALUE"), the common KHR/EXT/vendor extension codes
// ("CL_PLATFORM_NOT_FOUND_KHR"), and "CL_UNKNOWN_ERROR(<n>)" for anything
// else. The unknown-code text lives in a thread-local buffer that the next
// call on the same thread overwrites; known names are string literals.
const char* cl_error_name(cl_int code);

// Throws kdrt::Error(ErrorCode::Device, what + ": " + cl_error_name(code)).
[[noreturn]] void throw_cl_error(cl_int code, const std::string& what);

// A caught cl::Error as a kdrt::Error(ErrorCode::Device):
// "<what>: <OpenCL function> failed: <name>" (the bindings record the
// function, e.g. "clCreateBuffer"). `what` says what kdrt was doing.
Error to_kdrt_error(const cl::Error& e, const std::string& what);

// Runs f(), converting any cl::Error it throws into kdrt::Error. Use it
// around every block of OpenCL calls whose failure can leave the library.
template <class F>
decltype(auto) guard_cl(const std::string& what, F&& f) {
    try {
        return std::forward<F>(f)();
    } catch (const cl::Error& e) {
        throw to_kdrt_error(e, what);
    }
}

}  // namespace kdrt::detail::ocl
