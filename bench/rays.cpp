#include "rays.h"

#include "mesh_generator.h"

#include <kdrt/error.h>

#ifdef KDRT_BENCH_HAVE_EMBREE

#include "embree_scene.h"
#include "opencl_buffers.h"
#include "ray_export.h"

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/ray_query.h>
#include <kdrt/working_scene.h>

#include <glm/geometric.hpp>

#include <tbb/task_arena.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>

namespace kdrt::bench {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr std::size_t kChunk = 256;  // rays per work item of Embree's passes (a multiple of 16)

// Rays in the working frame (Embree's) and the same rays in world space (kdrt's queries).
struct RaySet {
    std::string name;
    bool coherent = false;
    std::vector<ShadingRay> working;
    std::vector<QueryRay> world;
};

RaySet make_ray_set(const WorkingScene& ws, bool camera, std::size_t random_count) {
    RaySet set{camera ? "camera" : "incoherent", camera, {}, {}};
    if (camera) {
        for (int y = 0; y < ws.height(); ++y)
            for (int x = 0; x < ws.width(); ++x) set.working.push_back(ws.camera_ray(x, y));
    } else {
        // Origins uniform in the box, directions uniform on the sphere (normalised Gaussians), seeded.
        std::mt19937 rng(20261129u);
        std::uniform_real_distribution<double> u(0.0, 1.0);
        std::normal_distribution<float> g(0.0f, 1.0f);
        const Aabb box = ws.bounds();
        while (set.working.size() < random_count) {
            const glm::dvec3 o = box.lo + glm::dvec3(u(rng), u(rng), u(rng)) * (box.hi - box.lo);
            const glm::vec3 d(g(rng), g(rng), g(rng));
            if (glm::length(d) > 1e-3f) set.working.push_back({glm::vec3(o), glm::normalize(d), -1});
        }
    }
    for (const ShadingRay& r : set.working) {
        const glm::dvec3 o = glm::dvec3(r.origin) + ws.frame_origin();
        QueryRay q{};
        for (int a = 0; a < 3; ++a) {
            q.origin[a] = static_cast<float>(o[a]);
            q.direction[a] = r.direction[a];
        }
        q.t_min = 0.0f;
        q.t_max = kInf;
        set.world.push_back(q);
    }
    return set;
}

// One pass of a tracer over a ray set: ids (closest: the object or -1; any
// hit: 1 or 0) and distances; returns its milliseconds.
using Pass = std::function<double(const RaySet&, bool any, std::int32_t* ids, float* ts)>;

struct Tracer {
    std::string name;
    Pass pass;
};

std::int32_t embree_id(const EmbreeScene& s, unsigned geom, unsigned prim) {
    if (geom == RTC_INVALID_GEOMETRY_ID) return -1;
    return static_cast<std::int32_t>(geom == 0 ? prim : s.sphere_count() + prim);  // 0: spheres, 1: triangles
}

void embree_single(const EmbreeScene& s, const RaySet& set, std::size_t b, std::size_t e, bool any, std::int32_t* ids,
                   float* ts) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (std::size_t i = b; i < e; ++i) {
        RTCRayHit rh;
        fill_ray(rh.ray, set.working[i], kInf);
        if (any) {
            rtcOccluded1(s.handle(), &context, &rh.ray);
            ids[i] = rh.ray.tfar < 0.0f;
            continue;
        }
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(s.handle(), &context, &rh);
        ids[i] = embree_id(s, rh.hit.geomID, rh.hit.primID);
        ts[i] = rh.ray.tfar;
    }
}

