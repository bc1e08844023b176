// OpenCL devices: enumeration over every platform, selection from a --device
// spec ("opencl", "opencl:N", "opencl:gpu", "opencl:cpu", "opencl:<substring>"),
// and the checks of buffer sizes against the device's memory limits.
#pragma once

#include "opencl/cl.h"

#include <kdrt/device.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace kdrt::detail::ocl {

struct ClDevice {
    cl::Platform platform;
    cl::Device device;
    DeviceInfo info;  // id "opencl:N", N = position in enumerate_devices()
    // CL_DEVICE_HOST_UNIFIED_MEMORY: the device computes in the host's memory
    // (a CPU device, an integrated GPU), so the caller's memory is wrapped
    // (CL_MEM_USE_HOST_PTR) rather than copied; PoCL then works on it in
    // place, though the specification lets a device keep copies.
    bool host_memory = false;
};

// Every device of every platform, in a stable global order (platforms as the
// ICD loader lists them, then each platform's devices). Never throws: no ICD,
// no platform (CL_PLATFORM_NOT_FOUND_KHR) or any other enumeration failure
// gives an empty list; a platform whose devices cannot be listed is skipped.
std::vector<ClDevice> enumerate_devices();

// The device a spec names, from enumerate_devices():
//   "opencl"              the first GPU, else the first CPU, else the first device
//   "opencl:N"            the device with id "opencl:N"
//   "opencl:gpu" | "opencl:cpu" | "opencl:accelerator"
//                         the first device of that type
//   "opencl:<substring>"  the first device whose name, vendor or platform
//                         contains <substring>, ignoring case
// The "opencl" prefix is matched ignoring case. Throws
// kdrt::Error(ErrorCode::Device) naming the spec and listing the available
// devices (id and name), or saying that no OpenCL platform was found.
ClDevice select_device(const std::string& spec);

// A device the application created its own context on (wrap_opencl_device):
// described like an enumerated one, with the id of the enumerated device it
// is ("opencl:N"), or "opencl:app" when the enumeration does not list it.
ClDevice describe_application_device(const cl::Device& device);

// The selection rule on its own, over given device descriptions: the index
// into `devices` that `spec` names; throws as select_device does.
std::size_t select_device_index(const std::string& spec, const std::vector<DeviceInfo>& devices);

// ---- device limits: check buffer sizes before allocating ---------------------
// So an oversized scene is a clear message rather than CL_INVALID_BUFFER_SIZE
// or CL_MEM_OBJECT_ALLOCATION_FAILURE in the middle of a render.

// Throws kdrt::Error(ErrorCode::Device) "<what> needs X MiB (N bytes) but the
// device's largest allocation is Y MiB (M bytes) on <device>..." when `bytes`
// exceeds CL_DEVICE_MAX_MEM_ALLOC_SIZE (device.info.max_allocation).
void check_allocation(const ClDevice& device, std::uint64_t bytes, const std::string& what);

// Throws kdrt::Error(ErrorCode::Device) when the buffers together
// (`total_bytes`) exceed CL_DEVICE_GLOBAL_MEM_SIZE (device.info.global_memory).
void check_total(const ClDevice& device, std::uint64_t total_bytes);

}  // namespace kdrt::detail::ocl
