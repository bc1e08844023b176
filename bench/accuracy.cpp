#include "accuracy.h"

#include "machine_info.h"
#include "report.h"
#include "scatter_plot.h"
#include "stats.h"

#include <kdrt/error.h>
#include <kdrt/render.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>

namespace kdrt::bench {

namespace {

// One point of the study: a name and what it changes from the default.
struct Setting {
    std::string name;
    std::function<void(RenderOptions&)> apply;
};

std::vector<Setting> settings() {
    return {
        {"default", [](RenderOptions&) {}},
        {"double", [](RenderOptions& o) { o.commit.accuracy.precision = Precision::Double; }},
        {"moller", [](RenderOptions& o) { o.commit.accuracy.triangle_test = TriangleTest::MollerTrumbore; }},
        {"textbook-sphere", [](RenderOptions& o) { o.commit.accuracy.sphere_test = SphereTest::Textbook; }},
        {"fixed-eps-1e-4", [](RenderOptions& o) { o.commit.accuracy.self_intersection = SelfIntersection::FixedEpsilon; }},
        {"all-cheap", [](RenderOptions& o) {
             o.commit.accuracy.triangle_test = TriangleTest::MollerTrumbore;
             o.commit.accuracy.sphere_test = SphereTest::Textbook;
             o.commit.accuracy.self_intersection = SelfIntersection::FixedEpsilon;
         }},
        {"depth-1", [](RenderOptions& o) { o.frame.max_depth = 1; }},
        {"depth-2", [](RenderOptions& o) { o.frame.max_depth = 2; }},
        {"depth-4", [](RenderOptions& o) { o.frame.max_depth = 4; }},
        {"depth-8", [](RenderOptions& o) { o.frame.max_depth = 8; }},
        {"spp-4", [](RenderOptions& o) { o.frame.samples = 4; }},
        {"spp-16", [](RenderOptions& o) { o.frame.samples = 16; }},
        {"median-tree", [](RenderOptions& o) {
             o.commit.tree.builder = KdBuilderKind::Median;
             o.commit.tree.max_depth = 10;
         }},
    };
}

struct Errors {
    double rmse = 0.0, psnr = 0.0, max_error = 0.0;
};

// On the displayed values: clamped to [0, 1] as an 8-bit file would show them.
Errors image_errors(const Image& ref, const Image& img) {
    Errors e;
    double sum = 0.0;
    for (std::size_t i = 0; i < ref.rgb.size(); ++i) {
        const double a = std::clamp(static_cast<double>(ref.rgb[i]), 0.0, 1.0);
        const double b = std::clamp(static_cast<double>(img.rgb[i]), 0.0, 1.0);
        sum += (a - b) * (a - b);
        e.max_error = std::max(e.max_error, std::abs(a - b));
    }
    e.rmse = std::sqrt(sum / static_cast<double>(std::max<std::size_t>(1, ref.rgb.size())));
    e.psnr = e.rmse > 0.0 ? 20.0 * std::log10(1.0 / e.rmse) : INFINITY;
    return e;
}

double id_differ_share(const RenderResult& ref, const RenderResult& r) {
    std::size_t differ = 0;
    for (std::size_t i = 0; i < ref.ids.size(); ++i) differ += ref.ids[i] != r.ids[i];
    return ref.ids.empty() ? 0.0 : static_cast<double>(differ) / static_cast<double>(ref.ids.size());
}

struct Row {
    std::string scene, device, setting;
    double ms = 0.0;
    Errors err;
    double id_share = 0.0;
    bool pareto = false;
};

// Marks the settings that nothing beats both in time and in error.
void mark_pareto(std::vector<Row*>& rows) {
    for (Row* a : rows) {
        a->pareto = true;
        for (const Row* b : rows)
            if (b != a && b->ms <= a->ms && b->err.rmse <= a->err.rmse && (b->ms < a->ms || b->err.rmse < a->err.rmse))
                a->pareto = false;
    }
}

}  // namespace

int run_accuracy(const AccuracyConfig& config) {
    std::vector<Row> rows;
    for (const NamedScene& ns : config.scenes) {
        RenderOptions base;
        base.frame.width = config.width;
        base.frame.height = config.height;
        base.frame.threads = 0;
        // The reference: C++ reference in double, the robust tests, full depth, many samples.
        RenderOptions ref_opt = base;
        ref_opt.device = "cpu";
        ref_opt.commit.accuracy.precision = Precision::Double;
        ref_opt.frame.samples = config.reference_samples;
        std::fprintf(stderr, "accuracy: %s: reference (%d spp)\n", ns.name.c_str(), config.reference_samples);
        const RenderResult reference = render(ns.scene, ref_opt);
        RenderOptions ref_ids = ref_opt;
        ref_ids.frame.samples = 1;
        ref_ids.frame.max_depth = 1;
        ref_ids.frame.want_ids = true;
        const RenderResult reference_ids = render(ns.scene, ref_ids);

        for (const std::string& device : config.devices) {
            std::vector<std::size_t> group;
            for (const Setting& s : settings()) {
                RenderOptions o = base;
                o.device = device;
                s.apply(o);
                std::fprintf(stderr, "accuracy: %s on %s: %s\n", ns.name.c_str(), device.c_str(), s.name.c_str());
                Row row;
                row.scene = ns.name;
                row.device = device;
                row.setting = s.name;
                try {
                    RenderResult r = render(ns.scene, o);  // warm-up: builds, compiles, caches
                    std::vector<double> ms;
                    for (int i = 0; i < config.runs; ++i) {
                        r = render(ns.scene, o);
                        ms.push_back(r.stats.render_ms);
                    }
                    row.ms = median(ms);
                    row.err = image_errors(reference.image, r.image);
                    RenderOptions id_opt = o;
                    id_opt.frame.samples = 1;
                    id_opt.frame.max_depth = 1;
                    id_opt.frame.want_ids = true;
                    row.id_share = id_differ_share(reference_ids, render(ns.scene, id_opt));
                } catch (const Error& e) {
                    std::fprintf(stderr, "accuracy: %s on %s, %s: %s\n", ns.name.c_str(), device.c_str(), s.name.c_str(),
                                 e.what());
                    continue;  // e.g. double on a device without fp64: left out of the table
                }
                group.push_back(rows.size());
                rows.push_back(row);
            }
            std::vector<Row*> g;
            for (std::size_t i : group) g.push_back(&rows[i]);
            mark_pareto(g);
        }
    }

    TextTable t;
    t.header = {"scene", "device", "setting", "render ms", "RMSE", "PSNR dB", "max error", "camera ids differ", "Pareto"};
    for (const Row& r : rows)
        t.add({r.scene, r.device, r.setting, fmt_ms(r.ms), fmt(r.err.rmse, 5), fmt(r.err.psnr, 1), fmt(r.err.max_error, 3),
               fmt(100.0 * r.id_share, 2) + "%", r.pareto ? "*" : ""});
    char what[200];
    std::snprintf(what, sizeof what, "%dx%d, reference: cpu double, watertight, careful, scale-aware, depth 15, %d spp",
                  config.width, config.height, config.reference_samples);
    write_text_file(config.out / "accuracy.csv", csv_preamble(std::string("kdrt-bench accuracy: ") + what) + t.csv());
    write_text_file(config.out / "accuracy.md",
                    markdown_preamble(std::string("kdrt-bench accuracy: ") + what) + "\n" + t.markdown() +
                        "\nPareto: * = no other setting on that scene and device is both faster and closer to the "
                        "reference. Errors on displayed values (clamped to [0, 1]).\n");

    ScatterPlot plot;
    plot.title = "kdrt: error against render time, per scene (Pareto front in red)";
    plot.subtitle = machine_lines();
    plot.x_label = "render time, ms (log)";
    plot.y_label = "RMSE (log)";
    for (const NamedScene& ns : config.scenes)
        for (const std::string& device : config.devices) {
            ScatterPanel panel;
            panel.title = ns.name + " on " + device;
            for (const Row& r : rows)
                if (r.scene == ns.name && r.device == device)
                    panel.points.push_back({r.setting, r.ms, r.err.rmse, r.pareto, {0.2f, 0.4f, 0.8f}});
            if (!panel.points.empty()) plot.panels.push_back(std::move(panel));
        }
    draw_scatter_plot(config.out / "accuracy.png", plot);
    std::cout << t.markdown();
    return 0;
}

}  // namespace kdrt::bench
