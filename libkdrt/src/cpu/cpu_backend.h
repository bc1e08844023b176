// The C++ reference behind kdrt::Device "cpu" (see device/backend.h).
#pragma once

#include "device/backend.h"

#include <memory>

namespace kdrt::detail {

std::unique_ptr<DeviceBackend> make_cpu_backend();

// What list_devices() and Device::info() report for "cpu".
DeviceInfo cpu_device_info();

}  // namespace kdrt::detail
