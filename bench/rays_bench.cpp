#include "rays_bench.h"

#include "machine_info.h"
#include "report.h"

#include <kdrt/error.h>

#ifdef KDRT_BENCH_HAVE_EMBREE

#include "camera_rays.h"
#include "embree_scene.h"
#include "interference.h"
#include "mesh_generator.h"
#include "parallel.h"
#include "ray_queries.h"
#include "stats.h"
#include "subprocess.h"
#include "table.h"
#include "timed_render.h"

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/ray_query.h>
#include <kdrt/render.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>

namespace kdrt::bench {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr std::size_t kChunk = 256;  // rays per work item, for every tracer (a multiple of 16)

// Origins uniform in the box, directions uniform on the sphere (normalised Gaussians).
std::vector<detail::Ray<float>> make_random_rays(const Aabb& box, std::size_t count, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<float> g(0.0f, 1.0f);
    std::vector<detail::Ray<float>> rays;
    rays.reserve(count);
    while (rays.size() < count) {
        const glm::dvec3 o = box.lo + glm::dvec3(u(rng), u(rng), u(rng)) * (box.hi - box.lo);
        const glm::vec3 d(g(rng), g(rng), g(rng));
        const float len = glm::length(d);
        if (!(len > 1e-3f)) continue;
        rays.emplace_back(glm::vec3(o), d / len);
    }
    return rays;
}

RTCBuildQuality quality_from_string(const std::string& q) {
    if (q == "low") return RTC_BUILD_QUALITY_LOW;
    if (q == "medium") return RTC_BUILD_QUALITY_MEDIUM;
    if (q == "high") return RTC_BUILD_QUALITY_HIGH;
    throw Error(ErrorCode::InvalidArgument, "--embree-quality '" + q + "': expected low, medium or high");
}

// One pass of `body(begin, end)` over n rays in chunks on `threads` workers; milliseconds.
template <class Body>
double timed_pass(std::size_t n, int threads, Body&& body) {
    const Stopwatch clock;
    parallel_chunks(n, threads, kChunk, [&](std::size_t b, std::size_t e, int) { body(b, e); });
    return clock.ms();
}

// Embree's side: one ray or 16-ray packets, closest or any hit; writes ids
// (object id or -1; any hit: 1 or 0) and t.
class EmbreeTracer {
public:
    EmbreeTracer(const EmbreeScene& scene, std::uint32_t sphere_count) : scene_(scene), spheres_(sphere_count) {}

    void single(const std::vector<detail::Ray<float>>& rays, std::size_t b, std::size_t e, bool any, float t_max,
                std::int32_t* ids, float* ts) const {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        for (std::size_t i = b; i < e; ++i) {
            RTCRayHit rh;
            fill_ray(rh.ray, rays[i], t_max);
            if (any) {
                rtcOccluded1(scene_.handle(), &context, &rh.ray);
                ids[i] = rh.ray.tfar < 0.0f;
                continue;
            }
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(scene_.handle(), &context, &rh);
            ids[i] = id_of(rh.hit.geomID, rh.hit.primID);
            ts[i] = rh.ray.tfar;
        }
    }

    void packets(const std::vector<detail::Ray<float>>& rays, std::size_t b, std::size_t e, bool any, float t_max,
                 bool coherent, std::int32_t* ids, float* ts) const {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        context.flags = coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
        for (std::size_t p = b; p < e; p += 16) {
            alignas(64) int valid[16];
            alignas(64) RTCRayHit16 rh;
            for (int k = 0; k < 16; ++k) {
                const std::size_t i = p + k;
                valid[k] = i < e ? -1 : 0;
                const detail::Ray<float>& r = rays[i < e ? i : b];
                rh.ray.org_x[k] = r.org.x;
                rh.ray.org_y[k] = r.org.y;
                rh.ray.org_z[k] = r.org.z;
                rh.ray.tnear[k] = 0.0f;
                rh.ray.dir_x[k] = r.dir.x;
                rh.ray.dir_y[k] = r.dir.y;
                rh.ray.dir_z[k] = r.dir.z;
                rh.ray.time[k] = 0.0f;
                rh.ray.tfar[k] = t_max;
                rh.ray.mask[k] = 0xFFFFFFFFu;
                rh.ray.id[k] = 0;
                rh.ray.flags[k] = 0;
                rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
                rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
            }
            if (any) rtcOccluded16(valid, scene_.handle(), &context, &rh.ray);
            else rtcIntersect16(valid, scene_.handle(), &context, &rh);
            for (int k = 0; k < 16 && p + k < e; ++k) {
                if (any) {
                    ids[p + k] = rh.ray.tfar[k] < 0.0f;
                } else {
                    ids[p + k] = id_of(rh.hit.geomID[k], rh.hit.primID[k]);
                    ts[p + k] = rh.ray.tfar[k];
                }
            }
        }
    }

private:
    std::int32_t id_of(unsigned geom, unsigned prim) const {
        if (geom == RTC_INVALID_GEOMETRY_ID) return -1;
        return static_cast<std::int32_t>(geom == 0 ? prim : spheres_ + prim);  // geometry 0: spheres, 1: triangles
    }

