// FORMAT.md's Whitted shading over any closest-hit / occlusion intersector,
// in float, in kdrt's working frame (detail::PreparedScene): the library's
// detail::WhittedTracer, so Embree renders the scenes under exactly the same
// contract and self-intersection rule. Run over kdrt's own detail::SceneTracer
// it must reproduce the cpu device's image, which checks this harness.
//
// Tracer needs: const SceneGeometry<float>& geometry() const;
//               detail::Hit<float> closest(const detail::Ray<float>&) const;
//               bool occluded(const detail::Ray<float>&, float t_max) const;
#pragma once

#include "parallel.h"
#include "stats.h"

#include "cpu/intersect.h"
#include "cpu/ray.h"
#include "cpu/whitted_tracer.h"
#include "scene/prepared_scene.h"

#include <kdrt/camera.h>
#include <kdrt/render.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace kdrt::bench {

// The library's own Whitted shading, over the given tracer.
template <class Tracer>
using WhittedShader = detail::WhittedTracer<float, Tracer>;

// Renders the prepared scene (one sample per pixel, the pixel centre) on
// `threads` workers handing out rows, as the cpu device does. Fills image,
// rays, render_ms, and ids / hit_t when asked.
template <class Tracer>
RenderResult render_whitted(const detail::PreparedScene& scene, const Tracer& tracer, int threads, bool want_ids,
                            const std::string& device_name) {
    const int W = scene.settings.width, H = scene.settings.height;
    const WhittedShader<Tracer> shader(scene, tracer);
    const CameraFrame cam(scene.camera, W, H);
    const glm::vec3 eye(cam.position);
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
                const detail::Ray<float> ray(eye, glm::vec3(cam.direction(x, y, W, H)));
                ++rc.camera;
                const detail::Hit<float> hit = tracer.closest(ray);
                result.image.set(x, y, shader.shade(ray, hit, 1, rc));
                if (want_ids) {
                    const std::size_t i = static_cast<std::size_t>(y) * W + x;
                    result.ids[i] = hit.id;
                    result.hit_t[i] = hit.valid() ? hit.t : 0.0f;
                }
            }
    });
    result.render_ms = clock.ms();
    for (const RayCounts& rc : counts) result.rays += rc;
    result.features = scene.features;
    result.device_name = device_name + " (" + std::to_string(workers) + " threads)";
    return result;
}

}  // namespace kdrt::bench
