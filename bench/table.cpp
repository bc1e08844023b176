#include "table.h"

#ifdef KDRT_BENCH_HAVE_EMBREE
#include "embree_render.h"
#endif

#include <kdrt/device.h>
#include <kdrt/enum_names.h>
#include <kdrt/error.h>
#include <kdrt/id_map.h>
#include <kdrt/image.h>
#include <kdrt/render.h>

#include <cstdio>
#include <optional>

namespace kdrt::bench {

namespace {

constexpr int kStudyMedianDepth = 10;  // the study's kd-trees: the median builder at depth 10

// One configuration of kdrt, and what it measured on the current scene.
struct Row {
    RenderOptions options;
    std::string tree;  // "-", "median-10" or "sah" (kd-trees), or "bvh"
    std::string status = "timed", note, device_name;
    IdMapComparison ids;
    std::vector<double> build_ms, compile_ms, render_ms;
    RayCounts rays;
};

// The study's rows, each kd-tree traversal on each tree (brute force once),
// and the BVH (kdrt's default) on each device.
std::vector<Row> make_rows(const TableOptions& t) {
    std::vector<Row> rows;
    for (const std::string& device : t.devices.empty() ? all_device_ids() : t.devices) {
        Row base;
        base.options.device = device;
        base.options.frame.width = t.width;
        base.options.frame.height = t.height;
        base.options.frame.max_depth = t.max_depth;
        base.options.frame.samples = 1;
        base.options.frame.threads = t.threads;
        for (const EnumName<Traversal>& traversal : enum_names<Traversal>())
            for (const KdBuilderKind builder : {KdBuilderKind::Median, KdBuilderKind::Sah}) {
                const bool none = traversal.value == Traversal::None;
                if (none && builder == KdBuilderKind::Median) continue;  // no tree: one row
                Row r = base;
                r.options.commit.accel = Accel::KdTree;
                r.options.commit.traversal = traversal.value;
                r.options.commit.tree.builder = builder;
                r.options.commit.tree.max_depth = builder == KdBuilderKind::Median ? kStudyMedianDepth : 0;
                r.tree = none ? "-" : builder == KdBuilderKind::Median ? "median-10" : "sah";
                rows.push_back(std::move(r));
            }
        Row b = base;
        b.options.commit.accel = Accel::Bvh;
        b.options.commit.traversal = Traversal::Stack;
        b.tree = "bvh";
        rows.push_back(std::move(b));
    }
    return rows;
}

// The cpu device without a tree, camera rays only (depth 1 and no lights
// give the same id map, much cheaper).
RenderResult reference_ids(const Scene& scene, const TableOptions& t) {
    Scene unlit = scene;
    unlit.lights.clear();
    RenderOptions o;
    o.device = "cpu";
    o.frame.width = t.width;
    o.frame.height = t.height;
    o.frame.max_depth = 1;
    o.frame.threads = t.threads;
    o.frame.want_ids = true;
    o.commit.traversal = Traversal::None;
    return render(unlit, o);
}

// Brute force is left out where a render, estimated from a 64x64 one, would
// take longer than the limit (ball-o-calypse: minutes on a laptop's cores).
bool too_slow(const Scene& scene, Row& row, const TableOptions& t) {
    if (row.options.commit.traversal != Traversal::None || t.width * t.height <= 64 * 64) return false;
    RenderOptions small = row.options;
    small.frame.width = std::min(64, t.width);
    small.frame.height = std::min(64, t.height);
    const double estimate_ms = render(scene, small).stats.render_ms * t.width * t.height /
                               (static_cast<double>(small.frame.width) * small.frame.height);
    if (estimate_ms <= 1000.0 * t.none_limit_s) return false;
    row.status = "over limit";
    row.note = "estimated " + std::to_string(static_cast<long>(estimate_ms / 1000.0)) + " s";
    return true;
}

// The warm-up render: it builds the tree and compiles the kernels, and its
// id map must be the reference's (ties and silhouettes aside).
std::optional<RenderResult> validate(const Scene& scene, const RenderResult& reference, Row& row) {
    RenderOptions o = row.options;
    o.frame.want_ids = true;
    RenderResult r = render(scene, o);
    row.ids = compare_id_maps(reference, r);
    row.device_name = r.stats.device_name;
    if (row.ids.ok()) return r;
    row.status = "failed validation";
    row.note = row.ids.summary();
    return std::nullopt;
}

Json row_json(const std::string& scene, const Row& r) {
    const double render = median(r.render_ms);
    return {{"scene", scene},
            {"device", r.options.device},
            {"device_name", r.device_name},
            {"traversal", to_string(r.options.commit.traversal)},
            {"tree", r.tree},
            {"status", r.status},
            {"note", r.note},
            {"ids", r.ids.pixels ? r.ids.summary() : ""},
            {"build_ms", median(r.build_ms)},
            {"compile_ms", median(r.compile_ms)},
            {"render_ms", render},
            {"runs", r.render_ms.size()},
            {"rays", r.rays.total()},
            {"mrays_per_s", mrays_per_s(static_cast<double>(r.rays.total()), render)}};
}

#ifdef KDRT_BENCH_HAVE_EMBREE
// Embree's side of one scene: validated like a row, and the harness checked.
struct EmbreeSide {
    std::optional<EmbreeRenderer> renderer;
    bool timed = false;
    Json result = Json::object();
    std::vector<double> render_ms;
    RayCounts rays;
};

void prepare_embree(EmbreeSide& e, const Scene& scene, const RenderResult& reference, const RenderResult* cpu_image,
                    const TableOptions& t) {
    RenderOptions o;
    o.frame.width = t.width;
    o.frame.height = t.height;
    o.frame.max_depth = t.max_depth;
    o.frame.samples = 1;
    e.renderer.emplace(scene, o);
    const RenderResult warm = e.renderer->render(t.threads, true);
    const IdMapComparison ids = compare_id_maps(reference, warm);
    e.result = {{"name", warm.stats.device_name}, {"status", ids.ok() ? "timed" : "failed validation"},
                {"ids", ids.summary()}, {"bvh_build_ms", e.renderer->commit_ms()}};
    e.timed = ids.ok();
    if (!cpu_image) return;
    e.result["rmse_vs_kdrt_cpu"] = image_rmse(cpu_image->image, warm.image);
    e.result["max_error_vs_kdrt_cpu"] = image_max_error(cpu_image->image, warm.image);
    // The harness: the same shader over kdrt's stack traversal must give the cpu device's image.
    const WorkingScene& prepared = e.renderer->prepared();
    const KdTree tree =
        build_kd_tree(prepared.build_input(), KdBuildConfig{}.with_triangle_cost(Device::open("cpu").triangle_cost()));
    const RenderResult h = render_whitted(prepared, *prepared.kd_intersector(tree, Traversal::Stack), t.threads, false);
    e.result["harness_rmse"] = image_rmse(cpu_image->image, h.image);
}
#endif

}  // namespace

Json run_table(const TableOptions& t) {
    if (t.runs < 1) throw Error(ErrorCode::InvalidArgument, "--runs must be at least 1");
    Json rows = Json::array(), embree = Json::array();
    int failures = 0;  // rows that failed validation or threw
    for (const NamedScene& ns : load_scenes(t.scenes.empty() ? study_scene_names() : t.scenes, t.scenes_dir)) {
        std::fprintf(stderr, "table: %s\n", ns.name.c_str());
        const RenderResult reference = reference_ids(ns.scene, t);
        std::vector<Row> scene_rows = make_rows(t);
        std::optional<RenderResult> cpu_image;  // the cpu device, stack traversal, SAH tree: Embree's yardstick
        for (Row& r : scene_rows) {
            try {
                if (too_slow(ns.scene, r, t)) continue;
                std::optional<RenderResult> warm = validate(ns.scene, reference, r);
                const CommitOptions& c = r.options.commit;
                if (warm && r.options.device == "cpu" && c.traversal == Traversal::Stack && r.tree == "sah")
                    cpu_image = std::move(warm);
            } catch (const std::exception& e) {
                r.status = "error";
                r.note = e.what();
            }
        }
#ifdef KDRT_BENCH_HAVE_EMBREE
        EmbreeSide e;
        prepare_embree(e, ns.scene, reference, cpu_image ? &*cpu_image : nullptr, t);
#endif
        for (int run = 0; run < t.runs; ++run) {
            for (Row& r : scene_rows) {
                if (r.status != "timed") continue;
                const RenderResult res = render(ns.scene, r.options);
                r.build_ms.push_back(res.stats.build_ms);
                r.compile_ms.push_back(res.stats.compile_ms);
                r.render_ms.push_back(res.stats.render_ms);
                r.rays = res.stats.rays;
            }
#ifdef KDRT_BENCH_HAVE_EMBREE
            if (e.timed) {
                const RenderResult res = e.renderer->render(t.threads, false);
                e.render_ms.push_back(res.stats.render_ms);
                e.rays = res.stats.rays;
            }
#endif
        }
        for (const Row& r : scene_rows) {
            failures += r.status == "failed validation" || r.status == "error";
            rows.push_back(row_json(ns.name, r));
            std::fprintf(stderr, "  %s %s %s: %s, %.1f ms\n", r.options.device.c_str(),
                         to_string(r.options.commit.traversal), r.tree.c_str(), r.status.c_str(), median(r.render_ms));
        }
#ifdef KDRT_BENCH_HAVE_EMBREE
        const double ms = median(e.render_ms);
        failures += !e.timed;
        e.result["scene"] = ns.name;
        e.result["render_ms"] = ms;
        e.result["mrays_per_s"] = mrays_per_s(static_cast<double>(e.rays.total()), ms);
        embree.push_back(e.result);
        std::fprintf(stderr, "  Embree: %.1f ms\n", ms);
#endif
    }
    return {{"settings",
             {{"width", t.width}, {"height", t.height}, {"max_depth", t.max_depth}, {"runs", t.runs},
              {"threads", worker_count(t.threads)}, {"median_depth", kStudyMedianDepth}}},
            {"rows", rows},
            {"embree", embree},
            {"failures", failures}};
}

}  // namespace kdrt::bench
