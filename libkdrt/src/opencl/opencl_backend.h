// The OpenCL device behind kdrt::Device (see device/backend.h).
#pragma once

#include "device/backend.h"
#include "opencl/cl_devices.h"

#include <memory>

namespace kdrt::detail {

std::unique_ptr<DeviceBackend> make_opencl_backend(const ocl::ClDevice& device);

}  // namespace kdrt::detail
