// WhittedTracer: FORMAT.md's Whitted shading over any tracer with
//   const SceneGeometry<Real>& geometry() const;
//   Hit<Real> closest(const Ray<Real>&) const;
//   bool occluded(const Ray<Real>&, Real t_max) const;
// The cpu device runs it over its Tracer (tracer.h); kdrt-bench runs it over
// Embree, so both shade by the very same code. The kernels' twin is cl/shade.cl.
#pragma once

#include "cpu/intersect.h"
#include "cpu/surface.h"
#include "scene/prepared_scene.h"

#include <kdrt/render_stats.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <optional>

namespace kdrt::detail::inline KDRT_CPU_ISA {

// Whitted shading exactly as FORMAT.md states it; recursion is fine here (the
// kernels use queues instead). Only the effects in `features` are simulated.
template <class Real, class TracerT>
class WhittedTracer {
public:
    using Vec = glm::vec<3, Real>;

    // fixed_epsilon > 0: the accuracy knob's absolute offset without self-exclusion.
    WhittedTracer(const PreparedScene& scene, const TracerT& tracer, Real fixed_epsilon = Real(0))
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
                const Real spec = specular_power(glm::dot(R, -ray.dir), static_cast<Real>(m.shininess));
                c += Vec(light.color) * (kd * C * std::max(Real(0), glm::dot(s.ns, L)) + ks * spec);
            }
        }
        if (depth >= f_.max_depth) return c;
        if (f_.reflection && m.reflect > 0.0) {
            const Vec R = ray.dir - Real(2) * glm::dot(ray.dir, s.ns) * s.ns;
            c += static_cast<Real>(m.reflect) * secondary(s, R, hit.id, depth, counts);
        }
        if (f_.refraction && m.transmit > 0.0) {
            const Vec T = refracted_direction(ray, s, static_cast<Real>(m.ior));
            c += static_cast<Real>(m.transmit) * secondary(s, T, hit.id, depth, counts);
        }
        return c;
    }

    // shade() for the N rays of a packet: each lane's colour is bit for bit
    // what shade() gives it, because the arithmetic is shade()'s, lane by
    // lane; only the rays are traced together. The lanes' shadow rays towards
    // one light go to the tracer's packet queries when they leave the same
    // object, their mirror and refracted rays when they leave the same flat
    // one (the packet queries answer as the single ones do, and take single
    // rays when the directions' signs differ); a lane without such a ray
    // borrows another lane's and drops the answer. `used`: the
    // lanes whose colour is wanted (bit k: lane k); the others are neither
    // shaded nor counted. Needs a tracer with Tracer's packet queries.
    template <int N>
    void shade_packet(const Ray<Real>* const (&rays)[N], const Hit<Real> (&hits)[N], std::uint32_t used, int depth,
                      RayCounts& counts, Vec (&out)[N]) const {
        Surface<Real> s[N];
        const Material* m[N] = {};
        std::uint32_t lit = 0;  // used lanes that hit something
        for (int k = 0; k < N; ++k) {
            if (!(used >> k & 1u)) continue;
            if (!hits[k].valid()) {
                out[k] = Vec(scene_.settings.background);
                continue;
            }
            lit |= 1u << k;
            s[k] = make_surface(tracer_.geometry(), *rays[k], hits[k]);
            m[k] = &scene_.materials[s[k].material];
            out[k] = Vec(scene_.settings.ambient) * Vec(m[k]->color) * static_cast<Real>(m[k]->diffuse);
        }
        if (f_.lights) {
            for (const PointLight& light : scene_.lights) {
                std::optional<Ray<Real>> shadow[N];
                Vec L[N];
                Real t_max[N] = {};
                std::uint32_t cast = 0;
                for (int k = 0; k < N; ++k) {
                    if (!(lit >> k & 1u)) continue;
                    L[k] = Vec(light.position) - s[k].p;
                    const Real dist = safe_length(L[k]);
                    L[k] /= dist;
                    if (!(glm::dot(s[k].ng, L[k]) > Real(0))) continue;
                    const Vec org = offset_origin(s[k], L[k], fixed_epsilon_);
                    ++counts.shadow;
                    shadow[k].emplace(org, L[k], leaving(hits[k].id));
                    t_max[k] = safe_length(Vec(light.position) - org);
                    cast |= 1u << k;
                }
                bool blocked[N] = {};
                occluded_packet(shadow, t_max, cast, hits, blocked);
                for (int k = 0; k < N; ++k) {
                    if (!(cast >> k & 1u) || blocked[k]) continue;
                    const Vec C(m[k]->color);
                    const Real kd = static_cast<Real>(m[k]->diffuse), ks = static_cast<Real>(m[k]->specular);
                    const Vec R = Real(2) * glm::dot(s[k].ns, L[k]) * s[k].ns - L[k];
                    const Real spec = specular_power(glm::dot(R, -rays[k]->dir), static_cast<Real>(m[k]->shininess));
                    out[k] += Vec(light.color) * (kd * C * std::max(Real(0), glm::dot(s[k].ns, L[k])) + ks * spec);
                }
            }
        }
        if (depth >= f_.max_depth) return;
        // Mirror rays, then refracted rays, each added as shade() adds them.
        auto add_secondary = [&](auto weight_of, auto direction_of) {
            std::optional<Ray<Real>> secondary_rays[N];
            std::uint32_t cast = 0;
            for (int k = 0; k < N; ++k) {
                if (!(lit >> k & 1u) || !(weight_of(*m[k]) > 0.0)) continue;
                const Vec dir = direction_of(k);
                ++counts.secondary;
                secondary_rays[k].emplace(offset_origin(s[k], dir, fixed_epsilon_), dir, leaving(hits[k].id));
                cast |= 1u << k;
            }
            Vec color[N];
            trace_packet(secondary_rays, cast, hits, depth, counts, color);
            for (int k = 0; k < N; ++k)
                if (cast >> k & 1u) out[k] += static_cast<Real>(weight_of(*m[k])) * color[k];
        };
        if (f_.reflection)
            add_secondary([](const Material& mat) { return mat.reflect; },
                          [&](int k) { return rays[k]->dir - Real(2) * glm::dot(rays[k]->dir, s[k].ns) * s[k].ns; });
        if (f_.refraction)
            add_secondary([](const Material& mat) { return mat.transmit; },
                          [&](int k) { return refracted_direction(*rays[k], s[k], static_cast<Real>(m[k]->ior)); });
    }

