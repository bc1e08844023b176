#include "table.h"

#include "chart.h"
#include "compile_probe.h"
#include "id_check.h"
#include "interference.h"
#include "machine_info.h"
#include "report.h"
#include "scene_set.h"
#include "stats.h"
#include "study_reference.h"
#include "subprocess.h"

#ifdef KDRT_BENCH_HAVE_EMBREE
#include "embree_renderer.h"
#endif

#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/render.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

namespace kdrt::bench {

namespace {

constexpr int kEstimateSize = 64;  // brute force is estimated from a render this size

struct RowConfig {
    std::string device;
    Traversal traversal = Traversal::Stack;
    bool has_tree = false;
    KdBuilderKind builder = KdBuilderKind::Sah;

    bool opencl() const { return device != "cpu"; }
    std::string tree_label() const {
        if (!has_tree) return "-";
        return builder == KdBuilderKind::Median ? "median-" + std::to_string(kStudyMedianDepth) : "sah";
    }
    std::string label() const {
        return device + " " + to_string(traversal) + (has_tree ? " " + tree_label() : "");
    }
};

enum class Status { Timed, OverLimit, Skipped, Failed, Error };

struct Cell {
    Status status = Status::Skipped;
    std::string note;
    IdCheck check;
    double build_ms = kNaN, cold_compile_ms = kNaN, cached_compile_ms = kNaN;
    double render_ms = kNaN, render_min_ms = kNaN, render_max_ms = kNaN, estimate_ms = kNaN;
    RayCounts rays;
    int runs = 0;
    int attempts = 0;
    Quietness quiet;  // other processes' CPU use during the timed runs
    bool cache_hits = true;
    std::string kernel_options, device_name;

    double mrays() const { return mrays_per_s(static_cast<double>(rays.total()), render_ms); }
};

struct EmbreeCell {
    Status status = Status::Skipped;
    std::string note, name;
    IdCheck check;
    double commit_ms = kNaN, render_ms = kNaN, rmse = kNaN, max_error = kNaN;
    Quietness quiet;
    RayCounts rays;
    double mrays() const { return mrays_per_s(static_cast<double>(rays.total()), render_ms); }
};

IdMap id_map(const RenderResult& r) { return {r.image.width, r.image.height, r.ids, r.hit_t}; }

std::vector<RowConfig> make_rows(const std::vector<std::string>& devices) {
    std::vector<RowConfig> rows;
    for (const std::string& d : devices) {
        rows.push_back({d, Traversal::None, false, KdBuilderKind::Sah});
        for (Traversal t : {Traversal::Restart, Traversal::Ropes, Traversal::Stack})
            for (KdBuilderKind b : {KdBuilderKind::Median, KdBuilderKind::Sah}) rows.push_back({d, t, true, b});
    }
    return rows;
}

RenderOptions options_for(const TableOptions& t, const RowConfig& row, const std::filesystem::path& kernel_cache) {
    RenderOptions o;
    o.frame.width = t.width;
    o.frame.height = t.height;
    o.frame.max_depth = t.max_depth;
    o.frame.samples = 1;
    o.device = row.device;
    o.frame.threads = t.threads;
    o.commit.traversal = row.traversal;
    o.commit.tree.builder = row.builder;
    o.commit.tree.max_depth = row.builder == KdBuilderKind::Median ? kStudyMedianDepth : 0;
    o.commit.kernel_cache_dir = kernel_cache;
    return o;
}

std::string status_text(Status s, const std::string& note) {
    switch (s) {
        case Status::Timed: return "";
        case Status::OverLimit: return note;
        case Status::Skipped: return "skipped";
        case Status::Failed: return "FAILED validation";
        case Status::Error: return "error";
    }
    return "?";
}

class TableRun {
public:
    explicit TableRun(const TableOptions& o) : opt_(o), scratch_("kdrt-bench-table") {
        kernel_cache_ = scratch_.fresh("kernels");
    }

