// Whether an OpenCL device is there for the OpenCL tests; without one they
// skip with a warning (CI sets KDRT_REQUIRE_OPENCL=1, and a test in
// test_opencl_render.cpp then fails instead, so a skip never goes unseen).
#pragma once

#include "opencl/cl_devices.h"

#include <catch2/catch.hpp>

#include <filesystem>

namespace kdrt_test {

inline bool have_opencl() {
    if (kdrt::detail::ocl::enumerate_devices().empty()) {
        WARN("no OpenCL device: skipping");
        return false;
    }
    return true;
}

// The kernel cache directory of the tests that render: none, so kdrt keeps
// no binaries on disk. PoCL, the tests' device, keeps compiled programs in
// its own cache across the test processes; asking it for a program's
// binaries, as kdrt's cache does, makes it compile every kernel of the
// program once more (seconds a program). The disk
// cache has tests of its own (ProgramCache in test_opencl_host.cpp).
inline std::filesystem::path no_disk_kernel_cache() { return {}; }

}  // namespace kdrt_test
