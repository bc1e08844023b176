// Raw closest-hit throughput: the camera rays of a scene, generated once
// (not timed), traced by a closest-hit function on N workers; nothing is
// shaded. For kdrt this is detail::SceneTracer (the C++ reference traversal),
// for Embree rtcIntersect1; both write the hit ids so they can be compared.
#pragma once

#include "parallel.h"
#include "stats.h"

#include "cpu/ray.h"
#include "scene/prepared_scene.h"

#include <cstdint>
#include <vector>

namespace kdrt::bench {

// One ray through each pixel centre, row-major from the top row, in the working frame.
std::vector<detail::Ray<float>> make_camera_rays(const detail::PreparedScene& scene);

struct RayTiming {
    double median_ms = 0.0;
    double mrays_per_s = 0.0;
    std::vector<std::int32_t> ids;  // from the last run
};

// One pass over the rays: closest(ray, t&) -> id into ids. Returns the milliseconds.
template <class Closest>
double trace_camera_rays(const std::vector<detail::Ray<float>>& rays, int threads, std::vector<std::int32_t>& ids,
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

// One untimed warm-up pass, then `runs` timed passes.
template <class Closest>
RayTiming time_camera_rays(const std::vector<detail::Ray<float>>& rays, int threads, int runs, Closest&& closest) {
    RayTiming out;
    std::vector<double> ms;
    for (int r = -1; r < runs; ++r) {
        const double t = trace_camera_rays(rays, threads, out.ids, closest);
        if (r >= 0) ms.push_back(t);
    }
    out.median_ms = median(ms);
    out.mrays_per_s = mrays_per_s(static_cast<double>(rays.size()), out.median_ms);
    return out;
}

// Rays whose ids differ between two runs.
std::size_t count_differences(const std::vector<std::int32_t>& a, const std::vector<std::int32_t>& b);

}  // namespace kdrt::bench