    const EmbreeScene& scene_;
    std::uint32_t spheres_;
};

struct Row {
    std::string mesh, rays, query;
    std::size_t triangles = 0, count = 0;
    double kdrt_ms = kNaN, e1_ms = kNaN, e16_ms = kNaN, opencl_ms = kNaN;
    std::size_t differ = 0, differ_far = 0;  // ids unlike Embree's; of them, with t farther apart than rounding
    double other_cores = 0.0;
};

struct MeshInfo {
    std::string name;
    std::size_t triangles = 0;
    double build_ms = kNaN, embree_commit_ms = kNaN;
    KdTreeStats stats;
};

class RaysBench {
public:
    explicit RaysBench(const RaysBenchOptions& o) : opt_(o), threads_(worker_count(o.threads)) {}

    int run() {
        if (opt_.devices.empty()) {
            for (const std::string& d : all_device_ids())
                if (d != "cpu") devices_.push_back(d);
        } else {
            for (const std::string& d : opt_.devices)
                if (d != "cpu") devices_.push_back(d);
        }
        for (const std::string& spec : opt_.meshes) measure_mesh(spec);
        write_outputs();
        return 0;
    }

private:
    void measure_mesh(const std::string& spec) {
        const Scene scene = make_generated_scene(spec);
        RenderOptions ro;
        ro.width = ro.height = opt_.camera_size;
        const detail::PreparedScene p = detail::prepare_scene(scene, ro);
        MeshInfo info;
        info.name = scene.name;
        info.triangles = p.geometry_f.triangles.size();
        std::fprintf(stderr, "%s: %zu triangles\n", info.name.c_str(), info.triangles);
        KdBuildConfig config;  // the default builder and parameters
        if (opt_.intersection_cost > 0.0) config.intersection_cost = opt_.intersection_cost;
        Stopwatch clock;
        KdTree tree = build_kd_tree(p.build_input(), config);
        info.build_ms = clock.ms();
        info.stats = kd_tree_stats(tree, config);
        if (opt_.traversal == "ropes") build_ropes(tree);
        const EmbreeScene embree(p.geometry_f, false, quality_from_string(opt_.embree_quality));
        info.embree_commit_ms = embree.commit_ms();
        std::fprintf(stderr, "  kd-tree build %.0f ms, Embree BVH build %.0f ms\n", info.build_ms, info.embree_commit_ms);
        meshes_.push_back(info);

        // kdrt traces through the public API, on the tree just built.
        ro.traversal = traversal_from_string(opt_.traversal);
        ro.tree = config;
        ro.tree_in_memory = std::make_shared<const KdTree>(std::move(tree));
        const CommittedScene committed = CommittedScene::commit(cpu_, scene, ro);
        const EmbreeTracer et(embree, static_cast<std::uint32_t>(p.geometry_f.spheres.size()));
        const std::vector<detail::Ray<float>> camera = make_camera_rays(p);
        const std::vector<detail::Ray<float>> random = make_random_rays(p.bounds, opt_.random_rays, 20261129u);

        for (int set = 0; set < 2; ++set) {
            const std::vector<detail::Ray<float>>& rays = set == 0 ? camera : random;
            const std::vector<QueryRay> query_rays = to_query_rays(rays, p.frame_origin);
            const bool coherent = set == 0;
            for (int any = 0; any < 2; ++any) {
                Row row;
                row.mesh = info.name;
                row.triangles = info.triangles;
                row.rays = coherent ? "camera" : "incoherent";
                row.query = any ? "any hit" : "closest";
                row.count = rays.size();
                measure(rays, query_rays, coherent, any != 0, committed, et, row);
                if (coherent && !any) row.opencl_ms = opencl_camera_ms(scene);
                std::fprintf(stderr, "  %s %s: kdrt %.2f, Embree1 %.2f, Embree16 %.2f Mrays/s; %zu differ (%zu not ties)\n",
                             row.rays.c_str(), row.query.c_str(), mrays(row, row.kdrt_ms), mrays(row, row.e1_ms),
                             mrays(row, row.e16_ms), row.differ, row.differ_far);
                rows_.push_back(row);
            }
        }
    }