    int run() {
        scenes_ = load_scenes(opt_.scenes, opt_.scenes_dir);
        devices_ = opt_.devices.empty() ? all_device_ids() : opt_.devices;
        rows_ = make_rows(devices_);
        cells_.assign(rows_.size(), std::vector<Cell>(scenes_.size()));
        embree_.assign(scenes_.size(), EmbreeCell{});
        const std::size_t total = rows_.size() * scenes_.size();
        std::fprintf(stderr, "kdrt-bench table: %zu configurations x %zu scenes at %dx%d, depth %d, %d run(s) after a warm-up\n",
                     rows_.size(), scenes_.size(), opt_.width, opt_.height, opt_.max_depth, opt_.runs);
        std::size_t done = 0;
        for (std::size_t s = 0; s < scenes_.size(); ++s) {
            reference(s);
            for (std::size_t r = 0; r < rows_.size(); ++r) {
                ++done;
                measure(r, s);
                print_progress(done, total, r, s);
            }
            embree(s);
            kdrt_image_.reset();
            reference_.reset();
        }
        write_outputs();
        return 0;
    }

private:
    // The cpu device without a tree, camera rays only (depth 1, no lights: the
    // id map is the same, the render much cheaper).
    void reference(std::size_t s) {
        Scene scene = scenes_[s].scene;
        scene.lights.clear();
        RenderOptions o;
        o.device = "cpu";
        o.frame.width = opt_.width;
        o.frame.height = opt_.height;
        o.frame.max_depth = 1;
        o.frame.samples = 1;
        o.frame.threads = opt_.threads;
        o.commit.traversal = Traversal::None;
        o.frame.want_ids = true;
        const RenderResult r = render(scene, o);
        reference_ = id_map(r);
        std::fprintf(stderr, "  %s: reference id map (cpu, no tree, camera rays) in %.0f ms\n", scenes_[s].name.c_str(),
                     r.stats.render_ms);
    }

    void measure(std::size_t ri, std::size_t si) {
        const RowConfig& row = rows_[ri];
        const NamedScene& ns = scenes_[si];
        Cell& c = cells_[ri][si];
        RenderOptions o = options_for(opt_, row, kernel_cache_);
        try {
            if (row.traversal == Traversal::None) {
                if (opt_.quick && ns.name == "ball-o-calypse") {
                    c.status = Status::Skipped;
                    c.note = "skipped in --quick";
                    return;
                }
                // Estimate from a small render scaled by the pixel count.
                RenderOptions small = o;
                small.frame.width = std::min(kEstimateSize, opt_.width);
                small.frame.height = std::min(kEstimateSize, opt_.height);
                const RenderResult r = render(ns.scene, small);
                c.estimate_ms = r.stats.render_ms * (static_cast<double>(opt_.width) * opt_.height) /
                                (static_cast<double>(small.frame.width) * small.frame.height);
                if (c.estimate_ms > opt_.none_limit_s * 1000.0) {
                    c.status = Status::OverLimit;
                    c.note = "> " + fmt(opt_.none_limit_s, 0) + " s (est. " + fmt(c.estimate_ms / 1000.0, 0) + " s)";
                    return;
                }
            }
            // Warm-up, and the one validation of this configuration.
            o.frame.want_ids = true;
            const RenderResult warm = render(ns.scene, o);
            c.check = compare_ids(*reference_, id_map(warm));
            c.kernel_options = warm.stats.opencl.kernel_options;
            c.device_name = warm.stats.device_name;
            if (!row.opencl() && row.traversal == Traversal::Stack && row.has_tree && row.builder == KdBuilderKind::Sah)
                kdrt_image_ = warm.image;
            if (!c.check.ok()) {
                c.status = Status::Failed;
                c.note = c.check.summary();
                return;
            }
            // --quick measures the cold compile of the stack traversal's kernels only (a child process each).
            if (row.opencl() && opt_.cold_compile && (!opt_.quick || row.traversal == Traversal::Stack)) {
                const ColdCompile& cold =
                    cold_.get(ns.path, row.device, row.traversal, opt_.max_depth, warm.stats.opencl.kernel_options, scratch_);
                c.cold_compile_ms = cold.ok ? cold.compile_ms : kNaN;
                if (!cold.ok) c.note = "cold compile: " + cold.error;
            }
            o.frame.want_ids = false;
            std::vector<double> build, compile, rend;
            c.quiet = measure_quietly([&] {
                build.clear();
                compile.clear();
                rend.clear();
                ++c.attempts;
                for (int i = 0; i < opt_.runs; ++i) {
                    const RenderResult r = render(ns.scene, o);
                    build.push_back(r.stats.build_ms);
                    compile.push_back(r.stats.compile_ms);
                    rend.push_back(r.stats.render_ms);
                    c.rays = r.stats.rays;
                    c.cache_hits = c.cache_hits && (!row.opencl() || r.stats.opencl.kernel_cache_hit);
                }
            });
            c.runs = opt_.runs;
            c.build_ms = median(build);
            c.cached_compile_ms = row.opencl() ? median(compile) : kNaN;
            c.render_ms = median(rend);
            c.render_min_ms = *std::min_element(rend.begin(), rend.end());
            c.render_max_ms = *std::max_element(rend.begin(), rend.end());
            c.status = Status::Timed;
        } catch (const std::exception& e) {
            c.status = Status::Error;
            c.note = e.what();
        }
    }

