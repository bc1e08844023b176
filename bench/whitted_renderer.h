// FORMAT.md's Whitted shading over any closest-hit / occlusion intersector,
// in float, in kdrt's working frame: kdrt::WorkingScene::shade, the cpu
// renderer's own shader, so Embree renders the scenes under exactly the same
// contract and self-intersection rule. Run over kdrt's own traversal
// (WorkingScene::kd_intersector) it must reproduce the cpu device's image,
// which checks this harness.
#pragma once

#include "parallel.h"
#include "stats.h"

#include <kdrt/render.h>
#include <kdrt/working_scene.h>

#include <string>

namespace kdrt::bench {

// Renders the scene (one sample per pixel, the pixel centre) on `threads`
// workers handing out rows, as the cpu device does. Fills image, rays,
// render_ms, and ids (public object ids) / hit_t when asked.
inline RenderResult render_whitted(const WorkingScene& scene, const ShadingIntersector& intersector, int threads,
                                   bool want_ids, const std::string& device_name) {
    const int W = scene.width(), H = scene.height();
    RenderResult result;
    result.image = Image(W, H);
    if (want_ids) {
        result.ids.assign(static_cast<std::size_t>(W) * H, -1);
        result.hit_t.assign(static_cast<std::size_t>(W) * H, 0.0f);
    }
    const int workers = worker_count(threads);
    std::vector<RayCounts> counts(static_cast<std::size_t>(workers));
    const Stopwatch clock;
    parallel_chunks(static_cast<std::size_t>(H), workers, 1, [&](std::size_t y0, std::size_t y1, int worker) {
        RayCounts& rc = counts[static_cast<std::size_t>(worker)];
        for (int y = static_cast<int>(y0); y < static_cast<int>(y1); ++y)
            for (int x = 0; x < W; ++x) {
                const ShadingRay ray = scene.camera_ray(x, y);
                ++rc.camera;
                const ShadingHit hit = intersector.closest(ray);
                result.image.set(x, y, scene.shade(ray, hit, intersector, rc));
                if (want_ids) {
                    const std::size_t i = static_cast<std::size_t>(y) * W + x;
                    const bool valid = hit.object >= 0;
                    result.ids[i] = valid ? static_cast<std::int32_t>(scene.object_id(static_cast<std::uint32_t>(hit.object))) : -1;
                    result.hit_t[i] = valid ? hit.t : 0.0f;
                }
            }
    });
    result.stats.render_ms = clock.ms();
    for (const RayCounts& rc : counts) result.stats.rays += rc;
    result.stats.features = scene.features();
    result.stats.device_name = device_name + " (" + std::to_string(workers) + " threads)";
    return result;
}

}  // namespace kdrt::bench
