// Embree 3 over kdrt's prepared geometry (float, the same working frame):
// spheres as RTC_GEOMETRY_TYPE_SPHERE_POINT (geometry 0), triangles as
// RTC_GEOMETRY_TYPE_TRIANGLE (geometry 1), so an Embree hit maps back to
// FORMAT.md's object id. Closest-hit and occlusion queries speak kdrt's
// detail::Ray / detail::Hit so that WhittedShader can use either intersector.
//
// Self-intersection as in kdrt: the shader offsets secondary rays along the
// normal (relative to the object's magnitude), and a context filter function
// (RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION; only set for rays that leave an
// object) rejects the object the ray leaves, except a sphere's far side for a
// ray heading into it. Camera rays run without any filter.
#pragma once

#ifdef KDRT_BENCH_HAVE_EMBREE

#include "cpu/intersect.h"
#include "cpu/ray.h"
#include "scene/prepared_scene.h"

#include <embree3/rtcore.h>

#include <string>

namespace kdrt::bench {

// One Embree device per process, with Embree's defaults: rtcCommitScene
// builds on TBB's pool of every logical CPU. (A second device with
// "threads=1" would cap the first too: TBB's limit is process-wide.)
RTCDevice embree_device();

class EmbreeScene {
public:
    // context_filter: build with RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION, needed
    // for secondary rays; the raw camera-ray test builds without it.
    EmbreeScene(const detail::SceneGeometry<float>& geometry, bool context_filter,
                RTCBuildQuality quality = RTC_BUILD_QUALITY_MEDIUM, RTCDevice device = embree_device());
    ~EmbreeScene();
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    double commit_ms() const { return commit_ms_; }  // rtcCommitScene: the BVH build
    RTCScene handle() const { return scene_; }
    const detail::SceneGeometry<float>& geometry() const { return g_; }

    detail::Hit<float> closest(const detail::Ray<float>& ray) const;
    bool occluded(const detail::Ray<float>& ray, float t_max) const;

    // The raw query for the throughput test: rtcIntersect1, no filter. Returns the object id or -1.
    std::int32_t intersect_id(const detail::Ray<float>& ray, float& t) const;

private:
    const detail::SceneGeometry<float>& g_;
    RTCScene scene_ = nullptr;
    double commit_ms_ = 0.0;
};

// An Embree ray from one of kdrt's, valid for (0, t_max).
void fill_ray(RTCRay& r, const detail::Ray<float>& ray, float t_max);

// "Embree 3.13.5" and the ISA Embree picked.
std::string embree_version();

}  // namespace kdrt::bench

#endif  // KDRT_BENCH_HAVE_EMBREE
