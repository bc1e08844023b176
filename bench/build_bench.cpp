#include "build_bench.h"

#include "camera_rays.h"
#include "machine_info.h"
#include "mesh_generator.h"
#include "parallel.h"
#include "ray_queries.h"
#include "report.h"
#include "scene_set.h"
#include "stats.h"
#include "study_reference.h"
#include "timed_render.h"

#include "render/working_scene_access.h"

#ifdef KDRT_BENCH_HAVE_EMBREE
#include "embree_scene.h"
#endif

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/kd_tree.h>
#include <kdrt/render.h>
#include <kdrt/working_scene.h>

#include <sys/resource.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

namespace kdrt::bench {

namespace {

struct Input {
    std::string name;
    Scene scene;
    bool generated = false;
};

struct BuilderRow {
    std::string input, builder;
    int build_threads = 1;
    std::size_t objects = 0;
    double build_ms = kNaN, ropes_ms = kNaN, render_ms = kNaN;
    std::string render_what;
    KdTreeStats stats;
    int max_depth = 0;
    double peak_rss_mib = kNaN, base_rss_mib = kNaN;
    detail::TraversalCosts probe;
    std::string note;

    double ns_per_nlogn() const {
        const double n = static_cast<double>(std::max<std::size_t>(objects, 2));
        return build_ms * 1e6 / (n * std::log2(n));
    }
    double per_object(std::size_t bytes) const { return objects ? static_cast<double>(bytes) / objects : kNaN; }
};

struct EmbreeRow {
    std::string input;
    double medium_ms = kNaN, high_ms = kNaN;
    std::string note;
};

// One field of /proc/self/status, in MiB.
double status_mib(const std::string& field) {
    std::ifstream in("/proc/self/status");
    std::string key;
    while (in >> key) {
        if (key == field + ":") {
            double kib = 0.0;
            in >> kib;
            return kib / 1024.0;
        }
        in.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
    }
    return kNaN;
}

// Resets the process's RSS high-water mark (VmHWM) to its current RSS, so that
// each build's peak is measured on its own; false where the kernel refuses.
bool reset_peak_rss() {
    std::ofstream out("/proc/self/clear_refs");
    out << "5";
    out.flush();
    return static_cast<bool>(out);
}

double peak_rss_mib() {
    const double hwm = status_mib("VmHWM");
    if (hwm == hwm) return hwm;
    rusage ru{};
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_maxrss / 1024.0;
}

// The builds measured on each input: the study's median tree, the exact SAH
// sweep (serial), and the binned SAH builder on 1 and 2 threads.
struct BuilderRun {
    KdBuilderKind kind;
    int threads;
    const char* label;
};
constexpr BuilderRun kBuilderRuns[] = {{KdBuilderKind::Median, 1, "median-10"},
                                       {KdBuilderKind::SahExact, 1, "sah-exact"},
                                       {KdBuilderKind::Sah, 1, "sah (binned)"},
                                       {KdBuilderKind::Sah, 2, "sah (binned)"}};

double available_gib() {
    std::ifstream in("/proc/meminfo");
    std::string key;
    double kib = 0.0;
    std::string unit;
    while (in >> key >> kib >> unit)
        if (key == "MemAvailable:") return kib / (1024.0 * 1024.0);
    return 0.0;
}

class BuildBench {
public:
    explicit BuildBench(const BuildBenchOptions& o) : opt_(o) {}