    void embree(std::size_t si) {
        EmbreeCell& e = embree_[si];
#ifdef KDRT_BENCH_HAVE_EMBREE
        if (!opt_.embree) return;
        const NamedScene& ns = scenes_[si];
        try {
            RenderOptions o;
            o.frame.width = opt_.width;
            o.frame.height = opt_.height;
            o.frame.max_depth = opt_.max_depth;
            o.frame.samples = 1;
            const EmbreeRenderer renderer(ns.scene, o);
            e.commit_ms = renderer.commit_ms();
            const RenderResult warm = renderer.render(opt_.threads, true);
            e.name = warm.stats.device_name;
            e.check = compare_ids(*reference_, id_map(warm));
            if (kdrt_image_) {
                e.rmse = image_rmse(*kdrt_image_, warm.image);
                e.max_error = image_max_error(*kdrt_image_, warm.image);
            }
            if (!e.check.ok()) {
                e.status = Status::Failed;
                e.note = e.check.summary();
            } else {
                std::vector<double> rend;
                e.quiet = measure_quietly([&] {
                    rend.clear();
                    for (int i = 0; i < opt_.runs; ++i) {
                        const RenderResult r = renderer.render(opt_.threads, false);
                        rend.push_back(r.stats.render_ms);
                        e.rays = r.stats.rays;
                    }
                });
                e.render_ms = median(rend);
                e.status = Status::Timed;
            }
        } catch (const std::exception& ex) {
            e.status = Status::Error;
            e.note = ex.what();
        }
        std::fprintf(stderr, "  %s: Embree: %s ms (%s Mrays/s), BVH build %s ms, ids %s, RMSE against kdrt cpu %s\n",
                     scenes_[si].name.c_str(), fmt_ms(e.render_ms).c_str(), fmt(e.mrays(), 2).c_str(),
                     fmt_ms(e.commit_ms).c_str(), e.check.summary().c_str(), fmt(e.rmse, 5).c_str());
#else
        (void)si;
        e.note = "built without Embree";
#endif
    }

    void print_progress(std::size_t done, std::size_t total, std::size_t r, std::size_t s) const {
        const Cell& c = cells_[r][s];
        std::string what;
        if (c.status == Status::Timed) {
            what = "render " + fmt_ms(c.render_ms) + " ms (" + fmt(c.mrays(), 2) + " Mrays/s), build " +
                   fmt_ms(c.build_ms) + " ms";
            if (rows_[r].opencl())
                what += ", compile " + fmt_ms(c.cold_compile_ms) + " cold / " + fmt_ms(c.cached_compile_ms) + " cached";
            what += ", ids " + c.check.summary();
        } else {
            what = status_text(c.status, c.note) + (c.note.empty() || c.status == Status::OverLimit ? "" : ": " + c.note);
        }
        std::fprintf(stderr, "[%zu/%zu] %s %s: %s\n", done, total, scenes_[s].name.c_str(), rows_[r].label().c_str(),
                     what.c_str());
    }

    // ---- outputs ---------------------------------------------------------

    std::vector<std::string> scene_header(std::vector<std::string> first) const {
        for (const NamedScene& s : scenes_) first.push_back(s.name);
        return first;
    }