private:
    // max(0, x)^n, n >= 0 (the kernels' specular_power in cl/shade.cl). A
    // highlight facing away gives 0 without a call to pow: pow(+0, n) is +0
    // for n > 0 and 1 for n = 0, so the bits are pow's.
    static Real specular_power(Real x, Real n) {
        return x > Real(0) ? std::pow(x, n) : (n == Real(0) ? Real(1) : Real(0));
    }

    // Snell's law into or out of the object; total internal reflection mirrors.
    static Vec refracted_direction(const Ray<Real>& ray, const Surface<Real>& s, Real ior) {
        const Real eta = s.inside ? ior : Real(1) / ior;
        const Real cos_i = -glm::dot(ray.dir, s.ns);
        const Real k = Real(1) - eta * eta * (Real(1) - cos_i * cos_i);
        return k >= Real(0) ? glm::normalize(eta * ray.dir + (eta * cos_i - std::sqrt(k)) * s.ns)
                            : ray.dir - Real(2) * glm::dot(ray.dir, s.ns) * s.ns;
    }

    // The lanes in `cast` (the others borrow the first one's ray), as one
    // packet when there are two or more and they all leave the same object
    // (a flat one if `flat_only`): rays from different objects part ways (many
    // small spheres make packets slower than their rays alone), and so do
    // mirror and refracted rays off a curved surface.
    // Returns the lane the others borrow from, or -1: no packet.
    template <int N>
    int gather(const std::optional<Ray<Real>> (&r)[N], std::uint32_t cast, const Hit<Real> (&from)[N], bool flat_only,
               const Ray<Real>* (&lanes)[N]) const {
        if (std::popcount(cast) < 2) return -1;
        int first = 0;
        while (!(cast >> first & 1u)) ++first;
        if (flat_only && static_cast<std::uint32_t>(from[first].id) < tracer_.geometry().spheres.size()) return -1;
        for (int k = 0; k < N; ++k)
            if ((cast >> k & 1u) && from[k].id != from[first].id) return -1;
        for (int k = 0; k < N; ++k) lanes[k] = (cast >> k & 1u) ? &*r[k] : &*r[first];
        return first;
    }

    template <int N>
    void occluded_packet(const std::optional<Ray<Real>> (&r)[N], const Real (&t_max)[N], std::uint32_t cast,
                         const Hit<Real> (&from)[N], bool (&blocked)[N]) const {
        const Ray<Real>* lanes[N];
        const int first = gather(r, cast, from, false, lanes);
        if (first < 0) {
            for (int k = 0; k < N; ++k)
                if (cast >> k & 1u) blocked[k] = tracer_.occluded(*r[k], t_max[k]);
            return;
        }
        Real limits[N];
        for (int k = 0; k < N; ++k) limits[k] = t_max[(cast >> k & 1u) ? k : first];
        bool b[N];
        tracer_.occluded(lanes, limits, b);
        for (int k = 0; k < N; ++k) blocked[k] = b[k];
    }

    // Secondary rays of depth + 1, traced and shaded.
    template <int N>
    void trace_packet(const std::optional<Ray<Real>> (&r)[N], std::uint32_t cast, const Hit<Real> (&from)[N],
                      int depth, RayCounts& counts, Vec (&color)[N]) const {
        const Ray<Real>* lanes[N];
        if (gather(r, cast, from, true, lanes) < 0) {
            for (int k = 0; k < N; ++k)
                if (cast >> k & 1u) color[k] = trace(*r[k], depth + 1, counts);
            return;
        }
        Hit<Real> hits[N];
        tracer_.closest(lanes, hits);
        shade_packet(lanes, hits, cast, depth + 1, counts, color);
    }

    Vec secondary(const Surface<Real>& s, const Vec& dir, std::int32_t from, int depth, RayCounts& counts) const {
        ++counts.secondary;
        return trace(Ray<Real>(offset_origin(s, dir, fixed_epsilon_), dir, leaving(from)), depth + 1, counts);
    }

    // The fixed-epsilon knob relies on the offset alone: no self-exclusion.
    std::int32_t leaving(std::int32_t id) const { return fixed_epsilon_ > Real(0) ? kNoObject : id; }

    const PreparedScene& scene_;
    const TracerT& tracer_;
    SceneFeatures f_;
    Real fixed_epsilon_;
};

}  // namespace kdrt::detail::KDRT_CPU_ISA
