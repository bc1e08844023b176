// Whether an OpenCL device is there for the OpenCL tests; without one they
// skip with a warning (CI sets KDRT_REQUIRE_OPENCL=1, and a test in
// test_opencl_render.cpp then fails instead, so a skip never goes unseen).
#pragma once

#include "opencl/cl_devices.h"

#include <catch2/catch.hpp>

namespace kdrt_test {

inline bool have_opencl() {
    if (kdrt::detail::ocl::enumerate_devices().empty()) {
        WARN("no OpenCL device: skipping");
        return false;
    }
    return true;
}

}  // namespace kdrt_test