void embree_packets(const EmbreeScene& s, const RaySet& set, std::size_t b, std::size_t e, bool any, std::int32_t* ids,
                    float* ts) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = set.coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    for (std::size_t p = b; p < e; p += 16) {
        alignas(64) int valid[16];
        alignas(64) RTCRayHit16 rh;
        for (std::size_t k = 0; k < 16; ++k) {
            valid[k] = p + k < e ? -1 : 0;
            const ShadingRay& r = set.working[p + k < e ? p + k : b];
            rh.ray.org_x[k] = r.origin.x;
            rh.ray.org_y[k] = r.origin.y;
            rh.ray.org_z[k] = r.origin.z;
            rh.ray.dir_x[k] = r.direction.x;
            rh.ray.dir_y[k] = r.direction.y;
            rh.ray.dir_z[k] = r.direction.z;
            rh.ray.tnear[k] = 0.0f;
            rh.ray.tfar[k] = kInf;
            rh.ray.time[k] = 0.0f;
            rh.ray.mask[k] = 0xFFFFFFFFu;
            rh.ray.id[k] = 0;
            rh.ray.flags[k] = 0;
            rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
        }
        if (any) rtcOccluded16(valid, s.handle(), &context, &rh.ray);
        else rtcIntersect16(valid, s.handle(), &context, &rh);
        for (std::size_t k = 0; k < 16 && p + k < e; ++k) {
            if (any) {
                ids[p + k] = rh.ray.tfar[k] < 0.0f;
            } else {
                ids[p + k] = embree_id(s, rh.hit.geomID[k], rh.hit.primID[k]);
                ts[p + k] = rh.ray.tfar[k];
            }
        }
    }
}

Pass embree_pass(const EmbreeScene& s, bool packets, int threads) {
    return [&s, packets, threads](const RaySet& set, bool any, std::int32_t* ids, float* ts) {
        const Stopwatch clock;
        parallel_chunks(set.working.size(), threads, kChunk, [&](std::size_t b, std::size_t e, int) {
            (packets ? embree_packets : embree_single)(s, set, b, e, any, ids, ts);
        });
        return clock.ms();
    };
}

// A pass's answers as time_tracers compares them: closest, the object or -1
// and t; any hit, 1 or 0.
void copy_answers(bool any, const std::vector<QueryHit>& hits, const std::vector<std::uint8_t>& hit, std::int32_t* ids,
                  float* ts) {
    for (std::size_t i = 0; i < (any ? hit.size() : hits.size()); ++i) {
        if (any) {
            ids[i] = hit[i];
            continue;
        }
        ids[i] = hits[i].object == KDRT_NO_HIT ? -1 : static_cast<std::int32_t>(hits[i].object);
        ts[i] = hits[i].t;
    }
}

// kdrt's queries, one call per pass, on a oneTBB arena of `threads` (the cpu device runs on oneTBB).
Pass kdrt_pass(const CommittedScene& scene, int threads) {
    return [&scene, threads](const RaySet& set, bool any, std::int32_t* ids, float* ts) {
        tbb::task_arena arena(threads);
        const std::size_t n = set.world.size();
        std::vector<QueryHit> hits(any ? 0 : n);
        std::vector<std::uint8_t> hit(any ? n : 0);
        const Stopwatch clock;
        arena.execute([&] {
            if (any) occluded(scene, set.world, hit);
            else intersect(scene, set.world, hits);
        });
        const double ms = clock.ms();
        copy_answers(any, hits, hit, ids, ts);
        return ms;
    };
}

// The same queries on an OpenCL device's own buffers: the query alone is timed.
Pass buffers_pass(OpenClBuffers& buffers) {
    return [&buffers](const RaySet& set, bool any, std::int32_t* ids, float* ts) {
        const std::size_t n = set.world.size();
        std::vector<QueryHit> hits(any ? 0 : n);
        std::vector<std::uint8_t> hit(any ? n : 0);
        const double ms = any ? buffers.any(set.world, hit) : buffers.closest(set.world, hits);
        copy_answers(any, hits, hit, ids, ts);
        return ms;
    };
}

