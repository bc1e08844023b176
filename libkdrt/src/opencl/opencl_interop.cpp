// kdrt/opencl_interop.h: a Device around the application's OpenCL objects.
#include "device/device_state.h"
#include "opencl/cl_device_context.h"
#include "opencl/opencl_backend.h"

#include <kdrt/opencl_interop.h>

namespace kdrt {

Device wrap_opencl_device(cl_context context, cl_device_id device, cl_command_queue queue) {
    auto state = std::make_shared<detail::DeviceState>();
    state->backend = detail::make_opencl_backend(std::make_shared<detail::ocl::ClDeviceContext>(context, device, queue));
    return Device(std::move(state));
}

}  // namespace kdrt
