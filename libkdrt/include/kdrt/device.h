// The devices a render can run on: "cpu" (the C++ reference) and, from the
// OpenCL issue on, every OpenCL device of every platform.
#pragma once

#include <kdrt/export.h>

#include <cstdint>
#include <string>
#include <vector>

namespace kdrt {

struct DeviceInfo {
    std::string id;        // what --device accepts: "cpu", "opencl:0", ...
    std::string platform;  // "C++ reference" or the OpenCL platform name
    std::string name;
    std::string vendor;
    std::string type;      // "cpu", "gpu", "accelerator", ...
    std::string driver_version;
    unsigned compute_units = 0;
    std::uint64_t global_memory = 0;     // bytes
    std::uint64_t max_allocation = 0;    // bytes
    bool fp64 = false;
};

KDRT_API std::vector<DeviceInfo> list_devices();

}  // namespace kdrt