// Ids unlike the reference's (tracer 0), and of them those that are not ties
// (both hit at the same distance up to float rounding). More than one ray in
// a thousand beyond ties fails the run: a tracer that finds other hits is not timed.
Json check_ids(const std::string& what, const std::string& tracer, const std::vector<std::int32_t>& ids,
               const std::vector<float>& ts, const std::vector<std::int32_t>& ref_ids, const std::vector<float>& ref_ts) {
    std::size_t differ = 0, beyond_ties = 0;
    for (std::size_t i = 0; i < ids.size(); ++i) {
        if (ids[i] == ref_ids[i]) continue;
        ++differ;
        const bool tie = ids[i] >= 0 && ref_ids[i] >= 0 &&
                         std::abs(ts[i] - ref_ts[i]) <= 1e-4f * std::max(1.0f, std::abs(ref_ts[i]));
        beyond_ties += !tie;
    }
    if (beyond_ties > ids.size() / 1000)
        throw std::runtime_error(what + ": " + tracer + " and rtcIntersect1 disagree on " + std::to_string(beyond_ties) +
                                 " of " + std::to_string(ids.size()) + " rays beyond ties");
    return {{"differ", differ}, {"differ_beyond_ties", beyond_ties}};
}

// The reference tracer's answers (tracer 0, Embree's rtcIntersect1).
struct Reference {
    std::vector<std::int32_t> ids;
    std::vector<float> ts;
};

// The first round validates (and warms up); the timed rounds take the tracers in turn.
Json time_tracers(const std::string& what, const std::vector<Tracer>& tracers, const RaySet& set, bool any, int runs,
                  Reference* reference) {
    const std::size_t n = set.working.size(), m = tracers.size();
    std::vector<std::vector<std::int32_t>> ids(m, std::vector<std::int32_t>(n, -1));
    std::vector<std::vector<float>> ts(m, std::vector<float>(n, kInf));
    std::vector<std::vector<double>> ms(m);
    Json results = Json::array();
    for (int run = -1; run < runs; ++run)
        for (std::size_t k = 0; k < m; ++k) {
            const double t = tracers[k].pass(set, any, ids[k].data(), ts[k].data());
            if (run >= 0) ms[k].push_back(t);
        }
    for (std::size_t k = 0; k < m; ++k) {
        Json r = {{"name", tracers[k].name}, {"ms", median(ms[k])},
                  {"mrays_per_s", mrays_per_s(static_cast<double>(n), median(ms[k]))}};
        r.update(check_ids(what, tracers[k].name, ids[k], ts[k], ids[0], ts[0]));
        results.push_back(r);
    }
    *reference = {std::move(ids[0]), std::move(ts[0])};
    return results;
}

RTCBuildQuality quality_from_string(const std::string& q) {
    if (q == "low") return RTC_BUILD_QUALITY_LOW;
    if (q == "medium") return RTC_BUILD_QUALITY_MEDIUM;
    if (q == "high") return RTC_BUILD_QUALITY_HIGH;
    throw Error(ErrorCode::InvalidArgument, "--embree-quality '" + q + "': expected low, medium or high");
}

std::vector<std::string> query_devices(const RaysOptions& o) {
    if (!o.devices.empty()) return o.devices;
    std::vector<std::string> ids = all_device_ids();
    if (ids.size() > 2) ids.resize(2);  // the cpu device and the first OpenCL device
    return ids;
}

// Builds, refits and updates are timed as `kdrt-bench build` times builds
// (median_build_ms): a first touch of fresh memory costs page faults that
// vary from process to process.
constexpr int kBuildRuns = 3;