    std::string render_cell(const Cell& c) const {
        if (c.status != Status::Timed) return status_text(c.status, c.note);
        return fmt_ms(c.render_ms) + (c.quiet.too_busy() ? " *" : "");
    }

    std::string settings_text() const {
        std::ostringstream o;
        o << opt_.width << "x" << opt_.height << ", ray depth " << opt_.max_depth << ", one sample per pixel; median of "
          << opt_.runs << " run(s) after one warm-up (the warm-up is the validation render). Trees: `median-"
          << kStudyMedianDepth << "` is the study's median builder at depth " << kStudyMedianDepth
          << ", `sah` the SAH builder with its automatic depth; `none` uses no tree. The cpu device and Embree use "
          << (opt_.threads > 0 ? std::to_string(opt_.threads) : std::to_string(machine_info().logical_cpus))
          << " threads. `none` is estimated from a " << kEstimateSize << "x" << kEstimateSize
          << " render and not run where the estimate exceeds " << fmt(opt_.none_limit_s, 0) << " s.";
        o << " A cell whose timed runs shared the machine with other processes using more than " << kBusyCores
          << " cores (from /proc/stat) is measured again, up to " << kMaxAttempts
          << " times (within 5 minutes of pauses in all); `*` marks a figure still taken under such load.";
        if (opt_.quick) o << " **--quick**: a smoke test, not a measurement.";
        return o.str();
    }

    TextTable render_table() const {
        TextTable t;
        t.header = scene_header({"device", "traversal", "tree"});
        for (std::size_t r = 0; r < rows_.size(); ++r) {
            std::vector<std::string> row{rows_[r].device, to_string(rows_[r].traversal), rows_[r].tree_label()};
            for (const Cell& c : cells_[r]) row.push_back(render_cell(c));
            t.add(row);
        }
        if (embree_enabled()) {
            std::vector<std::string> row{"Embree", "BVH", "Embree"};
            for (const EmbreeCell& e : embree_)
                row.push_back(e.status == Status::Timed
                                  ? fmt_ms(e.render_ms) + (e.quiet.too_busy() ? " *" : "")
                                  : status_text(e.status, e.note));
            t.add(row);
        }
        for (const StudyRow& s : study_rows()) {
            std::vector<std::string> row{s.label, "", "study"};
            for (const NamedScene& sc : scenes_) row.push_back(study_cell(s, sc.name));
            t.add(row);
        }
        return t;
    }

    TextTable per_row_table(const std::function<std::string(const Cell&)>& f,
                            const std::function<bool(const RowConfig&)>& keep = nullptr) const {
        TextTable t;
        t.header = scene_header({"device", "traversal", "tree"});
        for (std::size_t r = 0; r < rows_.size(); ++r) {
            if (keep && !keep(rows_[r])) continue;
            std::vector<std::string> row{rows_[r].device, to_string(rows_[r].traversal), rows_[r].tree_label()};
            for (const Cell& c : cells_[r]) row.push_back(c.status == Status::Timed ? f(c) : "-");
            t.add(row);
        }
        return t;
    }

    bool embree_enabled() const {
#ifdef KDRT_BENCH_HAVE_EMBREE
        return opt_.embree;
#else
        return false;
#endif
    }

    // Per device and scene: the fastest timed kdrt configuration against Embree, same run.
    TextTable embree_ratio_table() const {
        TextTable t;
        t.header = {"scene", "Embree ms", "Embree BVH build ms", "image RMSE vs kdrt cpu", "Embree ids"};
        for (const std::string& d : devices_) {
            t.header.push_back("best kdrt " + d);
            t.header.push_back(d + " / Embree");
        }
        for (std::size_t s = 0; s < scenes_.size(); ++s) {
            const EmbreeCell& e = embree_[s];
            std::vector<std::string> row{scenes_[s].name, fmt_ms(e.render_ms), fmt_ms(e.commit_ms), fmt(e.rmse, 5),
                                         e.check.summary()};
            for (const std::string& d : devices_) {
                const Cell* best = nullptr;
                const RowConfig* best_row = nullptr;
                for (std::size_t r = 0; r < rows_.size(); ++r) {
                    const Cell& c = cells_[r][s];
                    if (rows_[r].device != d || c.status != Status::Timed) continue;
                    if (!best || c.render_ms < best->render_ms) best = &c, best_row = &rows_[r];
                }
                if (!best) {
                    row.insert(row.end(), {"-", "-"});
                    continue;
                }
                row.push_back(fmt_ms(best->render_ms) + " (" + to_string(best_row->traversal) + " " +
                              best_row->tree_label() + ")");
                row.push_back(e.status == Status::Timed ? fmt_ratio(best->render_ms / e.render_ms) : "-");
            }
            t.add(row);
        }
        return t;
    }

