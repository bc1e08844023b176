#include "rays_bench.h"

#include "machine_info.h"
#include "report.h"

#include <kdrt/error.h>

#ifdef KDRT_BENCH_HAVE_EMBREE

#include "camera_rays.h"
#include "cl_buffer_queries.h"
#include "embree_scene.h"
#include "interference.h"
#include "mesh_generator.h"
#include "parallel.h"
#include "ray_queries.h"
#include "scene_set.h"
#include "stats.h"
#include "table.h"

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/ray_query.h>
#include <kdrt/working_scene.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>

namespace kdrt::bench {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr std::size_t kChunk = 256;  // rays per work item of Embree's passes (a multiple of 16)

// Origins uniform in the box, directions uniform on the sphere (normalised Gaussians).
std::vector<ShadingRay> make_random_rays(const Aabb& box, std::size_t count, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<float> g(0.0f, 1.0f);
    std::vector<ShadingRay> rays;
    rays.reserve(count);
    while (rays.size() < count) {
        const glm::dvec3 o = box.lo + glm::dvec3(u(rng), u(rng), u(rng)) * (box.hi - box.lo);
        const glm::vec3 d(g(rng), g(rng), g(rng));
        const float len = glm::length(d);
        if (!(len > 1e-3f)) continue;
        rays.push_back({glm::vec3(o), d / len, -1});
    }
    return rays;
}

RTCBuildQuality quality_from_string(const std::string& q) {
    if (q == "low") return RTC_BUILD_QUALITY_LOW;
    if (q == "medium") return RTC_BUILD_QUALITY_MEDIUM;
    if (q == "high") return RTC_BUILD_QUALITY_HIGH;
    throw Error(ErrorCode::InvalidArgument, "--embree-quality '" + q + "': expected low, medium or high");
}

// Embree's side: one ray or 16-ray packets, closest or any hit; writes ids
// (object index or -1; any hit: 1 or 0) and t.
class EmbreeTracer {
public:
    explicit EmbreeTracer(const EmbreeScene& scene) : scene_(scene) {}

