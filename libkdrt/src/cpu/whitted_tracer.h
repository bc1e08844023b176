// WhittedTracer: FORMAT.md's Whitted shading over any tracer with
//   const SceneGeometry<Real>& geometry() const;
//   Hit<Real> closest(const Ray<Real>&) const;
//   bool occluded(const Ray<Real>&, Real t_max) const;
// The C++ reference renderer runs it over SceneTracer; kdrt-bench runs it over
// Embree, so both shade by the very same code. The kernels' twin is cl/shade.cl.
#pragma once

#include "cpu/intersect.h"
#include "cpu/surface.h"
#include "scene/prepared_scene.h"

#include <kdrt/render_options.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace kdrt::detail {

// Whitted shading exactly as FORMAT.md states it; recursion is fine here (the
// kernels use queues instead). Only the effects in `features` are simulated.
template <class Real, class Tracer>
class WhittedTracer {
public:
    using Vec = glm::vec<3, Real>;

    // fixed_epsilon > 0: the accuracy knob's absolute offset without self-exclusion.
    WhittedTracer(const PreparedScene& scene, const Tracer& tracer, Real fixed_epsilon = Real(0))
        : scene_(scene), tracer_(tracer), f_(scene.features), fixed_epsilon_(fixed_epsilon) {}

    Vec trace(const Ray<Real>& ray, int depth, RayCounts& counts) const {
        const Hit<Real> hit = tracer_.closest(ray);
        return shade(ray, hit, depth, counts);
    }

    Vec shade(const Ray<Real>& ray, const Hit<Real>& hit, int depth, RayCounts& counts) const {
        if (!hit.valid()) return Vec(scene_.settings.background);
        const Surface<Real> s = make_surface(tracer_.geometry(), ray, hit);
        const Material& m = scene_.materials[s.material];
        const Vec C(m.color);
        const Real kd = static_cast<Real>(m.diffuse), ks = static_cast<Real>(m.specular);
        Vec c = Vec(scene_.settings.ambient) * C * kd;

        if (f_.lights) {
            for (const PointLight& light : scene_.lights) {
                Vec L = Vec(light.position) - s.p;
                const Real dist = safe_length(L);
                L /= dist;
                if (!(glm::dot(s.ng, L) > Real(0))) continue;
                const Vec org = offset_origin(s, L, fixed_epsilon_);
                ++counts.shadow;
                if (tracer_.occluded(Ray<Real>(org, L, leaving(hit.id)), safe_length(Vec(light.position) - org)))
                    continue;
                const Vec R = Real(2) * glm::dot(s.ns, L) * s.ns - L;
                const Real spec = std::pow(std::max(Real(0), glm::dot(R, -ray.dir)), static_cast<Real>(m.shininess));
                c += Vec(light.color) * (kd * C * std::max(Real(0), glm::dot(s.ns, L)) + ks * spec);
            }
        }
        if (depth >= f_.max_depth) return c;
        if (f_.reflection && m.reflect > 0.0) {
            const Vec R = ray.dir - Real(2) * glm::dot(ray.dir, s.ns) * s.ns;
            c += static_cast<Real>(m.reflect) * secondary(s, R, hit.id, depth, counts);
        }
        if (f_.refraction && m.transmit > 0.0) {
            const Real ior = static_cast<Real>(m.ior);
            const Real eta = s.inside ? ior : Real(1) / ior;
            const Real cos_i = -glm::dot(ray.dir, s.ns);
            const Real k = Real(1) - eta * eta * (Real(1) - cos_i * cos_i);
            const Vec T = k >= Real(0) ? glm::normalize(eta * ray.dir + (eta * cos_i - std::sqrt(k)) * s.ns)
                                       : ray.dir - Real(2) * glm::dot(ray.dir, s.ns) * s.ns;  // total internal reflection
            c += static_cast<Real>(m.transmit) * secondary(s, T, hit.id, depth, counts);
        }
        return c;
    }

private:
    Vec secondary(const Surface<Real>& s, const Vec& dir, std::int32_t from, int depth, RayCounts& counts) const {
        ++counts.secondary;
        return trace(Ray<Real>(offset_origin(s, dir, fixed_epsilon_), dir, leaving(from)), depth + 1, counts);
    }

    // The fixed-epsilon knob relies on the offset alone: no self-exclusion.
    std::int32_t leaving(std::int32_t id) const { return fixed_epsilon_ > Real(0) ? kNoObject : id; }

    const PreparedScene& scene_;
    const Tracer& tracer_;
    SceneFeatures f_;
    Real fixed_epsilon_;
};

}  // namespace kdrt::detail
