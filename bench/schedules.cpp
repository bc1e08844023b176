#include "schedules.h"

#include "id_check.h"
#include "interference.h"
#include "machine_info.h"
#include "report.h"
#include "scene_set.h"
#include "stats.h"
#include "subprocess.h"
#include "table.h"

#include <kdrt/error.h>
#include <kdrt/render.h>

#include <cstdio>
#include <functional>
#include <limits>
#include <sstream>

namespace kdrt::bench {

namespace {

struct Variant {
    std::string name;
    std::function<void(RenderOptions&)> apply;
};

std::vector<Variant> variants() {
    return {
        {"default (persistent, specialised, tiles, default local size)", [](RenderOptions&) {}},
        {"schedule wavefront (queues per bounce level)", [](RenderOptions& o) { o.frame.opencl.schedule = Schedule::Wavefront; }},
        {"schedule plain", [](RenderOptions& o) { o.frame.opencl.schedule = Schedule::Plain; }},
        {"generic kernel (--features all)", [](RenderOptions& o) { o.commit.all_features = true; }},
        {"ray order rows", [](RenderOptions& o) { o.frame.opencl.ray_order = RayOrder::Rows; }},
        {"ray order morton", [](RenderOptions& o) { o.frame.opencl.ray_order = RayOrder::Morton; }},
        {"local size 8", [](RenderOptions& o) { o.frame.opencl.local_size = 8; }},
        {"local size 16", [](RenderOptions& o) { o.frame.opencl.local_size = 16; }},
        {"local size 32", [](RenderOptions& o) { o.frame.opencl.local_size = 32; }},
        {"local size 64", [](RenderOptions& o) { o.frame.opencl.local_size = 64; }},
    };
}

struct Figure {
    double ms = kNaN;
    std::string status;  // empty when timed
    int launches = 0;
    Quietness quiet;
};

std::string mark(const Figure& f) { return f.quiet.too_busy() ? " *" : ""; }

}  // namespace

int run_schedules(const SchedulesOptions& opt) {
    if (opt.runs < 1) throw Error(ErrorCode::InvalidArgument, "--runs must be at least 1");
    machine_info();
    if (opt.quick) retry_budget_s = 0.0;
    std::vector<std::string> devices = opt.devices;
    if (devices.empty())
        for (const std::string& d : all_device_ids())
            if (d != "cpu") devices.push_back(d);
    if (devices.empty()) throw Error(ErrorCode::Device, "schedules: no OpenCL device");
    const std::vector<NamedScene> scenes = load_scenes(opt.scenes, opt.scenes_dir);
    const std::vector<Variant> vars = variants();
    TempDir scratch("kdrt-bench-schedules");
    const std::filesystem::path kernels = scratch.fresh("kernels");

    // [device][variant][scene]
    std::vector<std::vector<std::vector<Figure>>> fig(
        devices.size(), std::vector<std::vector<Figure>>(vars.size(), std::vector<Figure>(scenes.size())));
    for (std::size_t d = 0; d < devices.size(); ++d)
        for (std::size_t s = 0; s < scenes.size(); ++s) {
            IdMap baseline;
            for (std::size_t v = 0; v < vars.size(); ++v) {
                RenderOptions o;
                o.device = devices[d];
                o.frame.width = opt.width;
                o.frame.height = opt.height;
                o.frame.max_depth = opt.max_depth;
                o.frame.samples = 1;
                o.commit.traversal = Traversal::Stack;
                o.commit.kernel_cache_dir = kernels;
                vars[v].apply(o);
                Figure& f = fig[d][v][s];
                try {
                    o.frame.want_ids = true;
                    const RenderResult warm = render(scenes[s].scene, o);
                    const IdMap ids{warm.image.width, warm.image.height, warm.ids, warm.hit_t};
                    if (v == 0) baseline = ids;
                    const IdCheck check = compare_ids(baseline, ids);
                    if (!check.ok()) {
                        f.status = "FAILED: " + check.summary();
                    } else {
                        o.frame.want_ids = false;
                        std::vector<double> ms;
                        f.quiet = measure_quietly([&] {
                            ms.clear();
                            for (int r = 0; r < opt.runs; ++r) {
                                const RenderResult res = render(scenes[s].scene, o);
                                ms.push_back(res.stats.render_ms);
                                f.launches = res.stats.opencl.launches;
                            }
                        });
                        f.ms = median(ms);
                    }
                } catch (const std::exception& e) {
                    f.status = std::string("error: ") + e.what();
                }
                std::fprintf(stderr, "%s %s %s: %s\n", scenes[s].name.c_str(), devices[d].c_str(), vars[v].name.c_str(),
                             f.status.empty() ? (fmt_ms(f.ms) + " ms, " + std::to_string(f.launches) + " launches").c_str()
                                              : f.status.c_str());
            }
        }

    std::ostringstream md;
    md << markdown_preamble("kdrt-bench schedules") << opt.width << "x" << opt.height << ", ray depth " << opt.max_depth
       << ", stack traversal over the SAH tree; render time in ms, median of " << opt.runs
       << " runs after a warm-up whose id map is checked against the default's; in brackets the change against the "
          "default (negative: faster). A variant measured while other processes kept more than "
       << kBusyCores << " cores busy is measured again (up to " << kMaxAttempts
       << " times); `*` marks a figure still taken under such load.\n\n";
    TextTable csv;
    csv.header = {"device", "variant", "scene", "render_ms", "vs_default", "launches", "other_cores", "status"};
    for (std::size_t d = 0; d < devices.size(); ++d) {
        TextTable t;
        t.header = {"variant"};
        for (const NamedScene& s : scenes) t.header.push_back(s.name);
        for (std::size_t v = 0; v < vars.size(); ++v) {
            std::vector<std::string> row{vars[v].name};
            for (std::size_t s = 0; s < scenes.size(); ++s) {
                const Figure& f = fig[d][v][s];
                const double base = fig[d][0][s].ms;
                const double change = (f.ms / base - 1.0) * 100.0;
                if (!f.status.empty()) row.push_back(f.status);
                else if (v == 0) row.push_back(fmt_ms(f.ms) + mark(f));
                else row.push_back(fmt_ms(f.ms) + " (" + (change >= 0 ? "+" : "") + fmt(change, 0) + "%)" + mark(f));
                csv.add({devices[d], vars[v].name, scenes[s].name, fmt(f.ms, 3), fmt(f.ms / base, 4),
                         std::to_string(f.launches), fmt(f.quiet.other_cores, 2), f.status});
            }
            t.add(row);
        }
        md << "## " << devices[d] << "\n\n" << t.markdown() << "\n";
    }
    write_report(opt.out, "schedules", "schedules", md.str(), csv);
    return 0;
}

}  // namespace kdrt::bench
