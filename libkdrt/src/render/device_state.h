// What a kdrt::Device holds: its backend (the C++ reference or an OpenCL
// device with its context, queue and program cache), and the library's way
// in to it (kdrt/device.h declares DeviceAccess its friend).
#pragma once

#include "device/backend.h"

#include <kdrt/device.h>
#include <kdrt/error.h>

#include <memory>
#include <string>

namespace kdrt::detail {

struct DeviceState {
    std::unique_ptr<DeviceBackend> backend;  // never null
};

struct DeviceAccess {
    static Device make(std::shared_ptr<DeviceState> state) { return Device(std::move(state)); }

    // The device's state; kdrt::Error(InvalidArgument) naming `call` for a
    // moved-from Device, which holds none.
    static DeviceState& state(const Device& device, const char* call) {
        if (!device.state_)
            throw Error(ErrorCode::InvalidArgument,
                        std::string(call) + ": the kdrt::Device was moved from and holds no device");
        return *device.state_;
    }
    static DeviceBackend& backend(const Device& device, const char* call) { return *state(device, call).backend; }
};

}  // namespace kdrt::detail
