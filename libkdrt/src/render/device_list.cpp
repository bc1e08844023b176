#include <kdrt/device.h>

#include "opencl/cl_devices.h"

#include <thread>

namespace kdrt {

std::vector<DeviceInfo> list_devices() {
    DeviceInfo cpu;
    cpu.id = "cpu";
    cpu.platform = "C++ reference";
    cpu.name = "kdrt C++ reference renderer";
    cpu.vendor = "kdrt";
    cpu.type = "cpu";
    cpu.driver_version = "built in";
    cpu.compute_units = std::thread::hardware_concurrency();
    cpu.fp64 = true;
    std::vector<DeviceInfo> devices{cpu};
    for (const detail::ocl::ClDevice& d : detail::ocl::enumerate_devices()) devices.push_back(d.info);
    return devices;
}

}  // namespace kdrt
