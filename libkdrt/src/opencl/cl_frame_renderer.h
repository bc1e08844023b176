// One frame of the OpenCL renderer on a committed scene's buffers: the same
// picture as the C++ reference, traced by the kernels in cl/ as a wavefront
// of ray queues. Only the frame's own buffers (image, id map, ray queues) are
// made here; the scene's geometry, tree and shading buffers are not touched.
#pragma once

#include "opencl/cl.h"
#include "opencl/cl_device_context.h"
#include "opencl/cl_scene_buffers.h"
#include "scene/prepared_scene.h"

#include <kdrt/render_options.h>

namespace kdrt::detail::ocl {

// Renders `scene`'s camera and settings (size, samples, depth: the frame's)
// with `program` (built for the frame's kernel variant) on `buffers`
// (uploaded in options.precision). The frame-level options apply: schedule,
// ray order, launch limits, want_ids, progress. Between kernel launches the
// progress callback may cancel: kdrt::Error(Cancelled), with the queue idle
// and every frame buffer released. The caller holds the device's lock.
// result.compile_ms / upload_ms / kernel_options are left to the caller.
RenderResult render_frame(const ClDeviceContext& device, const ClSceneBuffers& buffers, const cl::Program& program,
                          const PreparedScene& scene, const RenderOptions& options);

}  // namespace kdrt::detail::ocl