    TextTable csv_table() const {
        TextTable t;
        t.header = {"scene", "device", "device_name", "traversal", "tree", "width", "height", "max_depth", "status",
                    "note", "runs", "build_ms", "compile_cold_ms", "compile_cached_ms", "kernel_cache_hit",
                    "render_ms", "render_min_ms", "render_max_ms", "rays_camera", "rays_shadow", "rays_secondary",
                    "rays_total", "mrays_per_s", "ids_differ", "ids_silhouette", "ids_tie", "ids_unexplained",
                    "estimate_ms", "other_cores", "attempts", "kernel_options"};
        const char* names[] = {"timed", "over-limit", "skipped", "failed-validation", "error"};
        for (std::size_t s = 0; s < scenes_.size(); ++s) {
            for (std::size_t r = 0; r < rows_.size(); ++r) {
                const Cell& c = cells_[r][s];
                t.add({scenes_[s].name, rows_[r].device, c.device_name, to_string(rows_[r].traversal),
                       rows_[r].tree_label(), std::to_string(opt_.width), std::to_string(opt_.height),
                       std::to_string(opt_.max_depth), names[static_cast<int>(c.status)], c.note,
                       std::to_string(c.runs), fmt(c.build_ms, 3), fmt(c.cold_compile_ms, 3),
                       fmt(c.cached_compile_ms, 3), rows_[r].opencl() && c.status == Status::Timed ? (c.cache_hits ? "1" : "0") : "",
                       fmt(c.render_ms, 3), fmt(c.render_min_ms, 3), fmt(c.render_max_ms, 3),
                       std::to_string(c.rays.camera), std::to_string(c.rays.shadow), std::to_string(c.rays.secondary),
                       std::to_string(c.rays.total()), fmt(c.mrays(), 4), std::to_string(c.check.mismatches),
                       std::to_string(c.check.edges), std::to_string(c.check.ties), std::to_string(c.check.unexplained),
                       fmt(c.estimate_ms, 1), fmt(c.quiet.other_cores, 2), std::to_string(c.attempts), c.kernel_options});
            }
            if (embree_enabled()) {
                const EmbreeCell& e = embree_[s];
                t.add({scenes_[s].name, "embree", e.name, "bvh", "embree", std::to_string(opt_.width),
                       std::to_string(opt_.height), std::to_string(opt_.max_depth), names[static_cast<int>(e.status)],
                       e.note + (std::isnan(e.rmse) ? "" : "rmse vs kdrt cpu " + fmt(e.rmse, 6)),
                       std::to_string(opt_.runs), fmt(e.commit_ms, 3), "", "", "", fmt(e.render_ms, 3), "", "",
                       std::to_string(e.rays.camera), std::to_string(e.rays.shadow), std::to_string(e.rays.secondary),
                       std::to_string(e.rays.total()), fmt(e.mrays(), 4), std::to_string(e.check.mismatches),
                       std::to_string(e.check.edges), std::to_string(e.check.ties),
                       std::to_string(e.check.unexplained), "", fmt(e.quiet.other_cores, 2), "", ""});
            }
            for (const StudyRow& st : study_rows()) {
                const double v = study_ms(st, scenes_[s].name);
                if (std::isnan(v)) continue;
                t.add({scenes_[s].name, "study", st.label, "", "", "500", "500", "15", "reference",
                       study_cell(st, scenes_[s].name), "", "", "", "", "", fmt(v, 0), "", "", "", "", "", "", "", "",
                       "", "", "", "", "", "", ""});
            }
        }
        return t;
    }