// The structure the cpu device built for its queries (its build timed again,
// median_build_ms), and Embree's BVH build beside it.
Json tree_json(const std::string& name, const WorkingScene& ws, const CommittedScene& cpu, const Scene& scene,
               const CommitOptions& commit, double embree_build_ms) {
    const double build_ms = median_build_ms(
        kBuildRuns, [&] { return CommittedScene::commit(cpu.device(), scene, commit).stats().build_ms; });
    Json j = {{"input", name},
              {"accel", to_string(commit.accel)},
              {"objects", ws.sphere_count() + ws.triangle_count()},
              {"build_ms", build_ms},
              {"embree_build_ms", embree_build_ms},
              {"device_bytes", cpu.stats().device_bytes}};
    if (const KdTree* tree = cpu.tree()) {
        const KdTreeStats s = kd_tree_stats(*tree, commit.tree.with_triangle_cost(cpu.device().triangle_cost()));
        j.update({{"nodes", s.nodes}, {"leaves", s.leaves}, {"empty_leaves", s.empty_leaves},
                  {"references_per_object", s.duplication},
                  {"bytes_per_object", s.per_object(s.node_bytes + s.leaf_object_bytes)}, {"sah_cost", s.sah_cost}});
    } else if (const std::optional<BvhStats> s = cpu.bvh_stats()) {
        j.update({{"nodes", s->nodes}, {"leaves", s->leaves}, {"empty_leaves", s->empty_slots},
                  {"references_per_object", 1.0}, {"bytes_per_object", s->per_object(s->total_bytes())},
                  {"sah_cost", s->sah_cost}});
    }
    return j;
}

// update() of a BVH scene whose every mesh vertex moved (a slight swell, no
// topology change), on a commit of its own: it refits instead of building.
// The refit's milliseconds (its boxes and the BVH's, CommitStats::build_ms)
// and the whole update's (the geometry prepared again, the packed leaves
// refilled); medians as median_build_ms, the vertices moving there and back.
Json refit_json(const Device& cpu, const Scene& scene) {
    CommitOptions commit;
    commit.accel = Accel::Bvh;
    CommittedScene c = CommittedScene::commit(cpu, scene, commit);
    Scene moved = scene;
    for (Mesh& m : moved.meshes)
        for (glm::dvec3& p : m.positions) p *= 1.0 + 0.002 * std::sin(7.0 * p.x + 3.0 * p.y);
    std::vector<double> refit_ms;
    bool there = false;
    const double update_ms = median_build_ms(kBuildRuns, [&] {
        there = !there;
        const CommitStats before = c.stats();
        Stopwatch clock;
        c.update(there ? moved : scene);
        const double ms = clock.ms();
        if (c.stats().refits != before.refits + 1) throw Error(ErrorCode::InvalidArgument, "update() did not refit");
        refit_ms.push_back(c.stats().build_ms - before.build_ms);
        return ms;
    });
    refit_ms.erase(refit_ms.begin(), refit_ms.end() - kBuildRuns);  // the warm-up's
    return {{"refit_ms", median(refit_ms)}, {"update_ms", update_ms}};
}

}  // namespace

