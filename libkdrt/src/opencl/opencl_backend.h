// The OpenCL device behind kdrt::Device (see device/backend.h): a persistent
// context, queue and program table (ClDeviceContext), and per committed scene
// its buffers (ClSceneBuffers), uploaded once, on which frames
// (render_frame) and ray queries (cl_ray_query.h) run.
#pragma once

#include "device/backend.h"
#include "opencl/cl.h"
#include "opencl/cl_device_context.h"
#include "opencl/cl_devices.h"

#include <cstddef>
#include <memory>
#include <vector>

namespace kdrt::detail {

// A device of kdrt's own (context and queue made here).
std::unique_ptr<DeviceBackend> make_opencl_backend(const ocl::ClDevice& device);
// A device around the application's context, device and queue (retained).
std::unique_ptr<DeviceBackend> make_opencl_backend(std::shared_ptr<ocl::ClDeviceContext> context);

// The OpenCL parts of a committed scene that the interop entry points
// (kdrt/opencl_interop.h) need beyond SceneBackend; a SceneBackend made by
// an OpenCL DeviceBackend is one of these.
class OpenClSceneBackend : public SceneBackend {
public:
    virtual const ocl::ClDeviceContext& device_context() const = 0;
    // Queries on the application's buffers (checked: context, sizes, flags).
    // Closest hits carry the application's ids (PreparedScene::name_table():
    // object, geometry, primitive of each internal id), mapped on the device
    // through a table uploaded at the first such query of the commit.
    virtual void intersect(cl_mem rays, cl_mem hits, std::size_t count) const = 0;
    virtual void occluded(cl_mem rays, cl_mem occluded, std::size_t count) const = 0;
    using SceneBackend::intersect;
    using SceneBackend::occluded;
};

}  // namespace kdrt::detail
