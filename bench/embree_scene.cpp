#include "embree_scene.h"

#ifdef KDRT_BENCH_HAVE_EMBREE

#include "common.h"

#include <kdrt/error.h>

#include <glm/geometric.hpp>

#include <limits>

namespace kdrt::bench {

namespace {

constexpr unsigned kSphereGeometry = 0;
constexpr unsigned kTriangleGeometry = 1;

std::string g_embree_error;

void on_embree_error(void*, RTCError code, const char* message) {
    g_embree_error = "Embree error " + std::to_string(static_cast<int>(code)) + ": " + (message ? message : "");
}

void check(const char* what) {
    if (!g_embree_error.empty()) {
        std::string e = std::string(what) + ": " + g_embree_error;
        g_embree_error.clear();
        throw Error(ErrorCode::Device, e);
    }
}

// The intersection context of a ray that leaves object `ignore`.
struct LeavingContext {
    RTCIntersectContext context;  // first member: Embree hands this pointer to the filter
    const std::vector<WorkingSphere>* spheres;
    std::int32_t ignore;
    glm::vec3 org, dir;
};

// Mirrors kdrt's intersect_sphere / intersect_object for the object a ray
// leaves: a triangle is never hit again; a sphere only on its far side, and
// only by a ray heading into it.
void reject_leaving_object(const RTCFilterFunctionNArguments* args) {
    const auto* c = reinterpret_cast<const LeavingContext*>(args->context);
    const auto sphere_count = static_cast<std::uint32_t>(c->spheres->size());
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0) continue;
        const unsigned geom = RTCHitN_geomID(args->hit, args->N, i);
        const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
        const auto id = static_cast<std::int32_t>(geom == kSphereGeometry ? prim : sphere_count + prim);
        if (id != c->ignore) continue;
        if (geom == kSphereGeometry) {
            const glm::vec3 to_org = c->org - (*c->spheres)[prim].center;
            const float along = -glm::dot(to_org, c->dir);  // t of the ray's closest approach to the centre
            const float t = RTCRayN_tfar(args->ray, args->N, i);
            if (glm::dot(c->dir, to_org) < 0.0f && t > along) continue;  // the far side, heading in: keep
        }
        args->valid[i] = 0;
    }
}


LeavingContext make_context(const std::vector<WorkingSphere>& spheres, const ShadingRay& ray) {
    LeavingContext c;
    rtcInitIntersectContext(&c.context);
    c.spheres = &spheres;
    c.ignore = ray.leaving;
    c.org = ray.origin;
    c.dir = ray.direction;
    if (ray.leaving >= 0) c.context.filter = reject_leaving_object;
    return c;
}

}  // namespace

RTCDevice embree_device() {
    static RTCDevice device = [] {
        RTCDevice d = rtcNewDevice(nullptr);
        if (!d) throw Error(ErrorCode::Device, "rtcNewDevice failed (error " + std::to_string(rtcGetDeviceError(nullptr)) + ")");
        rtcSetDeviceErrorFunction(d, on_embree_error, nullptr);
        return d;
    }();
    return device;
}

void fill_ray(RTCRay& r, const ShadingRay& ray, float t_max) {
    r.org_x = ray.origin.x;
    r.org_y = ray.origin.y;
    r.org_z = ray.origin.z;
    r.tnear = 0.0f;
    r.dir_x = ray.direction.x;
    r.dir_y = ray.direction.y;
    r.dir_z = ray.direction.z;
    r.time = 0.0f;
    r.tfar = t_max;
    r.mask = 0xFFFFFFFFu;
    r.id = 0;
    r.flags = 0;
}

std::string embree_version() { return std::string("Embree ") + RTC_VERSION_STRING; }

EmbreeScene::EmbreeScene(const WorkingScene& ws, bool context_filter, RTCBuildQuality quality, RTCDevice device) {
    for (std::uint32_t i = 0; i < ws.sphere_count(); ++i) spheres_.push_back(ws.sphere(i));
    scene_ = rtcNewScene(device);
    if (context_filter) rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
    rtcSetSceneBuildQuality(scene_, quality);
    if (!spheres_.empty()) {
        RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                                              4 * sizeof(float), spheres_.size()));
        for (std::size_t i = 0; i < spheres_.size(); ++i) {
            const WorkingSphere& s = spheres_[i];
            v[4 * i + 0] = s.center.x;
            v[4 * i + 1] = s.center.y;
            v[4 * i + 2] = s.center.z;
            v[4 * i + 3] = s.radius;
        }
        rtcSetGeometryBuildQuality(geom, quality);
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(scene_, geom, kSphereGeometry);
        rtcReleaseGeometry(geom);
    }
    if (ws.triangle_count() > 0) {
        RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        const std::size_t n = ws.triangle_count();
        auto* v = static_cast<float*>(
            rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * n));
        auto* idx = static_cast<unsigned*>(
            rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), n));
        check("allocating the triangle buffers");
        for (std::size_t i = 0; i < n; ++i) {
            const WorkingTriangle t = ws.triangle(static_cast<std::uint32_t>(i));
            const glm::vec3 p[3] = {t.v0, t.v1, t.v2};
            for (int k = 0; k < 3; ++k) {
                v[9 * i + 3 * k + 0] = p[k].x;
                v[9 * i + 3 * k + 1] = p[k].y;
                v[9 * i + 3 * k + 2] = p[k].z;
                idx[3 * i + k] = static_cast<unsigned>(3 * i + k);
            }
        }
        rtcSetGeometryBuildQuality(geom, quality);
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(scene_, geom, kTriangleGeometry);
        rtcReleaseGeometry(geom);
    }
    check("creating the Embree scene");
    const Stopwatch clock;
    rtcCommitScene(scene_);
    commit_ms_ = clock.ms();
    check("rtcCommitScene");
}

EmbreeScene::~EmbreeScene() {
    if (scene_) rtcReleaseScene(scene_);
}

ShadingHit EmbreeScene::closest(const ShadingRay& ray) const {
    LeavingContext c = make_context(spheres_, ray);
    RTCRayHit rh;
    fill_ray(rh.ray, ray, std::numeric_limits<float>::infinity());
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &c.context, &rh);
    ShadingHit h;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return h;
    h.object = static_cast<std::int32_t>(rh.hit.geomID == kSphereGeometry ? rh.hit.primID : sphere_count() + rh.hit.primID);
    h.t = rh.ray.tfar;
    h.u = rh.hit.u;
    h.v = rh.hit.v;
    return h;
}

bool EmbreeScene::occluded(const ShadingRay& ray, float t_max) const {
    LeavingContext c = make_context(spheres_, ray);
    RTCRay r;
    fill_ray(r, ray, t_max);
    rtcOccluded1(scene_, &c.context, &r);
    return r.tfar < 0.0f;  // set to -inf when something blocks the ray
}

std::int32_t EmbreeScene::intersect_id(const ShadingRay& ray, float& t) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    fill_ray(rh.ray, ray, std::numeric_limits<float>::infinity());
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return -1;
    t = rh.ray.tfar;
    return static_cast<std::int32_t>(rh.hit.geomID == kSphereGeometry ? rh.hit.primID : sphere_count() + rh.hit.primID);
}

}  // namespace kdrt::bench

#endif  // KDRT_BENCH_HAVE_EMBREE
