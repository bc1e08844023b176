// FORMAT.md's Whitted shading over any closest-hit / occlusion intersector,
// in float, in kdrt's working frame (detail::PreparedScene), with kdrt's
// self-intersection rule (offset along the normal relative to the object's
// magnitude, and the object the ray leaves ignored). It is how Embree renders
// the scenes under the same contract; run over kdrt's own detail::SceneTracer
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
#include "cpu/surface.h"
#include "render/prepared_scene.h"

#include <kdrt/camera.h>
#include <kdrt/render.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace kdrt::bench {

template <class Tracer>
class WhittedShader {
public:
    using Vec = glm::vec3;
    using Ray = detail::Ray<float>;
    using Hit = detail::Hit<float>;

    WhittedShader(const detail::PreparedScene& scene, const Tracer& tracer)
        : scene_(scene), tracer_(tracer), f_(scene.features) {}

    Vec shade(const Ray& ray, const Hit& hit, int depth, RayCounts& counts) const {
        if (!hit.valid()) return Vec(scene_.settings.background);
        const detail::Surface<float> s = detail::make_surface(tracer_.geometry(), ray, hit);
        const Material& m = scene_.materials[s.material];
        const Vec C(m.color);
        const float kd = static_cast<float>(m.diffuse), ks = static_cast<float>(m.specular);
        Vec c = Vec(scene_.settings.ambient) * C * kd;
        if (f_.lights) {
            for (const PointLight& light : scene_.lights) {
                Vec L = Vec(light.position) - s.p;
                const float dist = glm::length(L);
                L /= dist;
                if (!(glm::dot(s.ng, L) > 0.0f)) continue;
                const Vec org = detail::offset_origin(s, L);
                ++counts.shadow;
                if (tracer_.occluded(Ray(org, L, hit.id), glm::length(Vec(light.position) - org))) continue;
                const Vec R = 2.0f * glm::dot(s.ns, L) * s.ns - L;
                const float spec = std::pow(std::max(0.0f, glm::dot(R, -ray.dir)), static_cast<float>(m.shininess));
                c += Vec(light.color) * (kd * C * std::max(0.0f, glm::dot(s.ns, L)) + ks * spec);
            }
        }
        if (depth >= f_.max_depth) return c;
        if (f_.reflection && m.reflect > 0.0) {
            const Vec R = ray.dir - 2.0f * glm::dot(ray.dir, s.ns) * s.ns;
            c += static_cast<float>(m.reflect) * secondary(s, R, hit.id, depth, counts);
        }
        if (f_.refraction && m.transmit > 0.0) {
            const float ior = static_cast<float>(m.ior);
            const float eta = s.inside ? ior : 1.0f / ior;
            const float cos_i = -glm::dot(ray.dir, s.ns);
            const float k = 1.0f - eta * eta * (1.0f - cos_i * cos_i);
            const Vec T = k >= 0.0f ? glm::normalize(eta * ray.dir + (eta * cos_i - std::sqrt(k)) * s.ns)
                                    : ray.dir - 2.0f * glm::dot(ray.dir, s.ns) * s.ns;
            c += static_cast<float>(m.transmit) * secondary(s, T, hit.id, depth, counts);
        }
        return c;
    }

private:
    Vec secondary(const detail::Surface<float>& s, const Vec& dir, std::int32_t from, int depth,
                  RayCounts& counts) const {
        ++counts.secondary;
        const Ray ray(detail::offset_origin(s, dir), dir, from);
        return shade(ray, tracer_.closest(ray), depth + 1, counts);
    }

    const detail::PreparedScene& scene_;
    const Tracer& tracer_;
    SceneFeatures f_;
};

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
