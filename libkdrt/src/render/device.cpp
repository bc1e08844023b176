// kdrt::Device: the name check render() has always made, then the backend.
#include "common/terminal_text.h"
#include "cpu/cpu_backend.h"
#include "render/device_state.h"
#include "opencl/cl_devices.h"
#include "opencl/opencl_backend.h"

#include <kdrt/device.h>
#include <kdrt/error.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>

namespace kdrt {

Device Device::open(const std::string& name) {
    std::string device = name;
    if (device.empty()) {
        const char* env = std::getenv("KDRT_DEVICE");
        device = (env && *env) ? env : "cpu";
    }
    std::string lower = device;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    const bool opencl = lower == "opencl" || lower.rfind("opencl:", 0) == 0;
    auto state = std::make_shared<detail::DeviceState>();
    if (lower == "cpu") {
        state->backend = detail::make_cpu_backend();
    } else if (opencl) {
        state->backend = detail::make_opencl_backend(detail::ocl::select_device(device));
    } else {
        throw Error(ErrorCode::Device, "unknown device '" + detail::escape_for_terminal(device) +
                                           "' (expected cpu, opencl or opencl:N; see --list-devices)");
    }
    return detail::DeviceAccess::make(std::move(state));
}

const DeviceInfo& Device::info() const { return detail::DeviceAccess::backend(*this, "Device::info").info(); }
double Device::triangle_cost() const {
    return detail::DeviceAccess::backend(*this, "Device::triangle_cost").triangle_cost();
}

bool Device::is_opencl() const { return detail::DeviceAccess::backend(*this, "Device::is_opencl").is_opencl(); }

}  // namespace kdrt