    BarChart chart() const {
        BarChart ch;
        ch.title = "kdrt-bench table: render time per scene (ms, log scale)";
        ch.subtitle = {machine_info().cpu_model + ", " + std::to_string(machine_info().logical_cpus) + " CPUs; " +
                           machine_info().opencl.front(),
                       machine_info().date + "; " + std::to_string(opt_.width) + "x" + std::to_string(opt_.height) +
                           ", depth " + std::to_string(opt_.max_depth) + ", median of " + std::to_string(opt_.runs) +
                           (opt_.quick ? " (--quick)" : "") + "; hollow bars: more than shown"};
        ch.y_label = "ms";
        for (const NamedScene& s : scenes_) ch.groups.push_back(s.name);
        for (std::size_t d = 0; d < devices_.size(); ++d) {
            std::vector<std::size_t> idx;
            for (std::size_t r = 0; r < rows_.size(); ++r)
                if (rows_[r].device == devices_[d]) idx.push_back(r);
            for (std::size_t k = 0; k < idx.size(); ++k) {
                ChartSeries se;
                se.label = "kdrt " + rows_[idx[k]].label();
                se.color = series_color(d == 0 ? 0 : d == 1 ? 1 : 2, static_cast<int>(k), static_cast<int>(idx.size()));
                for (const Cell& c : cells_[idx[k]]) {
                    const bool over = c.status == Status::OverLimit;
                    se.values.push_back(c.status == Status::Timed ? c.render_ms : over ? opt_.none_limit_s * 1000.0 : kNaN);
                    se.lower_bound.push_back(over);
                }
                ch.series.push_back(se);
            }
        }
        if (embree_enabled()) {
            ChartSeries se;
            se.label = "Embree 3 (same shading)";
            se.color = series_color(4, 0, 1);
            for (const EmbreeCell& e : embree_) se.values.push_back(e.status == Status::Timed ? e.render_ms : kNaN);
            ch.series.push_back(se);
        }
        const auto& study = study_rows();
        for (std::size_t k = 0; k < study.size(); ++k) {
            ChartSeries se;
            se.label = study[k].label + " (2016)";
            se.color = series_color(3, static_cast<int>(k), static_cast<int>(study.size()));
            for (const NamedScene& s : scenes_) {
                se.values.push_back(study_ms(study[k], s.name));
                const auto& names = study_scene_names();
                const auto it = std::find(names.begin(), names.end(), s.name);
                se.lower_bound.push_back(it != names.end() &&
                                         study[k].lower_bound[static_cast<std::size_t>(it - names.begin())]);
            }
            ch.series.push_back(se);
        }
        return ch;
    }