    static double mrays(const Row& r, double ms) { return mrays_per_s(static_cast<double>(r.count), ms); }

    void measure(const std::vector<detail::Ray<float>>& rays, const std::vector<QueryRay>& query_rays, bool coherent,
                 bool any, const CommittedScene& committed, const EmbreeTracer& et, Row& row) const {
        const std::size_t n = rays.size();
        const float t_max = kInf;
        std::vector<std::int32_t> ids[3];
        std::vector<float> ts[3];
        for (int k = 0; k < 3; ++k) {
            ids[k].assign(n, -1);
            ts[k].assign(n, kInf);
        }
        auto pass = [&](int k) {
            std::int32_t* id = ids[k].data();
            float* t = ts[k].data();
            if (k == 0)
                return any ? time_occluded(committed, query_rays, threads_, id)
                           : time_intersect(committed, query_rays, threads_, id, t);
            return timed_pass(n, threads_, [&](std::size_t b, std::size_t e) {
                if (k == 1) {
                    et.single(rays, b, e, any, t_max, id, t);
                } else {
                    et.packets(rays, b, e, any, t_max, coherent, id, t);
                }
            });
        };
        // The first round validates (and warms up); the timed rounds interleave the three tracers.
        std::vector<double> ms[3];
        Interference others;
        for (int run = -1; run < opt_.runs; ++run) {
            for (int k = 0; k < 3; ++k) {
                const double t = pass(k);
                if (run >= 0) ms[k].push_back(t);
            }
            if (run == -1) validate(ids, ts, row);
        }
        row.other_cores = others.other_cores();
        row.kdrt_ms = median(ms[0]);
        row.e1_ms = median(ms[1]);
        row.e16_ms = median(ms[2]);
    }

    // kdrt's ids against rtcIntersect1's; Embree's two interfaces must agree exactly.
    static void validate(const std::vector<std::int32_t> ids[3], const std::vector<float> ts[3], Row& row) {
        for (std::size_t i = 0; i < ids[0].size(); ++i) {
            if (ids[1][i] != ids[2][i] && ids[1][i] >= 0 && ids[2][i] >= 0 && ts[1][i] != ts[2][i])
                std::fprintf(stderr, "  note: rtcIntersect1 and rtcIntersect16 differ on ray %zu\n", i);
            if (ids[0][i] == ids[1][i]) continue;
            ++row.differ;
            // A tie or an edge: both hit at the same distance up to float rounding.
            const float a = ts[0][i], b = ts[1][i];
            const bool tie = ids[0][i] >= 0 && ids[1][i] >= 0 && std::abs(a - b) <= 1e-4f * std::max(1.0f, std::abs(b));
            if (!tie) ++row.differ_far;
        }
        if (row.differ_far > ids[0].size() / 1000)
            throw std::runtime_error(row.mesh + " " + row.rays + " " + row.query + ": kdrt and Embree disagree on " +
                                                 std::to_string(row.differ_far) + " of " + std::to_string(ids[0].size()) +
                                                 " rays beyond ties and edges");
    }

    double opencl_camera_ms(const Scene& scene) {
        if (devices_.empty()) return kNaN;
        RenderOptions o;
        o.width = o.height = opt_.camera_size;
        o.device = devices_.front();
        o.tree_cache_dir = tmp_.fresh("trees");
        return camera_render_ms(scene, o, opt_.runs);
    }

