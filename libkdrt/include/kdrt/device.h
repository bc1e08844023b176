// The devices a render can run on: "cpu" (the C++ reference) and every
// OpenCL device of every platform; kdrt::Device, one of them opened.
//
// Thread safety: a Device may be shared by threads; committing scenes on it
// and tracing or rendering different CommittedScenes from several threads at
// once is safe (calls that use the OpenCL queue are serialised inside).
// One CommittedScene is used by one thread at a time, except intersect() and
// occluded() on host spans, which may run concurrently on the same scene.
#pragma once

#include <kdrt/export.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace kdrt {

struct DeviceInfo {
    std::string id;        // what --device accepts: "cpu", "opencl:0", ...
    std::string platform;  // "C++ reference" or the OpenCL platform name
    std::string name;
    std::string vendor;
    std::string type;      // "cpu", "gpu", "accelerator", ...
    std::string driver_version;
    unsigned compute_units = 0;
    std::uint64_t global_memory = 0;     // bytes
    std::uint64_t max_allocation = 0;    // bytes
    bool fp64 = false;
};

KDRT_API std::vector<DeviceInfo> list_devices();

namespace detail {
struct DeviceState;
struct DeviceAccess;
}  // namespace detail

// A device opened once and used for many scenes and frames. It owns what is
// expensive to make: on OpenCL the context, the command queue and the
// compiled-program cache; on "cpu" the worker threads' arena. A handle:
// copies share the device. A moved-from Device throws
// kdrt::Error(InvalidArgument) from every call.
class KDRT_API Device {
public:
    // "cpu", "opencl", "opencl:N", "opencl:gpu", "opencl:<name substring>";
    // empty: $KDRT_DEVICE, else "cpu". Throws kdrt::Error(Device) naming the
    // spec and listing the devices when it names none.
    static Device open(const std::string& name = "");

    const DeviceInfo& info() const;
    bool is_opencl() const;
    // The SAH cost of a triangle test in this device's kd-tree leaves: what a
    // tree committed on it is built with when KdBuildConfig::intersection_cost
    // is 0 (the default). The cpu device tests a leaf's triangles four or eight
    // at a time (0.3), the OpenCL kernels one at a time (0.6).
    double triangle_cost() const;

private:
    friend struct detail::DeviceAccess;
    explicit Device(std::shared_ptr<detail::DeviceState> state) : state_(std::move(state)) {}
    std::shared_ptr<detail::DeviceState> state_;
};

}  // namespace kdrt
