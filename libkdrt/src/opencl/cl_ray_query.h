// Ray queries (kdrt/ray_query.h) on a committed scene's OpenCL buffers: the
// kernels of cl/ray_query.cl over rays in host memory (uploaded in chunks,
// read back) or in the application's own cl_mem buffers (no copies).
#pragma once

#include "opencl/cl.h"
#include "opencl/cl_device_context.h"
#include "opencl/cl_scene_buffers.h"

#include <kdrt/layout.h>

#include <glm/vec3.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace kdrt::detail::ocl {

// What every query needs besides the rays: the device, the scene's buffers,
// the program built for the scene's query variant, and where the working
// frame sits in world space.
struct QueryTarget {
    const ClDeviceContext* device = nullptr;
    const ClSceneBuffers* buffers = nullptr;
    cl::Program program;
    bool fp64 = false;              // the program was built with KDRT_HAS_FP64
    glm::dvec3 frame_origin{0.0};   // PreparedScene::frame_origin
    double max_launch_ms = 200.0;   // no launch runs longer (display watchdogs)
    unsigned rays_per_item = 1;     // rays_per_work_item() of the program's variant
    bool repeats_objects = false;   // the kd-tree references objects from several leaves (KDRT_MAILBOX)
};

// Closest hits / any hits of rays in host memory; the hits carry internal
// object ids (the caller maps them). hits.size() / occluded.size() must equal
// rays.size(). The caller holds the device's lock.
void query_closest(const QueryTarget& target, std::span<const QueryRay> rays, std::span<QueryHit> hits);
void query_any(const QueryTarget& target, std::span<const QueryRay> rays, std::span<std::uint8_t> occluded);

// How many hits each ray has in its window, and every hit, nearest first
// (cl/every_hit.cl), as kdrt/ray_query.h's count_hits and all_hits count
// them; internal object ids (the caller maps them). counts.size() must equal
// rays.size(). The caller holds the device's lock.
void query_count_hits(const QueryTarget& target, std::span<const QueryRay> rays, std::span<std::uint32_t> counts);
void query_all_hits(const QueryTarget& target, std::span<const QueryRay> rays, std::vector<std::uint64_t>& splits,
                    std::vector<QueryHit>& hits);

// The closest point of the scene's surface to each point (world space;
// cl/closest_point.cl), internal object ids. out.size() must equal
// points.size(). The caller holds the device's lock.
void query_closest_points(const QueryTarget& target, std::span<const std::array<float, 3>> points,
                          std::span<ClosestPoint> out);

// The same on the application's buffers: `rays` holds QueryRay[count], `out`
// receives QueryHit[count] (closest) or cl_uchar[count] (any). Both must be
// buffers of the device's context, large enough, readable / writable by
// kernels; kdrt::Error(InvalidArgument) says which is not. Closest hits carry
// the application's ids when the buffers have an id map (upload_id_map).
// Returns with the work finished. The caller holds the device's lock.
void query_closest(const QueryTarget& target, cl_mem rays, cl_mem hits, std::size_t count);
void query_any(const QueryTarget& target, cl_mem rays, cl_mem occluded, std::size_t count);

}  // namespace kdrt::detail::ocl