    void write_outputs() const {
        TextTable t;
        const std::string dev = devices_.empty() ? std::string("OpenCL") : devices_.front();
        t.header = {"mesh", "rays", "query", "kdrt cpu Mrays/s", "Embree 1 Mrays/s", "Embree 16 Mrays/s",
                    "kdrt / Embree 1 (time)", dev + " Mrays/s (depth-1 render)", "ids unlike Embree (beyond ties)",
                    "others' cores"};
        TextTable csv;
        csv.header = {"mesh", "triangles", "rays", "query", "count", "tracer", "threads", "ms", "mrays_per_s", "note"};
        for (const Row& r : rows_) {
            t.add({r.mesh, r.rays, r.query, fmt(mrays(r, r.kdrt_ms), 2), fmt(mrays(r, r.e1_ms), 2),
                   fmt(mrays(r, r.e16_ms), 2), fmt_ratio(r.kdrt_ms / r.e1_ms),
                   std::isnan(r.opencl_ms) ? "-" : fmt(mrays(r, r.opencl_ms), 2),
                   fmt(100.0 * static_cast<double>(r.differ) / static_cast<double>(r.count), 3) + " % (" +
                       fmt(100.0 * static_cast<double>(r.differ_far) / static_cast<double>(r.count), 3) + " %)",
                   fmt(r.other_cores, 2)});
            auto line = [&](const std::string& who, double ms, const std::string& note) {
                csv.add({r.mesh, std::to_string(r.triangles), r.rays, r.query, std::to_string(r.count), who,
                         std::to_string(threads_), fmt(ms, 3), fmt(mrays(r, ms), 4), note});
            };
            line("kdrt cpu " + opt_.traversal, r.kdrt_ms,
                 std::to_string(r.differ) + " ids unlike Embree, " + std::to_string(r.differ_far) + " beyond ties");
            line("embree rtcIntersect1", r.e1_ms, "build quality " + opt_.embree_quality);
            line("embree rtcIntersect16", r.e16_ms, "build quality " + opt_.embree_quality);
            if (!std::isnan(r.opencl_ms)) line("kdrt " + dev + " depth-1 render", r.opencl_ms, "camera rays + generation + shading");
        }
        TextTable trees;
        trees.header = {"mesh", "triangles", "kd-tree build ms", "nodes", "leaves (empty)", "refs / triangle",
                        "tree bytes / triangle", "SAH cost", "Embree BVH build ms"};
        for (const MeshInfo& m : meshes_)
            trees.add({m.name, std::to_string(m.triangles), fmt_ms(m.build_ms), std::to_string(m.stats.nodes),
                       std::to_string(m.stats.leaves) + " (" + std::to_string(m.stats.empty_leaves) + ")",
                       fmt(m.stats.duplication, 2),
                       fmt(static_cast<double>(m.stats.total_bytes()) / static_cast<double>(std::max<std::size_t>(m.triangles, 1)), 1),
                       fmt(m.stats.sah_cost, 1), fmt_ms(m.embree_commit_ms)});
        std::ostringstream md;
        md << markdown_preamble("kdrt-bench rays") << "Ray throughput, Mrays/s, on " << threads_
           << " threads for every tracer (Embree: the bench's worker pool, " << kChunk
           << "-ray chunks; kdrt: one query call per pass on a oneTBB arena of as many threads); medians of " << opt_.runs
           << " runs after a validating warm-up, the tracers interleaved within each run. Camera rays: "
           << opt_.camera_size << "x" << opt_.camera_size << " pinhole; incoherent: " << opt_.random_rays
           << " rays, origins uniform in the bounds, directions uniform on the sphere (seeded). Any hit: t_max = inf. "
              "kdrt: kdrt::intersect / kdrt::occluded on a CommittedScene of the cpu device, "
           << opt_.traversal << " traversal over build_kd_tree's default tree"
           << (opt_.intersection_cost > 0.0 ? " (but SAH intersection cost " + fmt(opt_.intersection_cost, 2) + ")" : "")
           << ". "
              "Embree: build quality " << opt_.embree_quality
           << ", rtcIntersect1/rtcOccluded1 and rtcIntersect16/rtcOccluded16 (coherent flag for camera packets). "
              "The OpenCL column is a depth-1 render without lights (ray generation, closest hit, trivial shading, "
              "read-back): a lower bound on its camera-ray throughput.\n\n"
           << t.markdown() << "\n## Trees\n\n" << trees.markdown();
        write_report(opt_.out, "rays", "rays", md.str(), csv);
    }

    RaysBenchOptions opt_;
    int threads_;
    Device cpu_ = Device::open("cpu");
    std::vector<std::string> devices_;
    std::vector<MeshInfo> meshes_;
    std::vector<Row> rows_;
    TempDir tmp_{"kdrt-bench-rays"};
};

}  // namespace

int run_rays_bench(const RaysBenchOptions& options) {
    if (options.runs < 1) throw Error(ErrorCode::InvalidArgument, "--runs must be at least 1");
    if (options.meshes.empty()) throw Error(ErrorCode::InvalidArgument, "--meshes: no mesh given");
    machine_info();
    return RaysBench(options).run();
}

}  // namespace kdrt::bench

#else  // no Embree

namespace kdrt::bench {

int run_rays_bench(const RaysBenchOptions&) {
    throw Error(ErrorCode::Unsupported,
                "kdrt-bench was built without Embree 3 (install libembree-dev, e.g. scripts/install-deps.sh --bench, "
                "and reconfigure)");
}

}  // namespace kdrt::bench

#endif