    int run() {
        std::vector<Input> inputs;
        for (NamedScene& s : load_scenes(opt_.scenes, opt_.scenes_dir)) inputs.push_back({s.name, std::move(s.scene), false});
        for (const std::string& m : opt_.meshes) {
            const std::size_t n = parse_count(m);
            // 1 KiB per triangle covers the scene copies, the SAH builder's events and the tree with room to
            // spare (the measured peak for 4M triangles was 2.5 GiB); leave the rest of the machine its memory.
            const double need_gib = static_cast<double>(n) / (1024.0 * 1024.0);
            if (need_gib > 0.6 * available_gib()) {
                skipped_.push_back(m + " triangles: needs about " + fmt(need_gib, 1) + " GiB, " +
                                   fmt(available_gib(), 1) + " GiB available");
                std::fprintf(stderr, "kdrt-bench build: skipping %s\n", skipped_.back().c_str());
                continue;
            }
            Scene s = make_torus_scene(n);
            inputs.push_back({s.name, std::move(s), true});
        }
        for (Input& in : inputs) {
            measure(in);
            in.scene = Scene();  // free the big meshes as we go
        }
        write_outputs();
        return 0;
    }

private:
    void measure(const Input& in) {
        RenderOptions po;
        po.frame.width = po.frame.height = opt_.render_size;
        const WorkingScene prepared(in.scene, po);
        const KdBuildInput input = prepared.build_input();
        const int runs = in.scene.object_count() >= 2'000'000 ? 1 : opt_.runs;
        std::optional<std::vector<ShadingRay>> rays;
        for (const BuilderRun& run : kBuilderRuns) {
            const KdBuilderKind kind = run.kind;
            BuilderRow row;
            row.input = in.name;
            row.objects = in.scene.object_count();
            row.build_threads = run.threads;
            row.builder = run.label;
            if (kind == KdBuilderKind::SahExact && row.objects > 2'000'000) {
                std::fprintf(stderr, "  %s sah-exact: skipped (over 2M objects: minutes and GiBs)\n", in.name.c_str());
                continue;
            }
            // The tree the cpu device builds for its renders and queries: its own triangle cost.
            KdBuildConfig config = KdBuildConfig{}.with_triangle_cost(cpu_triangle_cost_);
            config.builder = kind;
            config.threads = run.threads;
            config.max_depth = kind == KdBuilderKind::Median ? kStudyMedianDepth : 0;
            std::vector<double> build, ropes;
            std::optional<KdTree> tree;
            const int first = runs > 1 ? -1 : 0;  // a warm-up build, except for the biggest inputs
            for (int r = first; r < runs; ++r) {
                tree.reset();
                const bool reset = reset_peak_rss();
                const double base = status_mib("VmRSS");
                Stopwatch clock;
                KdTree t = build_kd_tree(input, config);
                const double build_ms = clock.ms();
                if (r == (runs > 1 ? 0 : first)) {  // the peak of one build, its tree included
                    row.peak_rss_mib = reset ? peak_rss_mib() : kNaN;
                    row.base_rss_mib = base;
                }
                clock.restart();
                build_ropes(t);
                if (r >= 0) {
                    build.push_back(build_ms);
                    ropes.push_back(clock.ms());
                }
                tree = std::move(t);
            }
            row.build_ms = median(build);
            row.ropes_ms = median(ropes);
            row.stats = kd_tree_stats(*tree, config);
            row.max_depth = tree->max_depth;
            const bool same_tree_as_next = kind == KdBuilderKind::Sah && run.threads == 1;  // any thread count: one tree
            if (!same_tree_as_next) {
                row.probe = detail::traversal_costs(prepared, *tree, opt_.runs);
            }
            if (same_tree_as_next) {
                row.render_what = "(same tree as 2 threads)";
            } else if (!in.generated) {
                RenderOptions o;
                o.device = "cpu";
                o.frame.width = o.frame.height = opt_.render_size;
                o.frame.threads = opt_.threads;
                o.commit.traversal = Traversal::Stack;
                o.commit.tree = config;
                row.render_ms = median_render_ms(in.scene, o, opt_.runs);
                row.render_what = "render (cpu, stack)";
            } else {
                if (!rays) rays = make_camera_rays(prepared);
                RenderOptions o;
                o.commit.traversal = Traversal::Stack;
                o.commit.tree = config;
                o.commit.tree_files.in_memory = std::make_shared<const KdTree>(std::move(*tree));
                const CommittedScene committed = CommittedScene::commit(Device::open("cpu"), in.scene, o.commit);
                const std::vector<QueryRay> query_rays = to_query_rays(*rays, prepared.frame_origin());
                std::vector<std::int32_t> ids(query_rays.size());
                std::vector<float> ts(query_rays.size());
                std::vector<double> ms;
                for (int r = -1; r < opt_.runs; ++r) {
                    const double t = time_intersect(committed, query_rays, worker_count(opt_.threads), ids.data(), ts.data());
                    if (r >= 0) ms.push_back(t);
                }
                row.render_ms = median(ms);
                row.render_what = "camera rays only (kdrt::intersect, stack)";
            }
            std::fprintf(stderr,
                         "  %s %s x%d: %zu objects, build %s ms + ropes %s ms (%s ns per N log2 N), SAH cost %s, %zu nodes, "
                         "depth %d, %s B/obj (no ropes), %s %s ms, build peak RSS %s MiB (from %s); probe: %s ns/step, "
                         "%s ns/test, %s steps and %s tests per ray\n",
                         row.input.c_str(), row.builder.c_str(), row.build_threads, row.objects, fmt_ms(row.build_ms).c_str(),
                         fmt_ms(row.ropes_ms).c_str(), fmt(row.ns_per_nlogn(), 2).c_str(), fmt(row.stats.sah_cost, 2).c_str(),
                         row.stats.nodes, row.stats.max_leaf_depth,
                         fmt(row.per_object(row.stats.total_bytes() - row.stats.rope_bytes), 1).c_str(),
                         row.render_what.c_str(), fmt_ms(row.render_ms).c_str(), fmt(row.peak_rss_mib, 0).c_str(),
                         fmt(row.base_rss_mib, 0).c_str(), fmt(row.probe.ns_per_step, 2).c_str(),
                         fmt(row.probe.ns_per_test, 2).c_str(), fmt(row.probe.steps_per_ray, 1).c_str(),
                         fmt(row.probe.tests_per_ray, 1).c_str());
            rows_.push_back(row);
        }
        embree(in, prepared, runs);
    }

