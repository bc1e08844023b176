#include "cpu/reference_renderer.h"

#include "cpu/scene_tracer.h"
#include "cpu/surface.h"

#include <kdrt/camera.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

namespace kdrt::detail {

namespace {

// Whitted shading exactly as FORMAT.md states it; recursion is fine here (the
// kernels use queues instead). Only the effects in `features` are simulated.
template <class Real>
class WhittedTracer {
public:
    using Vec = glm::vec<3, Real>;

    WhittedTracer(const PreparedScene& scene, const SceneTracer<Real>& tracer, const RenderOptions& options)
        : scene_(scene), tracer_(tracer), f_(scene.features),
          fixed_epsilon_(options.self_intersection == SelfIntersection::FixedEpsilon
                             ? static_cast<Real>(options.fixed_epsilon)
                             : Real(0)) {}

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
                const Real dist = glm::length(L);
                L /= dist;
                if (!(glm::dot(s.ng, L) > Real(0))) continue;
                const Vec org = offset_origin(s, L, fixed_epsilon_);
                ++counts.shadow;
                if (tracer_.occluded(Ray<Real>(org, L, leaving(hit.id)), glm::length(Vec(light.position) - org)))
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
    const SceneTracer<Real>& tracer_;
    SceneFeatures f_;
    Real fixed_epsilon_;
};

template <class Real>
RenderResult render_with(const PreparedScene& scene, const KdTree* tree, const RenderOptions& options) {
    using Vec = glm::vec<3, Real>;
    const int W = scene.settings.width, H = scene.settings.height, N = scene.settings.samples;
    IntersectConfig config;
    config.moller = options.triangle_test == TriangleTest::MollerTrumbore;
    config.textbook = options.sphere_test == SphereTest::Textbook;
    SceneTracer<Real> tracer(scene.geometry<Real>(), tree, options.traversal, config);
    WhittedTracer<Real> whitted(scene, tracer, options);
    const CameraFrame cam(scene.camera, W, H);
    const Vec eye(cam.position);

    RenderResult result;
    result.image = Image(W, H);
    if (options.want_ids) {
        result.ids.assign(static_cast<std::size_t>(W) * H, -1);
        result.hit_t.assign(static_cast<std::size_t>(W) * H, 0.0f);
    }

    int threads = options.threads > 0 ? options.threads : static_cast<int>(std::thread::hardware_concurrency());
    threads = std::clamp(threads, 1, 256);
    std::atomic<int> next_row{0}, rows_done{0};
    std::vector<RayCounts> counts(static_cast<std::size_t>(threads));

    auto worker = [&](int index) {
        RayCounts& rc = counts[static_cast<std::size_t>(index)];
        for (int y = next_row++; y < H; y = next_row++) {
            for (int x = 0; x < W; ++x) {
                Vec sum(0);
                for (int s = 0; s < N; ++s) {
                    double sx, sy;
                    sample_offset(s, N, sx, sy);
                    const Ray<Real> ray(eye, Vec(cam.direction(x, y, W, H, sx, sy)));
                    ++rc.camera;
                    const Hit<Real> hit = tracer.closest(ray);
                    sum += whitted.shade(ray, hit, 1, rc);
                    // The id map records the first sample's camera ray (the pixel centre when N = 1).
                    if (options.want_ids && s == 0) {
                        const std::size_t i = static_cast<std::size_t>(y) * W + x;
                        result.ids[i] = hit.id;
                        result.hit_t[i] = hit.valid() ? static_cast<float>(hit.t) : 0.0f;
                    }
                }
                result.image.set(x, y, glm::vec3(sum / static_cast<Real>(N)));
            }
            const int done = ++rows_done;
            // Only the calling thread (index 0) reports progress.
            if (index == 0 && options.progress) options.progress(static_cast<double>(done) / H);
        }
    };

    const auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (int i = 1; i < threads; ++i) pool.emplace_back(worker, i);
    worker(0);
    for (std::thread& t : pool) t.join();
    if (options.progress) options.progress(1.0);
    result.render_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    for (const RayCounts& rc : counts) result.rays += rc;
    result.features = scene.features;
    result.device_name = std::string("cpu (C++ reference, ") + (sizeof(Real) == 8 ? "double" : "float") + ", " +
                         std::to_string(threads) + " threads)";
    return result;
}

}  // namespace

RenderResult render_reference(const PreparedScene& scene, const KdTree* tree, const RenderOptions& options) {
    if (options.precision == Precision::Double) return render_with<double>(scene, tree, options);
    return render_with<float>(scene, tree, options);
}

}  // namespace kdrt::detail
