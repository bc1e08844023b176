#include <kdrt/device.h>

#include "cpu/cpu_backend.h"
#include "opencl/cl_devices.h"

namespace kdrt {

std::vector<DeviceInfo> list_devices() {
    std::vector<DeviceInfo> devices{detail::cpu_device_info()};
    for (const detail::ocl::ClDevice& d : detail::ocl::enumerate_devices()) devices.push_back(d.info);
    return devices;
}

}  // namespace kdrt
