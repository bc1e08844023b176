// One frame of the OpenCL renderer on a committed scene's buffers: the same
// picture as the C++ reference, traced by the kernels in cl/ as a wavefront
// of ray queues. Only the frame's own buffers (image, id map, ray queues) are
// made here, or taken from the scene's earlier frames (FrameBuffers); the
// scene's geometry, tree and shading buffers are not touched.
#pragma once

#include "opencl/cl.h"
#include "opencl/cl_device_context.h"
#include "opencl/cl_scene_buffers.h"
#include "scene/prepared_scene.h"

#include <kdrt/commit_options.h>
#include <kdrt/frame_options.h>
#include <kdrt/render_result.h>

#include <cstddef>
#include <vector>

namespace kdrt::detail::ocl {

// A committed scene's frame buffers, kept from one frame to the next (the
// largest asked for so far): a frame that fits reuses them instead of
// allocating its image, id map, queues and pixel table again, which on PoCL
// also meant page faults on every first touch. Owned by the scene's backend
// and used under the device's lock; contents are rewritten by each frame,
// except a pixel table that is already the one asked for and an accumulator
// that the last frame's resolve left clear (accum_zero).
struct FrameBuffers {
    cl::Buffer accum, rgb, ids, hit_t, counters, order;
    std::size_t accum_bytes = 0, rgb_bytes = 0, ids_bytes = 0, hit_t_bytes = 0, counters_bytes = 0, order_bytes = 0;
    // The whole accumulator holds zeros: resolve_image leaves it so, and the
    // next frame need not fill it (false after a new buffer or a frame that
    // did not finish). A frame whose kernels write the image themselves
    // (to_pixel in cl/render.cl) neither reads nor writes it.
    bool accum_zero = false;
    std::vector<cl::Buffer> levels;  // ray queues by bounce level, level_bytes each
    std::size_t level_bytes = 0;
    // What `order` holds: the pixel table of a width x height region in this order (width 0: none).
    int order_width = 0, order_height = 0;
    RayOrder order_kind = RayOrder::Rows;
};

// Renders `scene`'s camera and settings (size, samples, depth: the frame's)
// with `program` (built for the frame's kernel variant) on `buffers`
// (uploaded in `precision`). The frame's options apply: region, want_ids,
// progress, the OpenCL execution (schedule, ray order, launch limits,
// profiling). Between kernel launches the progress callback may cancel:
// kdrt::Error(Cancelled), with the queue idle and the frame's buffers kept in
// `frame_buffers`. The caller holds the device's lock. The result's
// stats.compile_ms / upload_ms and the program's part of stats.opencl are
// left to the caller.
RenderResult render_frame(const ClDeviceContext& device, const ClSceneBuffers& buffers, const cl::Program& program,
                          const PreparedScene& scene, Precision precision, const FrameOptions& frame,
                          FrameBuffers& frame_buffers);

}  // namespace kdrt::detail::ocl
