#include "embree_compare.h"

#include "machine_info.h"
#include "report.h"

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/error.h>

#ifdef KDRT_BENCH_HAVE_EMBREE

#include "camera_rays.h"
#include "embree_renderer.h"
#include "id_check.h"
#include "interference.h"
#include "parallel.h"
#include "ray_queries.h"
#include "scene_set.h"
#include "stats.h"
#include "table.h"
#include "whitted_renderer.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace kdrt::bench {

namespace {

struct RawFigure {
    std::string what;  // "kdrt stack", "Embree rtcIntersect1", ...
    int threads = 1;
    double ms = kNaN, mrays = kNaN;
    std::size_t differ = 0;  // camera hits that differ from kdrt's stack traversal
};

struct SceneResult {
    std::string name;
    std::vector<double> kdrt_ms, kdrt_mrays;  // per device
    double kdrt_build_ms = kNaN;
    double embree_ms = kNaN, embree_mrays = kNaN, embree_commit_ms = kNaN;
    double rmse = kNaN, max_error = kNaN, harness_rmse = kNaN, harness_max = kNaN;
    double other_cores = 0.0, other_cores_rays = 0.0;  // other processes' CPU use during the timed parts
    IdCheck ids;  // Embree's camera ids against the kdrt cpu device's
    std::size_t camera_rays = 0;
    std::vector<RawFigure> raw;
    std::vector<double> opencl_camera_ms;  // per device (NaN for cpu)
};

class EmbreeCompare {
public:
    explicit EmbreeCompare(const EmbreeCompareOptions& o) : opt_(o) {}

    int run() {
        devices_ = opt_.devices.empty() ? all_device_ids() : opt_.devices;
        if (devices_.empty() || devices_.front() != "cpu") devices_.insert(devices_.begin(), "cpu");
        for (NamedScene& s : load_scenes(opt_.scenes, opt_.scenes_dir)) results_.push_back(measure(s));
        write_outputs();
        return 0;
    }

private:
    RenderOptions base_options() const {
        RenderOptions o;
        o.frame.width = opt_.width;
        o.frame.height = opt_.height;
        o.frame.max_depth = opt_.max_depth;
        o.frame.samples = 1;
        o.frame.threads = opt_.threads;
        o.commit.traversal = traversal_from_string(opt_.traversal);
        o.commit.tree.builder = kd_builder_from_string(opt_.tree);
        o.commit.tree.max_depth = o.commit.tree.builder == KdBuilderKind::Median ? 10 : 0;
        return o;
    }

