// A Scene as kdrt's renderers see it, for tools that bring their own
// intersector (kdrt-bench's Embree harness): the working frame's float
// geometry, its camera rays, and FORMAT.md's Whitted shading (the cpu
// renderer's own code) over closest-hit and occlusion queries the caller
// supplies. An intersector that finds what kdrt finds gets the cpu device's
// image bit for bit.
//
// The working frame is world space moved so that the scene's bounds are
// centred on the origin (world = working + frame_origin()). Objects are
// addressed by their index: spheres 0 .. S-1, then triangles S .. S+T-1;
// object_id() gives the public id Scene::add_* returned.
#pragma once

#include <kdrt/aabb.h>
#include <kdrt/export.h>
#include <kdrt/commit_options.h>
#include <kdrt/kd_tree.h>
#include <kdrt/render.h>
#include <kdrt/render_stats.h>
#include <kdrt/scene.h>
#include <kdrt/scene_features.h>

#include <glm/vec3.hpp>

#include <cstdint>
#include <limits>
#include <memory>

namespace kdrt {

// A ray in the working frame; direction is unit length. `leaving` is the
// index of the object a secondary ray leaves (its origin already pushed off
// the surface), or -1. kdrt's self-intersection rule: that object is not
// reported again, except a sphere's far side for a ray heading into it.
struct ShadingRay {
    glm::vec3 origin{0.0f}, direction{0.0f, 0.0f, 1.0f};
    std::int32_t leaving = -1;
};

struct ShadingHit {
    float t = std::numeric_limits<float>::infinity();
    std::int32_t object = -1;  // object index, -1: no hit
    float u = 0.0f, v = 0.0f;  // triangle: barycentrics of v1 and v2
};

// The caller's closest-hit and occlusion queries. Called from the threads
// that call shade(), concurrently.
class KDRT_API ShadingIntersector {
public:
    virtual ~ShadingIntersector();
    virtual ShadingHit closest(const ShadingRay& ray) const = 0;
    virtual bool occluded(const ShadingRay& ray, float t_max) const = 0;  // a hit with 0 < t < t_max
};

struct WorkingSphere {
    glm::vec3 center;
    float radius;
};

struct WorkingTriangle {
    glm::vec3 v0, v1, v2;
};

class KDRT_API WorkingScene {
public:
    // Prepared as a render with `options` would prepare it (the frame's
    // size, depth and samples; float precision only; the device is not
    // used). Throws kdrt::Error on bad input.
    explicit WorkingScene(const Scene& scene, const RenderOptions& options = {});
    ~WorkingScene();
    WorkingScene(WorkingScene&&) noexcept;
    WorkingScene& operator=(WorkingScene&&) noexcept;

    int width() const;
    int height() const;
    int samples() const;
    SceneFeatures features() const;
    Aabb bounds() const;              // the objects' bounds, working frame
    glm::dvec3 frame_origin() const;  // world position of the working frame's origin

    std::uint32_t sphere_count() const;
    std::uint32_t triangle_count() const;
    WorkingSphere sphere(std::uint32_t index) const;      // index < sphere_count()
    WorkingTriangle triangle(std::uint32_t index) const;  // index < triangle_count(): object sphere_count() + index
    std::uint32_t object_id(std::uint32_t object) const;  // the public id of an object index
    KdBuildInput build_input() const;  // for build_kd_tree, by object index

    // The camera ray through the centre of pixel (x, y), y = 0 the top row.
    ShadingRay camera_ray(int x, int y) const;

    // FORMAT.md's Whitted shading of a camera ray's closest hit (depth 1):
    // shadow and secondary rays go to `intersector`; counts.shadow and
    // counts.secondary are added to.
    glm::vec3 shade(const ShadingRay& ray, const ShadingHit& hit, const ShadingIntersector& intersector,
                    RayCounts& counts) const;

    // kdrt's own C++ traversal over `tree` (which must outlive it) as an
    // intersector: what checks a harness against the cpu device.
    std::unique_ptr<ShadingIntersector> kd_intersector(const KdTree& tree, Traversal traversal) const;

private:
    struct State;
    std::unique_ptr<State> state_;
};

}  // namespace kdrt
