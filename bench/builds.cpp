#include "builds.h"

#include "mesh_generator.h"

#ifdef KDRT_BENCH_HAVE_EMBREE
#include "embree_scene.h"
#endif

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/kd_tree.h>
#include <kdrt/render.h>
#include <kdrt/working_scene.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>
#include <optional>

namespace kdrt::bench {

namespace {

constexpr std::size_t kBig = 2'000'000;  // from here one build without a warm-up, and no exact sweep

// A field of /proc/self/status or /proc/meminfo, in MiB (NaN when missing).
double proc_mib(const char* file, const std::string& field) {
    std::ifstream in(file);
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

// Resets the process's RSS high-water mark (VmHWM) to its current RSS, so
// that each build's peak is its own; false where the kernel refuses.
bool reset_peak_rss() {
    std::ofstream out("/proc/self/clear_refs");
    out << "5";
    out.flush();
    return static_cast<bool>(out);
}

struct Builder {
    KdBuilderKind kind;
    int threads;  // 0: every logical CPU
    const char* label;
};

constexpr Builder kBuilders[] = {{KdBuilderKind::Median, 1, "median-10"},
                                 {KdBuilderKind::SahExact, 1, "sah-exact"},
                                 {KdBuilderKind::Sah, 1, "sah"},
                                 {KdBuilderKind::Sah, 0, "sah"}};

Json measure_builder(const std::string& name, const KdBuildInput& input, std::size_t objects, const Builder& b,
                     double triangle_cost, int runs) {
    KdBuildConfig config = KdBuildConfig{}.with_triangle_cost(triangle_cost);
    config.builder = b.kind;
    config.threads = worker_count(b.threads);
    config.max_depth = b.kind == KdBuilderKind::Median ? 10 : 0;
    std::vector<double> build, ropes;
    double peak = kNaN, before = kNaN;
    std::optional<KdTree> tree;
    for (int r = runs > 1 ? -1 : 0; r < runs; ++r) {  // a warm-up, except for the biggest inputs
        tree.reset();
        const bool reset = reset_peak_rss();
        const double rss = proc_mib("/proc/self/status", "VmRSS");
        Stopwatch clock;
        KdTree t = build_kd_tree(input, config);
        const double build_ms = clock.ms();
        if (r == 0) {  // one build's peak, its tree included
            peak = reset ? proc_mib("/proc/self/status", "VmHWM") : kNaN;
            before = rss;
        }
        clock.restart();
        build_ropes(t);
        if (r >= 0) {
            build.push_back(build_ms);
            ropes.push_back(clock.ms());
        }
        tree = std::move(t);
    }
    const KdTreeStats s = kd_tree_stats(*tree, config);
    std::fprintf(stderr, "  %s %s on %d thread(s): %.1f ms, %zu nodes, %.1f B/object without ropes\n", name.c_str(),
                 b.label, config.threads, median(build), s.nodes, s.per_object(s.node_bytes + s.leaf_object_bytes));
    return {{"input", name},
            {"objects", objects},
            {"builder", b.label},
            {"threads", config.threads},
            {"build_ms", median(build)},
            {"ropes_ms", median(ropes)},
            {"sah_cost", s.sah_cost},
            {"nodes", s.nodes},
            {"leaves", s.leaves},
            {"empty_leaves", s.empty_leaves},
            {"max_depth", s.max_leaf_depth},
            {"references_per_object", s.duplication},
            {"node_bytes", s.node_bytes},
            {"leaf_list_bytes", s.leaf_object_bytes},
            {"rope_bytes", s.rope_bytes},
            {"rss_before_mib", before},
            {"build_peak_rss_mib", peak}};
}

// The BVH builder (CommitOptions::accel = Accel::Bvh) through a commit on
// the cpu device, in an arena of `threads`: CommitStats::build_ms is the
// objects' boxes and the build, what rtcCommitScene does, without the
// commit's preparation and packing. Its peak is left out: a commit's peak
// holds those too.
Json measure_bvh(const std::string& name, const Device& cpu, const Scene& scene, std::size_t objects, int threads,
                 int runs) {
    CommitOptions commit;
    commit.accel = Accel::Bvh;
    commit.bvh.threads = worker_count(threads);
    std::optional<BvhStats> s;
    const double build_ms = median_build_ms(runs, [&] {  // a warm-up, except for the biggest inputs
        double ms = kNaN;
        tbb::task_arena arena(commit.bvh.threads);  // the boxes too, which a commit makes on the pool it runs in
        arena.execute([&] {
            const CommittedScene c = CommittedScene::commit(cpu, scene, commit);
            ms = c.stats().build_ms;
            s = c.bvh_stats();
        });
        return ms;
    });
    if (!s) throw Error(ErrorCode::InvalidArgument, "a commit with Accel::Bvh reported no BVH");
    std::fprintf(stderr, "  %s bvh on %d thread(s): %.1f ms, %zu nodes, %.1f B/object\n", name.c_str(),
                 commit.bvh.threads, build_ms, s->nodes, s->per_object(s->total_bytes()));
    return {{"input", name},
            {"objects", objects},
            {"builder", "bvh"},
            {"threads", commit.bvh.threads},
            {"build_ms", build_ms},
            {"ropes_ms", nullptr},
            {"sah_cost", s->sah_cost},
            {"nodes", s->nodes},
            {"leaves", s->leaves},
            {"empty_slots", s->empty_slots},
            {"max_depth", s->depth},
            {"references_per_object", static_cast<double>(s->leaf_object_bytes / sizeof(std::uint32_t)) /
                                          static_cast<double>(std::max<std::size_t>(objects, 1))},
            {"node_bytes", s->node_bytes},
            {"leaf_list_bytes", s->leaf_object_bytes},
            {"rope_bytes", 0},
            {"rss_before_mib", nullptr},
            {"build_peak_rss_mib", nullptr}};
}

#ifdef KDRT_BENCH_HAVE_EMBREE
// rtcCommitScene on Embree's TBB pool (every logical CPU), medium and high quality.
Json measure_embree(const std::string& name, const WorkingScene& ws, int runs) {
    Json j = {{"input", name}};
    for (const RTCBuildQuality q : {RTC_BUILD_QUALITY_MEDIUM, RTC_BUILD_QUALITY_HIGH})
        j[q == RTC_BUILD_QUALITY_MEDIUM ? "medium_ms" : "high_ms"] =
            median_build_ms(runs, [&] { return EmbreeScene(ws, false, q).commit_ms(); });
    std::fprintf(stderr, "  %s Embree: %.1f ms medium, %.1f ms high\n", name.c_str(), j["medium_ms"].get<double>(),
                 j["high_ms"].get<double>());
    return j;
}
#endif

}  // namespace

Json run_build(const BuildOptions& o) {
    if (o.runs < 1) throw Error(ErrorCode::InvalidArgument, "--runs must be at least 1");
    const Device cpu = Device::open("cpu");
    const double triangle_cost = cpu.triangle_cost();
    Json rows = Json::array(), embree = Json::array(), skipped = Json::array();
    std::vector<std::string> inputs = o.scenes;
    inputs.insert(inputs.end(), o.meshes.begin(), o.meshes.end());
    for (std::size_t i = 0; i < inputs.size(); ++i) {
        const bool generated = i >= o.scenes.size();
        NamedScene in = generated ? NamedScene{"", make_generated_scene(inputs[i])}
                                  : std::move(load_scenes({inputs[i]}, o.scenes_dir).front());
        if (generated) in.name = in.scene.name;
        const std::size_t objects = in.scene.object_count();
        std::fprintf(stderr, "build: %s, %zu objects\n", in.name.c_str(), objects);
        // About 1 KiB per object covers the copies, the builders' work lists and the trees.
        if (objects / 1024.0 > 0.6 * proc_mib("/proc/meminfo", "MemAvailable")) {
            skipped.push_back(in.name + ": not enough memory available");
            continue;
        }
        const WorkingScene ws(in.scene);
        const KdBuildInput input = ws.build_input();
        const int runs = objects >= kBig ? 1 : o.runs;
        for (const Builder& b : kBuilders) {
            if (b.kind == KdBuilderKind::SahExact && objects >= kBig) {
                skipped.push_back(in.name + " sah-exact: minutes and GiBs from 2M objects");
                continue;
            }
            rows.push_back(measure_builder(in.name, input, objects, b, triangle_cost, runs));
        }
        for (const int threads : {1, 0}) rows.push_back(measure_bvh(in.name, cpu, in.scene, objects, threads, runs));
        in.scene = Scene();  // Embree needs the prepared geometry only
#ifdef KDRT_BENCH_HAVE_EMBREE
        embree.push_back(measure_embree(in.name, ws, runs));
#endif
    }
    return {{"settings", {{"runs", o.runs}, {"threads", worker_count(0)}, {"triangle_cost", triangle_cost}}},
            {"rows", rows},
            {"embree", embree},
            {"skipped", skipped}};
}

}  // namespace kdrt::bench
