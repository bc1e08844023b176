#include <kdrt/device.h>

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
    return {cpu};
}

}  // namespace kdrt