    void embree([[maybe_unused]] const Input& in, [[maybe_unused]] const WorkingScene& prepared,
                [[maybe_unused]] int runs) {
#ifdef KDRT_BENCH_HAVE_EMBREE
        EmbreeRow e;
        e.input = in.name;
        try {
            for (RTCBuildQuality q : {RTC_BUILD_QUALITY_MEDIUM, RTC_BUILD_QUALITY_HIGH}) {
                std::vector<double> ms;
                // A warm-up build (the first one also starts TBB's thread pool), except for the biggest inputs.
                for (int r = runs > 1 ? -1 : 0; r < runs; ++r) {
                    const double commit = EmbreeScene(prepared, false, q).commit_ms();
                    if (r >= 0) ms.push_back(commit);
                }
                (q == RTC_BUILD_QUALITY_MEDIUM ? e.medium_ms : e.high_ms) = median(ms);
            }
        } catch (const std::exception& ex) {
            e.note = ex.what();
        }
        std::fprintf(stderr, "  %s Embree BVH: %s ms (medium quality), %s ms (high)\n", in.name.c_str(),
                     fmt_ms(e.medium_ms).c_str(), fmt_ms(e.high_ms).c_str());
        embree_.push_back(e);
#endif
    }

    void write_outputs() const {
        TextTable t;
        t.header = {"input", "objects", "builder", "threads", "build ms", "ropes ms", "ns per N log2 N", "SAH cost", "nodes",
                    "leaves (empty)", "max depth", "objects per leaf", "duplication", "B/obj nodes", "B/obj leaves+lists",
                    "B/obj ropes", "render at " + std::to_string(opt_.render_size) + "² ms", "RSS before build MiB",
                    "build peak RSS MiB", "probe ns/step", "probe ns/test", "steps/ray", "tests/ray"};
        for (const BuilderRow& r : rows_) {
            t.add({r.input, std::to_string(r.objects), r.builder, std::to_string(r.build_threads), fmt_ms(r.build_ms),
                   fmt_ms(r.ropes_ms),
                   fmt(r.ns_per_nlogn(), 2), fmt(r.stats.sah_cost, 2), std::to_string(r.stats.nodes),
                   std::to_string(r.stats.leaves) + " (" + std::to_string(r.stats.empty_leaves) + ")",
                   std::to_string(r.stats.max_leaf_depth), fmt(r.stats.mean_objects_per_leaf, 1),
                   fmt(r.stats.duplication, 2), fmt(r.per_object(r.stats.node_bytes), 1),
                   fmt(r.per_object(r.stats.leaf_object_bytes), 1),
                   fmt(r.per_object(r.stats.rope_bytes), 1), fmt_ms(r.render_ms), fmt(r.base_rss_mib, 0),
                   fmt(r.peak_rss_mib, 0), fmt(r.probe.ns_per_step, 2), fmt(r.probe.ns_per_test, 2),
                   fmt(r.probe.steps_per_ray, 1), fmt(r.probe.tests_per_ray, 1)});
        }
        TextTable et;
        et.header = {"input", "Embree BVH build ms (medium)", "Embree BVH build ms (high)",
                     "kdrt binned SAH build ms, 1 thread", "2 threads", "2 threads / Embree high",
                     "2 threads / Embree medium", "speed-up 1 -> 2 threads"};
        for (const EmbreeRow& e : embree_) {
            double one = kNaN, two = kNaN;
            for (const BuilderRow& r : rows_)
                if (r.input == e.input && r.builder == "sah (binned)") (r.build_threads == 1 ? one : two) = r.build_ms;
            et.add({e.input, fmt_ms(e.medium_ms), fmt_ms(e.high_ms), fmt_ms(one), fmt_ms(two), fmt_ratio(two / e.high_ms),
                    fmt_ratio(two / e.medium_ms), fmt_ratio(one / two)});
        }
        std::ostringstream md;
        md << markdown_preamble("kdrt-bench build") << "Build times are the median of " << opt_.runs
           << " build(s) (one for inputs of 2M objects and more). median-10 and sah-exact are serial; the binned SAH "
              "builder (the default `sah`) runs on oneTBB with the threads given, and builds the same tree for any "
              "count. Ropes are built after the tree and timed apart. Every builder uses the SAH constants the cpu "
              "device builds with (its triangle cost: "
           << fmt(cpu_triangle_cost_, 2) << "), which also give the SAH cost column. Bytes per object: nodes (8 B each), leaf records and leaf lists, ropes (48 B per "
              "leaf). RSS before build: the process (scene, prepared geometry, build input) when the build starts; "
              "build peak RSS: the high-water mark during one build (VmHWM, reset before it through "
              "/proc/self/clear_refs), tree included. The probe columns (detail::traversal_costs, libkdrt/src/cpu/traversal_costs.cpp) time the stack traversal "
              "over the camera rays without stopping at hits: ns per loop step with the leaves skipped, and the "
              "extra ns per object test when every listed object is tested; the SAH cost constants come from "
              "these. The render column is the cpu device with "
              "the stack traversal for the scenes (median of "
           << opt_.runs
           << " after a warm-up; tracing and shading, tree build excluded) and camera rays only (closest hit, no "
              "shading) for the generated tori. Peak RSS is the process's high-water mark so far.\n\n";
        md << t.markdown() << "\n";
        if (!embree_.empty())
            md << "## Embree's BVH build beside it\n\nrtcCommitScene over the same float geometry, on Embree's TBB "
                  "pool (every logical CPU: "
               << machine_info().logical_cpus << "); kdrt's binned SAH builder on 1 and 2 threads.\n\n"
               << et.markdown() << "\n";
        if (!skipped_.empty()) {
            md << "Skipped:\n\n";
            for (const std::string& s : skipped_) md << "- " << s << "\n";
        }
        TextTable csv = t;
        if (!embree_.empty()) {
            csv.header.push_back("embree_medium_ms");
            csv.header.push_back("embree_high_ms");
            for (auto& row : csv.rows) {
                std::string med = "", high = "";
                for (const EmbreeRow& e : embree_)
                    if (e.input == row[0]) med = fmt(e.medium_ms, 3), high = fmt(e.high_ms, 3);
                row.push_back(med);
                row.push_back(high);
            }
        }
        write_report(opt_.out, "build", "build", md.str(), csv);
    }

    BuildBenchOptions opt_;
    std::vector<BuilderRow> rows_;
    std::vector<EmbreeRow> embree_;
    std::vector<std::string> skipped_;
    double cpu_triangle_cost_ = Device::open("cpu").triangle_cost();
};

}  // namespace

int run_build_bench(const BuildBenchOptions& options) {
    if (options.runs < 1) throw Error(ErrorCode::InvalidArgument, "--runs must be at least 1");
    machine_info();
    return BuildBench(options).run();
}

}  // namespace kdrt::bench
