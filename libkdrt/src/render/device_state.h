// What a kdrt::Device holds: its backend (the C++ reference or an OpenCL
// device with its context, queue and program cache).
#pragma once

#include "device/backend.h"

#include <memory>

namespace kdrt::detail {

struct DeviceState {
    std::unique_ptr<DeviceBackend> backend;  // never null
};

}  // namespace kdrt::detail
