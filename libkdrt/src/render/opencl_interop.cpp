// kdrt/opencl_interop.h: a Device around the application's OpenCL objects,
// and ray queries into the application's buffers.
#include "render/committed_scene_state.h"
#include "render/device_state.h"
#include "opencl/cl_device_context.h"
#include "opencl/opencl_backend.h"

#include <kdrt/error.h>
#include <kdrt/opencl_interop.h>

namespace kdrt {

Device wrap_opencl_device(cl_context context, cl_device_id device, cl_command_queue queue) {
    auto state = std::make_shared<detail::DeviceState>();
    state->backend = detail::make_opencl_backend(std::make_shared<detail::ocl::ClDeviceContext>(context, device, queue));
    return detail::DeviceAccess::make(std::move(state));
}

namespace {

const detail::OpenClSceneBackend& opencl_scene(const CommittedScene& scene, const char* call) {
    const detail::CommittedSceneState& s = detail::CommittedSceneAccess::state(scene, call);
    const auto* backend = dynamic_cast<const detail::OpenClSceneBackend*>(&s.ready_backend());
    if (!backend)
        throw Error(ErrorCode::InvalidArgument, std::string(call) + " on cl_mem buffers: the scene is committed on '" +
                                                    s.device.info().id + "', not on an OpenCL device");
    return *backend;
}

}  // namespace

void intersect(const CommittedScene& scene, cl_mem rays, cl_mem hits, std::size_t count) {
    // The hits leave the library here, so the device maps the ids (a table uploaded once).
    opencl_scene(scene, "intersect").intersect(rays, hits, count);
}

void occluded(const CommittedScene& scene, cl_mem rays, cl_mem occluded, std::size_t count) {
    opencl_scene(scene, "occluded").occluded(rays, occluded, count);
}

}  // namespace kdrt