Json run_rays(const RaysOptions& o) {
    if (o.runs < 1) throw Error(ErrorCode::InvalidArgument, "--runs must be at least 1");
    const int threads = worker_count(o.threads);
    std::vector<NamedScene> inputs = load_scenes(o.scenes, o.scenes_dir);
    for (const std::string& spec : o.meshes) {
        Scene s = make_generated_scene(spec);
        inputs.push_back({s.name, std::move(s)});
    }
    std::vector<Device> devices;
    for (const std::string& d : query_devices(o)) devices.push_back(Device::open(d));
    Json trees = Json::array(), rows = Json::array(), embree_builds = Json::array();
    for (const NamedScene& in : inputs) {
        RenderOptions ro;
        ro.frame.width = ro.frame.height = o.camera_size;
        const WorkingScene ws(in.scene, ro);
        const RTCBuildQuality quality = quality_from_string(o.embree_quality);
        const EmbreeScene embree(ws, false, quality);
        const double embree_ms =
            median_build_ms(kBuildRuns, [&] { return EmbreeScene(ws, false, quality).commit_ms(); });
        std::fprintf(stderr, "rays: %s: Embree BVH %.0f ms\n", in.name.c_str(), embree_ms);
        std::vector<Tracer> tracers{{"Embree rtcIntersect1", embree_pass(embree, false, threads)},  // the reference
                                    {"Embree rtcIntersect16", embree_pass(embree, true, threads)}};
        std::optional<EmbreeScene> spatial;  // Embree's high quality: spatial splits
        if (o.embree_high && o.embree_quality == "medium") {
            spatial.emplace(ws, false, RTC_BUILD_QUALITY_HIGH);
            const double high_ms =
                median_build_ms(kBuildRuns, [&] { return EmbreeScene(ws, false, RTC_BUILD_QUALITY_HIGH).commit_ms(); });
            std::fprintf(stderr, "rays: %s: Embree high-quality BVH %.0f ms\n", in.name.c_str(), high_ms);
            tracers.push_back({"Embree rtcIntersect1 high", embree_pass(*spatial, false, threads)});
            embree_builds.push_back({{"input", in.name}, {"medium_ms", embree_ms}, {"high_ms", high_ms}});
        }
        std::vector<CommittedScene> committed;  // each device builds its own structure
        std::vector<std::unique_ptr<OpenClBuffers>> buffer_scenes;  // --device-buffers: each on its own context
        committed.reserve(devices.size() * o.accels.size());
        for (const std::string& accel : o.accels) {
            CommitOptions commit;
            commit.accel = accel_from_string(accel);
            if (o.intersection_cost > 0.0) commit.tree.intersection_cost = o.intersection_cost;
            for (const Device& d : devices) {
                const CommittedScene& c = committed.emplace_back(CommittedScene::commit(d, in.scene, commit));
                if (d.info().id == "cpu") {
                    trees.push_back(tree_json(in.name, ws, c, in.scene, commit, embree_ms));
                    if (commit.accel == Accel::Bvh && !in.scene.meshes.empty())
                        trees.back().update(refit_json(d, in.scene));
                }
                tracers.push_back({"kdrt " + d.info().id + " " + accel, kdrt_pass(c, threads)});
                if (o.device_buffers && d.is_opencl()) {
                    buffer_scenes.push_back(std::make_unique<OpenClBuffers>(d.info(), in.scene, commit));
                    tracers.push_back(
                        {"kdrt " + d.info().id + " " + accel + " buffers", buffers_pass(*buffer_scenes.back())});
                }
            }
        }
        std::optional<RayExport> exported;
        if (!o.export_dir.empty() && one_mesh(in.scene)) exported.emplace(o.export_dir, in.scene);
        for (const bool camera : {true, false}) {
            const RaySet set = make_ray_set(ws, camera, o.random_rays);
            if (exported) exported->rays(set.name, set.world);
            for (const bool any : {false, true}) {
                const std::string what = in.name + " " + set.name + (any ? " any hit" : " closest");
                Reference reference;
                Json tracer_results = time_tracers(what, tracers, set, any, o.runs, &reference);
                if (exported) exported->answers(any, reference.ids, reference.ts);
                std::fprintf(stderr, "  %s:", what.c_str());
                for (const Json& t : tracer_results)
                    std::fprintf(stderr, " %s %.2f", t["name"].get<std::string>().c_str(), t["mrays_per_s"].get<double>());
                std::fprintf(stderr, " Mrays/s\n");
                rows.push_back({{"input", in.name}, {"rays", set.name}, {"query", any ? "any hit" : "closest"},
                                {"count", set.working.size()}, {"tracers", tracer_results}});
            }
        }
        if (exported) exported->finish();
    }
    return {{"settings",
             {{"runs", o.runs}, {"threads", threads}, {"camera_size", o.camera_size}, {"random_rays", o.random_rays},
              {"embree_quality", o.embree_quality}, {"embree_high", o.embree_high},
              {"intersection_cost", o.intersection_cost}, {"accels", o.accels}}},
            {"trees", trees},
            {"embree_builds", embree_builds},
            {"rows", rows}};
}

}  // namespace kdrt::bench

#else  // no Embree

namespace kdrt::bench {

Json run_rays(const RaysOptions&) {
    throw Error(ErrorCode::Unsupported,
                "kdrt-bench was built without Embree 3 (scripts/install-deps.sh --bench, then reconfigure)");
}

}  // namespace kdrt::bench

#endif