    void write_outputs() const {
        std::filesystem::create_directories(opt_.out);
        const BarChart ch = chart();
        const bool text = draw_bar_chart(opt_.out / "table.png", ch);

        std::ostringstream md;
        md << markdown_preamble("kdrt-bench table") << settings_text() << "\n\n";
        md << "## Render time, ms (median)\n\n" << render_table().markdown() << "\n";
        md << "## Throughput, Mrays/s (all rays traced / render time)\n\n"
           << per_row_table([](const Cell& c) { return fmt(c.mrays(), 2); }).markdown() << "\n";
        md << "## Rays traced per render (camera + shadow + secondary)\n\n"
           << per_row_table([](const Cell& c) { return std::to_string(c.rays.total()); }).markdown() << "\n";
        md << "## Tree build, ms (median; includes the ropes)\n\n"
           << per_row_table([](const Cell& c) { return fmt_ms(c.build_ms); }, [](const RowConfig& r) { return r.has_tree; })
                  .markdown()
           << "\n";
        if (std::any_of(rows_.begin(), rows_.end(), [](const RowConfig& r) { return r.opencl(); })) {
            md << "## Kernel compile, ms: cold (empty kernel cache and POCL_CACHE_DIR, in a child process) / "
                  "cached (median of the timed runs)\n\n"
               << per_row_table([](const Cell& c) { return fmt_ms(c.cold_compile_ms) + " / " + fmt_ms(c.cached_compile_ms); },
                                [](const RowConfig& r) { return r.opencl(); })
                      .markdown()
               << "\n";
        }
        md << "## Validation: camera id maps against cpu/none\n\n"
              "Ids may differ only at silhouette pixels or where two distances agree to 1e-4; anything else fails "
              "and the configuration is not timed.\n\n";
        {
            TextTable t;
            t.header = scene_header({"device", "traversal", "tree"});
            for (std::size_t r = 0; r < rows_.size(); ++r) {
                std::vector<std::string> row{rows_[r].device, to_string(rows_[r].traversal), rows_[r].tree_label()};
                for (const Cell& c : cells_[r]) row.push_back(c.check.pixels ? c.check.summary() : status_text(c.status, c.note));
                t.add(row);
            }
            if (embree_enabled()) {
                std::vector<std::string> row{"Embree", "BVH", "Embree"};
                for (const EmbreeCell& e : embree_) row.push_back(e.check.summary());
                t.add(row);
            }
            md << t.markdown() << "\n";
        }
        if (embree_enabled()) {
            md << "## kdrt against Embree, same run\n\n"
                  "Whole render (tracing and shading, tree/BVH build excluded) of the fastest kdrt configuration per "
                  "device against Embree 3 under the same shading contract (bench/whitted_renderer.h over "
                  "rtcIntersect1/rtcOccluded1). A ratio above 1 means kdrt is slower.\n\n"
               << embree_ratio_table().markdown() << "\n";
        }
        md << "## Chart\n\n![render times](table.png)\n\n";
        md << "Bars per scene, log scale, in this order" << (text ? "" : " (the PNG has no text: no font was found)")
           << ":\n\n";
        for (const ChartSeries& s : ch.series) {
            char rgb[16];
            std::snprintf(rgb, sizeof rgb, "#%02x%02x%02x", static_cast<int>(s.color[0] * 255),
                          static_cast<int>(s.color[1] * 255), static_cast<int>(s.color[2] * 255));
            md << "- `" << rgb << "` " << s.label << "\n";
        }
        md << "\nThe study's rows (i7-2670QM / GeForce GT 540M, 2016) are context, not a yardstick: its scenes are "
              "only described in words.\n";
        write_text_file(opt_.out / "table.md", md.str());
        write_text_file(opt_.out / "table.csv", csv_preamble("kdrt-bench table") + csv_table().csv());
        std::fprintf(stderr, "kdrt-bench table: wrote %s, %s and %s\n", (opt_.out / "table.md").c_str(),
                     (opt_.out / "table.csv").c_str(), (opt_.out / "table.png").c_str());
    }

    TableOptions opt_;
    TempDir scratch_;
    std::filesystem::path kernel_cache_;
    std::vector<NamedScene> scenes_;
    std::vector<std::string> devices_;
    std::vector<RowConfig> rows_;
    std::vector<std::vector<Cell>> cells_;  // [row][scene]
    std::vector<EmbreeCell> embree_;        // [scene]
    std::optional<IdMap> reference_;
    std::optional<Image> kdrt_image_;       // cpu stack sah, for Embree's RMSE
    ColdCompileCache cold_;
};

}  // namespace

void parse_size(const std::string& text, int& width, int& height) {
    const auto x = text.find('x');
    try {
        if (x == std::string::npos) throw std::invalid_argument("no x");
        std::size_t a = 0, b = 0;
        width = std::stoi(text.substr(0, x), &a);
        height = std::stoi(text.substr(x + 1), &b);
        if (a != x || b != text.size() - x - 1 || width < 1 || height < 1 || width > 16384 || height > 16384)
            throw std::invalid_argument("range");
    } catch (const std::exception&) {
        throw Error(ErrorCode::InvalidArgument, "--size '" + text + "': expected WxH, e.g. 500x500");
    }
}

std::vector<std::string> all_device_ids() {
    std::vector<std::string> ids;
    for (const DeviceInfo& d : list_devices()) ids.push_back(d.id);
    return ids;
}

int run_table(const TableOptions& options) {
    if (options.runs < 1) throw Error(ErrorCode::InvalidArgument, "--runs must be at least 1");
    machine_info();  // the date and load at the start
    if (options.quick) retry_budget_s = 0.0;  // a smoke test does not wait for a quiet machine
    return TableRun(options).run();
}

}  // namespace kdrt::bench
