// Embree 3 over kdrt's working-frame geometry (kdrt::WorkingScene, float):
// spheres as RTC_GEOMETRY_TYPE_SPHERE_POINT (geometry 0), triangles as
// RTC_GEOMETRY_TYPE_TRIANGLE (geometry 1), so an Embree hit maps back to
// kdrt's object index. Its closest-hit and occlusion queries are a
// kdrt::ShadingIntersector, so that WorkingScene::shade shades Embree's hits.
//
// Self-intersection as in kdrt: the shader offsets secondary rays along the
// normal (relative to the object's magnitude), and a context filter function
// (RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION; only set for rays that leave an
// object) rejects the object the ray leaves, except a sphere's far side for a
// ray heading into it. Camera rays run without any filter.
#pragma once

#ifdef KDRT_BENCH_HAVE_EMBREE

#include <kdrt/working_scene.h>

#include <embree3/rtcore.h>

#include <string>
#include <vector>

namespace kdrt::bench {

// One Embree device per process, with Embree's defaults: rtcCommitScene
// builds on TBB's pool of every logical CPU. (A second device with
// "threads=1" would cap the first too: TBB's limit is process-wide.)
RTCDevice embree_device();

class EmbreeScene final : public ShadingIntersector {
public:
    // context_filter: build with RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION, needed
    // for secondary rays; the raw camera-ray test builds without it.
    EmbreeScene(const WorkingScene& scene, bool context_filter,
                RTCBuildQuality quality = RTC_BUILD_QUALITY_MEDIUM, RTCDevice device = embree_device());
    ~EmbreeScene() override;
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    double commit_ms() const { return commit_ms_; }  // rtcCommitScene: the BVH build
    RTCScene handle() const { return scene_; }
    std::uint32_t sphere_count() const { return static_cast<std::uint32_t>(spheres_.size()); }

    ShadingHit closest(const ShadingRay& ray) const override;
    bool occluded(const ShadingRay& ray, float t_max) const override;

    // The raw query for the throughput test: rtcIntersect1, no filter. Returns the object id or -1.
    std::int32_t intersect_id(const ShadingRay& ray, float& t) const;

private:
    std::vector<WorkingSphere> spheres_;  // the filter's far-side rule needs the centres
    RTCScene scene_ = nullptr;
    double commit_ms_ = 0.0;
};

// An Embree ray from one of kdrt's, valid for (0, t_max).
void fill_ray(RTCRay& r, const ShadingRay& ray, float t_max);

// "Embree 3.13.5" and the ISA Embree picked.
std::string embree_version();

}  // namespace kdrt::bench

#endif  // KDRT_BENCH_HAVE_EMBREE