    SceneResult measure(const NamedScene& ns) {
        SceneResult res;
        res.name = ns.name;
        const RenderOptions base = base_options();
        std::fprintf(stderr, "%s:\n", ns.name.c_str());

        // Warm-ups: kdrt on every device, then Embree, whose image and ids are checked against kdrt's cpu device.
        RenderResult kdrt_cpu;
        for (const std::string& d : devices_) {
            RenderOptions o = base;
            o.device = d;
            o.frame.want_ids = d == "cpu";
            RenderResult r = render(ns.scene, o);
            if (d == "cpu") kdrt_cpu = std::move(r);
        }
        res.kdrt_build_ms = kdrt_cpu.stats.build_ms;
        const EmbreeRenderer embree(ns.scene, base);
        res.embree_commit_ms = embree.commit_ms();
        const RenderResult ew = embree.render(opt_.threads, true);
        res.rmse = image_rmse(kdrt_cpu.image, ew.image);
        res.max_error = image_max_error(kdrt_cpu.image, ew.image);
        res.ids = compare_ids({kdrt_cpu.image.width, kdrt_cpu.image.height, kdrt_cpu.ids, kdrt_cpu.hit_t},
                              {ew.image.width, ew.image.height, ew.ids, ew.hit_t});

        // The harness: the same shader over kdrt's own traversal must give the cpu device's image.
        const WorkingScene& prepared = embree.prepared();
        KdTree tree = build_kd_tree(prepared.build_input(), base.commit.tree);
        build_ropes(tree);
        {
            const RenderResult h =
                render_whitted(prepared, *prepared.kd_intersector(tree, base.commit.traversal), opt_.threads, false, "harness");
            res.harness_rmse = image_rmse(kdrt_cpu.image, h.image);
            res.harness_max = image_max_error(kdrt_cpu.image, h.image);
        }

        // Whole renders, interleaved so that a change in the machine's load hits both sides.
        std::vector<std::vector<double>> kms(devices_.size());
        std::vector<double> ems;
        std::vector<double> krays(devices_.size(), 0.0);
        double erays = 0.0;
        Interference others;
        for (int run = 0; run < opt_.runs; ++run) {
            for (std::size_t d = 0; d < devices_.size(); ++d) {
                RenderOptions o = base;
                o.device = devices_[d];
                const RenderResult r = render(ns.scene, o);
                kms[d].push_back(r.stats.render_ms);
                krays[d] = static_cast<double>(r.stats.rays.total());
            }
            const RenderResult r = embree.render(opt_.threads, false);
            ems.push_back(r.stats.render_ms);
            erays = static_cast<double>(r.stats.rays.total());
        }
        res.other_cores = others.other_cores();
        for (std::size_t d = 0; d < devices_.size(); ++d) {
            res.kdrt_ms.push_back(median(kms[d]));
            res.kdrt_mrays.push_back(mrays_per_s(krays[d], res.kdrt_ms.back()));
        }
        res.embree_ms = median(ems);
        res.embree_mrays = mrays_per_s(erays, res.embree_ms);

        // Camera rays only: closest hit, nothing shaded.
        const std::vector<ShadingRay> rays = make_camera_rays(prepared);
        res.camera_rays = rays.size();
        const EmbreeScene raw(prepared, false);
        const int all = worker_count(opt_.threads);
        std::vector<int> thread_counts{1};
        if (all > 1) thread_counts.push_back(all);
        // The four tracers take turns within each run, so that a change in the machine's load hits all of them.
        // kdrt through its public ray queries, one committed scene per traversal over the same tree.
        const Traversal traversals[3] = {Traversal::Stack, Traversal::Ropes, Traversal::Restart};
        const auto shared_tree = std::make_shared<const KdTree>(std::move(tree));
        const Device cpu = Device::open("cpu");
        std::vector<CommittedScene> committed;
        for (Traversal traversal : traversals) {
            RenderOptions o = base;
            o.commit.traversal = traversal;
            o.commit.tree_files.in_memory = shared_tree;
            committed.push_back(CommittedScene::commit(cpu, ns.scene, o.commit));
        }
        const std::vector<QueryRay> query_rays = to_query_rays(rays, prepared.frame_origin());
        std::vector<float> ts(rays.size());
        others.restart();
        for (int threads : thread_counts) {
            std::vector<double> ms[4];
            std::vector<std::int32_t> ids[4];
            for (int run = -1; run < opt_.runs; ++run) {
                for (int k = 0; k < 3; ++k) {
                    ids[k].resize(rays.size());
                    const double t = time_intersect(committed[static_cast<std::size_t>(k)], query_rays, threads,
                                                    ids[k].data(), ts.data());
                    if (run >= 0) ms[k].push_back(t);
                }
                const double t = trace_camera_rays(rays, threads, ids[3], [&](const ShadingRay& ray, float& tt) {
                    return raw.intersect_id(ray, tt);
                });
                if (run >= 0) ms[3].push_back(t);
            }
            for (int k = 0; k < 4; ++k) {
                const double m = median(ms[k]);
                const std::string what = k < 3 ? std::string("kdrt ") + to_string(traversals[k]) + " (" + opt_.tree + ")"
                                               : std::string("Embree rtcIntersect1");
                res.raw.push_back({what, threads, m, mrays_per_s(static_cast<double>(rays.size()), m),
                                   count_differences(ids[0], ids[k])});
            }
        }

        res.other_cores_rays = others.other_cores();

        // The OpenCL devices: the same queries over the same tree (host spans: the rays' upload and the hits'
        // read-back are in the time).
        for (const std::string& d : devices_) {
            if (d == "cpu") {
                res.opencl_camera_ms.push_back(kNaN);
                continue;
            }
            RenderOptions o = base;
            o.commit.tree_files.in_memory = shared_tree;
            const CommittedScene on_device = CommittedScene::commit(Device::open(d), ns.scene, o.commit);
            std::vector<std::int32_t> device_ids(rays.size());
            std::vector<double> ms;
            for (int run = -1; run < opt_.runs; ++run) {
                const double t = time_intersect(on_device, query_rays, all, device_ids.data(), ts.data());
                if (run >= 0) ms.push_back(t);
            }
            res.opencl_camera_ms.push_back(median(ms));
        }

        for (std::size_t d = 0; d < devices_.size(); ++d)
            std::fprintf(stderr, "  whole render: kdrt %s %s ms, Embree %s ms: %s\n", devices_[d].c_str(),
                         fmt_ms(res.kdrt_ms[d]).c_str(), fmt_ms(res.embree_ms).c_str(),
                         fmt_ratio(res.kdrt_ms[d] / res.embree_ms).c_str());
        std::fprintf(stderr, "  Embree image RMSE %s (max %s), ids %s; harness RMSE %s\n", fmt(res.rmse, 5).c_str(),
                     fmt(res.max_error, 3).c_str(), res.ids.summary().c_str(), fmt(res.harness_rmse, 6).c_str());
        for (const RawFigure& f : res.raw)
            std::fprintf(stderr, "  camera rays: %s, %d thread(s): %s ms, %s Mrays/s, %zu ids differ from kdrt stack\n",
                         f.what.c_str(), f.threads, fmt_ms(f.ms).c_str(), fmt(f.mrays, 2).c_str(), f.differ);
        return res;
    }

