// kdrt::Device: a device opened once and used for many scenes and frames.
// It owns what is expensive to make: on OpenCL the context, the command
// queue and the compiled-program cache; on "cpu" the worker threads' arena.
//
// Thread safety: a Device may be shared by threads; committing scenes on it
// and tracing or rendering different CommittedScenes from several threads at
// once is safe (calls that use the OpenCL queue are serialised inside).
// One CommittedScene is used by one thread at a time, except intersect() and
// occluded() on host spans, which may run concurrently on the same scene.
#pragma once

#include <kdrt/export.h>
#include <kdrt/device.h>

#include <memory>
#include <string>

namespace kdrt {

namespace detail { struct DeviceState; }

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

    // Internal: the state shared by the scenes committed on this device.
    explicit Device(std::shared_ptr<detail::DeviceState> state) : state_(std::move(state)) {}
    const std::shared_ptr<detail::DeviceState>& state() const { return state_; }

private:
    std::shared_ptr<detail::DeviceState> state_;
};

}  // namespace kdrt
