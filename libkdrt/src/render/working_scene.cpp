// kdrt::WorkingScene: a PreparedScene behind a small public face, and the
// cpu renderer's WhittedTracer over a caller's intersector.
#include "cpu/intersect.h"
#include "cpu/ray.h"
#include "cpu/tracer.h"
#include "cpu/whitted_tracer.h"
#include "scene/prepared_scene.h"

#include <kdrt/camera.h>
#include <kdrt/error.h>
#include <kdrt/working_scene.h>

namespace kdrt {

namespace {

using detail::Hit;
using detail::Ray;

ShadingRay to_shading(const Ray<float>& r) { return {r.org, r.dir, r.ignore}; }

// The caller's intersector in the shape WhittedTracer traces through.
class CallerTracer {
public:
    CallerTracer(const detail::SceneGeometry<float>& g, const ShadingIntersector& i) : g_(g), i_(i) {}
    const detail::SceneGeometry<float>& geometry() const { return g_; }
    Hit<float> closest(const Ray<float>& ray) const {
        const ShadingHit s = i_.closest(to_shading(ray));
        Hit<float> h;
        if (s.object < 0) return h;
        h.t = s.t;
        h.id = s.object;
        h.b1 = s.u;
        h.b2 = s.v;
        return h;
    }
    bool occluded(const Ray<float>& ray, float t_max) const { return i_.occluded(to_shading(ray), t_max); }

private:
    const detail::SceneGeometry<float>& g_;
    const ShadingIntersector& i_;
};

// kdrt's own traversal as a caller's intersector.
class KdIntersector final : public ShadingIntersector {
public:
    KdIntersector(const detail::SceneGeometry<float>& g, const KdTree& tree, Traversal traversal)
        : tracer_(g, &tree, traversal) {}
    ShadingHit closest(const ShadingRay& ray) const override {
        const Hit<float> h = tracer_.closest(Ray<float>(ray.origin, ray.direction, ray.leaving));
        return {h.t, h.id, h.b1, h.b2};
    }
    bool occluded(const ShadingRay& ray, float t_max) const override {
        return tracer_.occluded(Ray<float>(ray.origin, ray.direction, ray.leaving), t_max);
    }

private:
    detail::Tracer<float> tracer_;
};

}  // namespace

ShadingIntersector::~ShadingIntersector() = default;

struct WorkingScene::State {
    detail::PreparedScene p;
    CameraFrame camera;
    glm::vec3 eye;
    State(detail::PreparedScene&& prepared)
        : p(std::move(prepared)), camera(p.camera, p.settings.width, p.settings.height), eye(camera.position) {}
};

WorkingScene::WorkingScene(const Scene& scene, const RenderOptions& options) {
    if (options.commit.accuracy.precision != Precision::Float)
        throw Error(ErrorCode::Unsupported, "WorkingScene: float precision only");
    state_ = std::make_unique<State>(detail::prepare_scene(scene, options.commit, options.frame));
}
WorkingScene::~WorkingScene() = default;
WorkingScene::WorkingScene(WorkingScene&&) noexcept = default;
WorkingScene& WorkingScene::operator=(WorkingScene&&) noexcept = default;

int WorkingScene::width() const { return state_->p.settings.width; }
int WorkingScene::height() const { return state_->p.settings.height; }
int WorkingScene::samples() const { return state_->p.settings.samples; }
SceneFeatures WorkingScene::features() const { return state_->p.features; }
Aabb WorkingScene::bounds() const { return state_->p.bounds; }
glm::dvec3 WorkingScene::frame_origin() const { return state_->p.frame_origin; }
std::uint32_t WorkingScene::sphere_count() const {
    return static_cast<std::uint32_t>(state_->p.geometry_f.spheres.size());
}
std::uint32_t WorkingScene::triangle_count() const {
    return static_cast<std::uint32_t>(state_->p.geometry_f.triangles.size());
}
WorkingSphere WorkingScene::sphere(std::uint32_t index) const {
    const auto& s = state_->p.geometry_f.spheres.at(index);
    return {s.center, s.radius};
}
WorkingTriangle WorkingScene::triangle(std::uint32_t index) const {
    const auto& t = state_->p.geometry_f.triangles.at(index);
    return {t.v0, t.v1, t.v2};
}
std::uint32_t WorkingScene::object_id(std::uint32_t object) const { return state_->p.public_id(object); }
KdBuildInput WorkingScene::build_input() const { return state_->p.build_input(); }

ShadingRay WorkingScene::camera_ray(int x, int y) const {
    const State& s = *state_;
    return {s.eye, glm::vec3(s.camera.direction(x, y, s.p.settings.width, s.p.settings.height)), -1};
}

glm::vec3 WorkingScene::shade(const ShadingRay& ray, const ShadingHit& hit, const ShadingIntersector& intersector,
                              RayCounts& counts) const {
    const CallerTracer tracer(state_->p.geometry_f, intersector);
    const detail::WhittedTracer<float, CallerTracer> whitted(state_->p, tracer);
    Hit<float> h;
    if (hit.object >= 0) {
        h.t = hit.t;
        h.id = hit.object;
        h.b1 = hit.u;
        h.b2 = hit.v;
    }
    return whitted.shade(Ray<float>(ray.origin, ray.direction, ray.leaving), h, 1, counts);
}

std::unique_ptr<ShadingIntersector> WorkingScene::kd_intersector(const KdTree& tree, Traversal traversal) const {
    return std::make_unique<KdIntersector>(state_->p.geometry_f, tree, traversal);
}

}  // namespace kdrt
