// Raw closest-hit throughput: the camera rays of a scene, generated once
// (not timed) in kdrt's working frame, traced by a closest-hit function on N
// workers (Embree's rtcIntersect1; kdrt's side goes through ray_queries.h);
// nothing is shaded, the hit ids are kept so that they can be compared.
#pragma once

#include "parallel.h"
#include "stats.h"

#include <kdrt/working_scene.h>

#include <cstdint>
#include <vector>

namespace kdrt::bench {

// One ray through each pixel centre, row-major from the top row, in the working frame.
std::vector<ShadingRay> make_camera_rays(const WorkingScene& scene);

// One pass over the rays: closest(ray, t&) -> id into ids. Returns the milliseconds.
template <class Closest>
double trace_camera_rays(const std::vector<ShadingRay>& rays, int threads, std::vector<std::int32_t>& ids,
                         Closest&& closest) {
    ids.assign(rays.size(), -1);
    const Stopwatch clock;
    parallel_chunks(rays.size(), worker_count(threads), 256, [&](std::size_t b, std::size_t e, int) {
        for (std::size_t i = b; i < e; ++i) {
            float t = 0.0f;
            ids[i] = closest(rays[i], t);
        }
    });
    return clock.ms();
}

// Rays whose ids differ between two runs.
std::size_t count_differences(const std::vector<std::int32_t>& a, const std::vector<std::int32_t>& b);

}  // namespace kdrt::bench
