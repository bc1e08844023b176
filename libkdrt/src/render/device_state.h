// What a kdrt::Device holds: its backend (the C++ reference or an OpenCL
// device with its context, queue and program cache). Here, not in
// src/render, so that src/opencl can make a Device around the application's
// own OpenCL objects (wrap_opencl_device).
#pragma once

#include "device/backend.h"

#include <memory>

namespace kdrt::detail {

struct DeviceState {
    std::unique_ptr<DeviceBackend> backend;  // never null
};

}  // namespace kdrt::detail