    void single(const std::vector<ShadingRay>& rays, std::size_t b, std::size_t e, bool any, std::int32_t* ids,
                float* ts) const {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        for (std::size_t i = b; i < e; ++i) {
            RTCRayHit rh;
            fill_ray(rh.ray, rays[i], kInf);
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

    void packets(const std::vector<ShadingRay>& rays, std::size_t b, std::size_t e, bool any, bool coherent,
                 std::int32_t* ids, float* ts) const {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        context.flags = coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
        for (std::size_t p = b; p < e; p += 16) {
            alignas(64) int valid[16];
            alignas(64) RTCRayHit16 rh;
            for (int k = 0; k < 16; ++k) {
                const std::size_t i = p + k;
                valid[k] = i < e ? -1 : 0;
                const ShadingRay& r = rays[i < e ? i : b];
                rh.ray.org_x[k] = r.origin.x;
                rh.ray.org_y[k] = r.origin.y;
                rh.ray.org_z[k] = r.origin.z;
                rh.ray.tnear[k] = 0.0f;
                rh.ray.dir_x[k] = r.direction.x;
                rh.ray.dir_y[k] = r.direction.y;
                rh.ray.dir_z[k] = r.direction.z;
                rh.ray.time[k] = 0.0f;
                rh.ray.tfar[k] = kInf;
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
        return static_cast<std::int32_t>(geom == 0 ? prim : scene_.sphere_count() + prim);  // 0: spheres, 1: triangles
    }

    const EmbreeScene& scene_;
};

// One tracer of the table: a pass over the rays (any: occlusion) writing ids
// and ts, returning its milliseconds. kdrt's tracers report public object
// ids, Embree's object indices: the inputs here add objects in FORMAT.md's
// order, so they are the same.
struct Tracer {
    std::string name;
    bool kdrt = false;
    std::function<double(bool any, std::int32_t* ids, float* ts)> pass;
};

struct Row {
    std::string input, rays, query;
    std::size_t objects = 0, count = 0;
    std::vector<double> ms;                      // per tracer
    std::vector<std::size_t> differ, differ_far;  // per tracer: ids unlike rtcIntersect1's; of them, beyond ties
    double other_cores = 0.0;
};

struct InputInfo {
    std::string name;
    std::size_t objects = 0;
    double build_ms = kNaN, embree_commit_ms = kNaN;
    KdTreeStats stats;
};

class RaysBench {
public:
    explicit RaysBench(const RaysBenchOptions& o) : opt_(o), threads_(worker_count(o.threads)) {}

    int run() {
        std::string dev = "opencl";
        if (!opt_.devices.empty()) {
            dev.clear();
            for (const std::string& d : opt_.devices)
                if (d != "cpu" && dev.empty()) dev = d;
        }
        if (!dev.empty()) {
            bool found = false;
            for (const DeviceInfo& d : list_devices()) found = found || d.id != "cpu";
            if (found || !opt_.devices.empty()) {  // a device asked for by name must exist
                opencl_.emplace(Device::open(dev));
                buffers_.emplace(dev);
                opencl_name_ = dev;
            }
        }
        if (!(opt_.scenes.size() == 1 && opt_.scenes.front() == "none"))
            for (NamedScene& s : load_scenes(opt_.scenes, opt_.scenes_dir)) measure(s.name, s.scene);
        for (const std::string& spec : opt_.meshes) {
            const Scene scene = make_generated_scene(spec);
            measure(scene.name, scene);
        }
        write_outputs();
        return 0;
    }

private:
    void measure(const std::string& name, const Scene& scene) {
        RenderOptions ro;
        ro.frame.width = ro.frame.height = opt_.camera_size;
        ro.frame.samples = 1;
        const WorkingScene ws(scene, ro);
        InputInfo info;
        info.name = name;
        info.objects = ws.sphere_count() + ws.triangle_count();
        std::fprintf(stderr, "%s: %zu objects\n", name.c_str(), info.objects);
        // kdrt traces through the public API. Each device builds its own tree,
        // with its own triangle cost unless --intersection-cost gives one; the
        // build time and tree figures are the cpu device's.
        ro.commit.traversal = traversal_from_string(opt_.traversal);
        if (opt_.intersection_cost > 0.0) ro.commit.tree.intersection_cost = opt_.intersection_cost;
        const CommittedScene on_cpu = CommittedScene::commit(cpu_, scene, ro.commit);
        info.build_ms = on_cpu.stats().build_ms;
        info.stats = kd_tree_stats(*on_cpu.tree(), ro.commit.tree.with_triangle_cost(on_cpu.device().triangle_cost()));
        const EmbreeScene embree(ws, false, quality_from_string(opt_.embree_quality));
        info.embree_commit_ms = embree.commit_ms();
        std::fprintf(stderr, "  kd-tree build %.0f ms (cpu device), Embree BVH build %.0f ms\n", info.build_ms,
                     info.embree_commit_ms);
        inputs_.push_back(info);
        std::optional<CommittedScene> on_cl, on_buffers;
        if (opencl_) {
            on_cl.emplace(CommittedScene::commit(*opencl_, scene, ro.commit));
            // The same device through the caller's buffers: its tree, not a second build.
            RenderOptions same_tree = ro;
            same_tree.commit.tree_files.in_memory = std::make_shared<const KdTree>(*on_cl->tree());
            on_buffers.emplace(CommittedScene::commit(buffers_->device(), scene, same_tree.commit));
        }
        const EmbreeTracer et(embree);
        const std::vector<ShadingRay> camera = make_camera_rays(ws);
        const std::vector<ShadingRay> random = make_random_rays(ws.bounds(), opt_.random_rays, 20261129u);

        for (int set = 0; set < 2; ++set) {
            const std::vector<ShadingRay>& rays = set == 0 ? camera : random;
            const std::vector<QueryRay> query_rays = to_query_rays(rays, ws.frame_origin());
            const bool coherent = set == 0;
            if (buffers_) buffers_->upload(query_rays);
            const std::size_t n = rays.size();
            auto embree_pass = [&](bool packets) {
                return [&et, &rays, n, coherent, packets, this](bool any, std::int32_t* ids, float* ts) {
                    const Stopwatch c;
                    parallel_chunks(n, threads_, kChunk, [&](std::size_t b, std::size_t e, int) {
                        if (packets) et.packets(rays, b, e, any, coherent, ids, ts);
                        else et.single(rays, b, e, any, ids, ts);
                    });
                    return c.ms();
                };
            };
            auto query_pass = [&](const CommittedScene& committed) {
                return [c = &committed, &query_rays, this](bool any, std::int32_t* ids, float* ts) {
                    return any ? time_occluded(*c, query_rays, threads_, ids) : time_intersect(*c, query_rays, threads_, ids, ts);
                };
            };
            std::vector<Tracer> tracers;
            tracers.push_back({"Embree rtcIntersect1", false, embree_pass(false)});  // the reference: first
            tracers.push_back({"Embree rtcIntersect16", false, embree_pass(true)});
            tracers.push_back({"kdrt cpu", true, query_pass(on_cpu)});
            if (on_cl) {
                tracers.push_back({"kdrt " + opencl_name_, true, query_pass(*on_cl)});
                tracers.push_back({"kdrt " + opencl_name_ + " cl_mem", true,
                                    [&](bool any, std::int32_t* ids, float* ts) {
                                        return any ? buffers_->time_occluded(*on_buffers, ids)
                                                   : buffers_->time_intersect(*on_buffers, ids, ts);
                                    }});
            }
            for (int any = 0; any < 2; ++any) {
                Row row;
                row.input = name;
                row.objects = info.objects;
                row.rays = coherent ? "camera" : "incoherent";
                row.query = any ? "any hit" : "closest";
                row.count = n;
                time_tracers(tracers, any != 0, row);
                std::fprintf(stderr, "  %s %s:", row.rays.c_str(), row.query.c_str());
                for (std::size_t k = 0; k < tracers.size(); ++k)
                    std::fprintf(stderr, " %s %.2f", tracers[k].name.c_str(), mrays(row, row.ms[k]));
                std::fprintf(stderr, " Mrays/s\n");
                rows_.push_back(row);
            }
            names_.clear();
            for (const Tracer& t : tracers) names_.push_back({t.name, t.kdrt});
        }
    }

    static double mrays(const Row& r, double ms) { return mrays_per_s(static_cast<double>(r.count), ms); }

    // The first round validates (and warms up); the timed rounds interleave the tracers.
    void time_tracers(const std::vector<Tracer>& tracers, bool any, Row& row) const {
        const std::size_t n = row.count, m = tracers.size();
        std::vector<std::vector<std::int32_t>> ids(m, std::vector<std::int32_t>(n, -1));
        std::vector<std::vector<float>> ts(m, std::vector<float>(n, kInf));
        std::vector<std::vector<double>> ms(m);
        Interference others;
        for (int run = -1; run < opt_.runs; ++run) {
            for (std::size_t k = 0; k < m; ++k) {
                const double t = tracers[k].pass(any, ids[k].data(), ts[k].data());
                if (run >= 0) ms[k].push_back(t);
            }
            if (run == -1) validate(tracers, ids, ts, row);
        }
        row.other_cores = others.other_cores();
        for (const auto& v : ms) row.ms.push_back(median(v));
    }

    // Every tracer's ids against rtcIntersect1's (tracer 0): beyond ties and
    // edges, at most one ray in a thousand may differ.
    static void validate(const std::vector<Tracer>& tracers, const std::vector<std::vector<std::int32_t>>& ids,
                         const std::vector<std::vector<float>>& ts, Row& row) {
        for (std::size_t k = 0; k < ids.size(); ++k) {
            std::size_t differ = 0, far = 0;
            for (std::size_t i = 0; i < ids[k].size(); ++i) {
                if (ids[k][i] == ids[0][i]) continue;
                ++differ;
                // A tie or an edge: both hit at the same distance up to float rounding.
                const float a = ts[k][i], b = ts[0][i];
                const bool tie = ids[k][i] >= 0 && ids[0][i] >= 0 && std::abs(a - b) <= 1e-4f * std::max(1.0f, std::abs(b));
                if (!tie) ++far;
            }
            row.differ.push_back(differ);
            row.differ_far.push_back(far);
            if (far > ids[k].size() / 1000)
                throw std::runtime_error(row.input + " " + row.rays + " " + row.query + ": " + tracers[k].name +
                                         " and Embree disagree on " + std::to_string(far) + " of " +
                                         std::to_string(ids[k].size()) + " rays beyond ties and edges");
        }
    }

    void write_outputs() const {
        TextTable t;
        t.header = {"input", "rays", "query"};
        for (const auto& tr : names_) t.header.push_back(tr.first + " Mrays/s");
        t.header.insert(t.header.end(), {"kdrt cpu / Embree 1 (time)", "ids unlike Embree 1, % (beyond ties)", "others' cores"});
        TextTable csv;
        csv.header = {"input", "objects", "rays", "query", "count", "tracer", "threads", "ms", "mrays_per_s", "note"};
        for (const Row& r : rows_) {
            std::vector<std::string> cells{r.input, r.rays, r.query};
            std::string differ;
            for (std::size_t k = 0; k < r.ms.size(); ++k) {
                cells.push_back(fmt(mrays(r, r.ms[k]), 2));
                if (k == 0 || !names_[k].second) continue;
                differ += (differ.empty() ? "" : "; ") + names_[k].first.substr(5) + " " +
                          fmt(100.0 * static_cast<double>(r.differ[k]) / static_cast<double>(r.count), 3) + " (" +
                          fmt(100.0 * static_cast<double>(r.differ_far[k]) / static_cast<double>(r.count), 3) + ")";
                csv.add({r.input, std::to_string(r.objects), r.rays, r.query, std::to_string(r.count),
                         names_[k].first + " " + opt_.traversal, std::to_string(threads_), fmt(r.ms[k], 3),
                         fmt(mrays(r, r.ms[k]), 4),
                         std::to_string(r.differ[k]) + " ids unlike Embree, " + std::to_string(r.differ_far[k]) + " beyond ties"});
            }
            for (std::size_t k = 0; k < 2; ++k)
                csv.add({r.input, std::to_string(r.objects), r.rays, r.query, std::to_string(r.count), names_[k].first,
                         std::to_string(threads_), fmt(r.ms[k], 3), fmt(mrays(r, r.ms[k]), 4),
                         "build quality " + opt_.embree_quality});
            cells.insert(cells.end(), {fmt_ratio(r.ms[2] / r.ms[0]), differ, fmt(r.other_cores, 2)});
            t.add(cells);
        }
        TextTable trees;
        trees.header = {"input", "objects", "kd-tree build ms", "nodes", "leaves (empty)", "refs / object",
                        "tree bytes / object", "SAH cost", "Embree BVH build ms"};
        for (const InputInfo& m : inputs_)
            trees.add({m.name, std::to_string(m.objects), fmt_ms(m.build_ms), std::to_string(m.stats.nodes),
                       std::to_string(m.stats.leaves) + " (" + std::to_string(m.stats.empty_leaves) + ")",
                       fmt(m.stats.duplication, 2),
                       fmt(static_cast<double>(m.stats.total_bytes()) / static_cast<double>(std::max<std::size_t>(m.objects, 1)), 1),
                       fmt(m.stats.sah_cost, 1), fmt_ms(m.embree_commit_ms)});
        std::ostringstream md;
        md << markdown_preamble("kdrt-bench rays") << "Ray throughput, Mrays/s; the cpu tracers on " << threads_
           << " threads (Embree: the bench's worker pool, " << kChunk
           << "-ray chunks; kdrt cpu: one query call per pass on a oneTBB arena of as many threads); medians of "
           << opt_.runs << " runs after a validating warm-up, the tracers interleaved within each run. Camera rays: "
           << opt_.camera_size << "x" << opt_.camera_size << ", the scene's pinhole camera; incoherent: " << opt_.random_rays
           << " rays, origins uniform in the bounds, directions uniform on the sphere (seeded). Any hit: t_max = inf. "
              "kdrt: kdrt::intersect / kdrt::occluded on a CommittedScene, "
           << opt_.traversal << " traversal over build_kd_tree's default tree"
           << (opt_.intersection_cost > 0.0 ? " (but SAH intersection cost " + fmt(opt_.intersection_cost, 2) + ")" : "")
           << ", the same tree on every device. "
           << (opencl_ ? "kdrt " + opencl_name_ + ": the same queries on the OpenCL device (host spans: the rays' upload and "
                         "the hits' read-back are in the time); cl_mem: kdrt/opencl_interop.h on buffers of the bench's own "
                         "context, rays uploaded once, the hits left on the device (the time of the queries alone). "
                       : std::string("No OpenCL device. "))
           << "Embree: build quality " << opt_.embree_quality
           << ", rtcIntersect1/rtcOccluded1 and rtcIntersect16/rtcOccluded16 (coherent flag for camera packets).\n\n"
           << t.markdown() << "\n## Trees\n\n" << trees.markdown();
        write_report(opt_.out, "rays", "rays", md.str(), csv);
    }

    RaysBenchOptions opt_;
    int threads_;
    Device cpu_ = Device::open("cpu");
    std::optional<Device> opencl_;
    std::optional<ClBufferQueries> buffers_;
    std::string opencl_name_;
    std::vector<std::pair<std::string, bool>> names_;  // the tracers' names, and which are kdrt's: the same for every input
    std::vector<InputInfo> inputs_;
    std::vector<Row> rows_;
};

}  // namespace

int run_rays_bench(const RaysBenchOptions& options) {
    if (options.runs < 1) throw Error(ErrorCode::InvalidArgument, "--runs must be at least 1");
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