    const RawFigure* raw(const SceneResult& r, const std::string& what_prefix, int threads) const {
        for (const RawFigure& f : r.raw)
            if (f.threads == threads && f.what.rfind(what_prefix, 0) == 0) return &f;
        return nullptr;
    }

    void write_outputs() const {
        const int all = worker_count(opt_.threads);
        TextTable whole;
        whole.header = {"scene", "Embree ms", "Embree Mrays/s"};
        for (const std::string& d : devices_) {
            whole.header.push_back("kdrt " + d + " ms");
            whole.header.push_back(d + " / Embree");
        }
        whole.header.insert(whole.header.end(), {"kdrt tree build ms", "Embree BVH build ms", "image RMSE (max)",
                                                 "Embree ids vs kdrt", "harness RMSE", "others' cores"});
        for (const SceneResult& r : results_) {
            std::vector<std::string> row{r.name, fmt_ms(r.embree_ms), fmt(r.embree_mrays, 2)};
            for (std::size_t d = 0; d < devices_.size(); ++d) {
                row.push_back(fmt_ms(r.kdrt_ms[d]));
                row.push_back(fmt_ratio(r.kdrt_ms[d] / r.embree_ms));
            }
            row.insert(row.end(), {fmt_ms(r.kdrt_build_ms), fmt_ms(r.embree_commit_ms),
                                   fmt(r.rmse, 5) + " (" + fmt(r.max_error, 3) + ")", r.ids.summary(),
                                   fmt(r.harness_rmse, 6), fmt(r.other_cores, 2)});
            whole.add(row);
        }

        TextTable cam;
        cam.header = {"scene", "rays"};
        std::vector<int> counts{1};
        if (all > 1) counts.push_back(all);
        for (int t : counts) {
            std::string th(1, ' ');
            th.append(std::to_string(t)).append("T");
            cam.header.insert(cam.header.end(), {"kdrt stack" + th, "kdrt ropes" + th, "kdrt restart" + th,
                                                 "Embree" + th, "kdrt stack / Embree" + th});
        }
        for (const std::string& d : devices_)
            if (d != "cpu") cam.header.push_back("kdrt " + d);
        cam.header.push_back("Embree ids differing");
        cam.header.push_back("others' cores");
        for (const SceneResult& r : results_) {
            std::vector<std::string> row{r.name, std::to_string(r.camera_rays)};
            for (int t : counts) {
                const RawFigure* st = raw(r, "kdrt stack", t);
                const RawFigure* ro = raw(r, "kdrt ropes", t);
                const RawFigure* re = raw(r, "kdrt restart", t);
                const RawFigure* em = raw(r, "Embree", t);
                row.insert(row.end(), {fmt(st->mrays, 2), fmt(ro->mrays, 2), fmt(re->mrays, 2), fmt(em->mrays, 2),
                                       fmt_ratio(st->ms / em->ms)});
            }
            for (std::size_t d = 0; d < devices_.size(); ++d)
                if (devices_[d] != "cpu")
                    row.push_back(fmt(mrays_per_s(static_cast<double>(r.camera_rays), r.opencl_camera_ms[d]), 2));
            const RawFigure* em = raw(r, "Embree", counts.back());
            row.push_back(std::to_string(em->differ));
            row.push_back(fmt(r.other_cores_rays, 2));
            cam.add(row);
        }

        std::ostringstream md;
        md << markdown_preamble("kdrt-bench embree") << opt_.width << "x" << opt_.height << ", ray depth "
           << opt_.max_depth << "; kdrt with the " << opt_.traversal << " traversal over the " << opt_.tree
           << " tree; the cpu device and Embree on " << all << " threads; medians of " << opt_.runs
           << " runs after a warm-up, kdrt and Embree interleaved in the same run. \"others' cores\": the CPU "
              "other processes used meanwhile (from /proc/stat), in cores of "
           << machine_info().logical_cpus << ".\n\n"
           << "## Whole render (tracing and shading; tree and BVH builds apart)\n\n"
           << "A ratio above 1 means kdrt is slower. The Embree renderer is bench/whitted_renderer.h (FORMAT.md's "
              "Whitted shading) over rtcIntersect1 / rtcOccluded1, with kdrt's self-intersection rule (relative "
              "offset, the object left ignored through a context filter). The harness RMSE is the same shader over "
              "kdrt's own C++ traversal against the cpu device: 0 means the harness adds nothing of its own.\n\n"
           << whole.markdown() << "\n"
           << "## Camera rays only: closest-hit throughput, Mrays/s\n\n"
           << "The same camera rays, generated once; kdrt's public ray queries (kdrt::intersect on a CommittedScene of the cpu device, one call per pass on a oneTBB arena of that many threads) against "
              "rtcIntersect1 (no filter), 1 thread and "
           << all
           << ". The OpenCL columns are the same kdrt::intersect on that device over the same tree, on host spans "
              "(the rays' upload and the hits' read-back included).\n\n"
           << cam.markdown();
        TextTable csv;
        csv.header = {"scene", "measure", "config", "threads", "ms", "mrays_per_s", "note"};
        for (const SceneResult& r : results_) {
            for (std::size_t d = 0; d < devices_.size(); ++d)
                csv.add({r.name, "whole_render", "kdrt " + devices_[d] + " " + opt_.traversal + " " + opt_.tree,
                         devices_[d] == "cpu" ? std::to_string(all) : "", fmt(r.kdrt_ms[d], 3), fmt(r.kdrt_mrays[d], 4),
                         "ratio to Embree " + fmt(r.kdrt_ms[d] / r.embree_ms, 4)});
            csv.add({r.name, "whole_render", "embree", std::to_string(all), fmt(r.embree_ms, 3), fmt(r.embree_mrays, 4),
                     "rmse " + fmt(r.rmse, 6) + " max " + fmt(r.max_error, 4) + " harness rmse " + fmt(r.harness_rmse, 6)});
            csv.add({r.name, "build", "kdrt " + opt_.tree, "1", fmt(r.kdrt_build_ms, 3), "", ""});
            csv.add({r.name, "build", "embree", std::to_string(all), fmt(r.embree_commit_ms, 3), "", ""});
            for (const RawFigure& f : r.raw)
                csv.add({r.name, "camera_rays", f.what, std::to_string(f.threads), fmt(f.ms, 3), fmt(f.mrays, 4),
                         std::to_string(f.differ) + " ids differ from kdrt stack"});
            for (std::size_t d = 0; d < devices_.size(); ++d)
                if (devices_[d] != "cpu")
                    csv.add({r.name, "camera_rays", "kdrt " + devices_[d] + " " + opt_.traversal + " (" + opt_.tree + ")", "",
                             fmt(r.opencl_camera_ms[d], 3),
                             fmt(mrays_per_s(static_cast<double>(r.camera_rays), r.opencl_camera_ms[d]), 4), ""});
        }
        write_report(opt_.out, "embree", "embree", md.str(), csv);
    }

    EmbreeCompareOptions opt_;
    std::vector<std::string> devices_;
    std::vector<SceneResult> results_;
};

}  // namespace

int run_embree_compare(const EmbreeCompareOptions& options) {
    if (options.runs < 1) throw Error(ErrorCode::InvalidArgument, "--runs must be at least 1");
    machine_info();
    return EmbreeCompare(options).run();
}

}  // namespace kdrt::bench

#else  // no Embree

namespace kdrt::bench {

int run_embree_compare(const EmbreeCompareOptions&) {
    throw Error(ErrorCode::Unsupported,
                "kdrt-bench was built without Embree 3 (install libembree-dev, e.g. scripts/install-deps.sh --bench, "
                "and reconfigure)");
}

}  // namespace kdrt::bench

#endif
