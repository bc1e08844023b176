#include "pocl_profile.h"

#include "id_check.h"
#include "interference.h"
#include "machine_info.h"
#include "report.h"
#include "scene_set.h"
#include "stats.h"
#include "subprocess.h"

#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/render.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <sstream>

namespace kdrt::bench {

namespace {

// A table row: a trace kernel's levels 1 and 2 apart, deeper levels together.
std::string row_name(const CommandTime& c) {
    if (c.level == 0) return c.command;
    if (c.level <= 2) return c.command + ", level " + std::to_string(c.level) + (c.level == 1 ? " (camera rays)" : "");
    return c.command + ", levels 3+";
}

bool is_trace(const std::string& row) { return row.rfind("trace_", 0) == 0; }

struct Run {
    std::map<std::string, std::pair<double, double>> rows;  // name -> (count, device ms)
    double render_ms = kNaN, busy_ms = kNaN;
};

Run profiled_run(const Scene& scene, const RenderOptions& o) {
    const RenderResult r = render(scene, o);
    Run run;
    run.render_ms = r.stats.render_ms;
    run.busy_ms = r.stats.opencl.device_busy_ms;
    for (const CommandTime& c : r.stats.opencl.command_times) {
        auto& [count, ms] = run.rows[row_name(c)];
        count += static_cast<double>(c.count);
        ms += c.device_ms;
    }
    return run;
}

std::string opencl_device(const std::string& asked, unsigned& compute_units) {
    for (const DeviceInfo& d : list_devices())
        if (d.id != "cpu" && (asked.empty() || d.id == asked)) {
            compute_units = d.compute_units;
            return d.id;
        }
    throw Error(ErrorCode::Device, asked.empty() ? "pocl-profile: no OpenCL device" : "pocl-profile: no device " + asked);
}

}  // namespace

int run_pocl_profile(const PoclProfileOptions& opt) {
    if (opt.runs < 1) throw Error(ErrorCode::InvalidArgument, "--runs must be at least 1");
    machine_info();
    unsigned units = 0;
    const std::string device = opencl_device(opt.device, units);
    const std::vector<NamedScene> scenes = load_scenes(opt.scenes, opt.scenes_dir);
    const double opencl_triangle_cost = Device::open(device).triangle_cost();
    const double cpu_triangle_cost = Device::open("cpu").triangle_cost();
    TempDir scratch("kdrt-bench-pocl-profile");
    const std::filesystem::path kernels = scratch.fresh("kernels");

    std::ostringstream md;
    md << markdown_preamble("kdrt-bench pocl-profile") << opt.width << "x" << opt.height << ", ray depth "
       << opt.max_depth << ", " << opt.traversal << " traversal over the SAH tree, " << opt.precision << ", on "
       << device << " (" << units << " compute units). Device ms: OpenCL event profiling "
       << "(CL_PROFILING_COMMAND_START to _END), median of " << opt.runs
       << " runs; share: of the profiled render time. `host` is render time minus the device's busy time (launches, "
          "the blocking counter reads after each launch, idle). The reference is the C++ renderer (cpu device) on "
       << units << " threads and the same traversal, twice: on the SAH tree " << device
       << " builds (its triangle cost, Device::triangle_cost: " << fmt(opencl_triangle_cost, 1)
       << "), the same tree, and on the tree the cpu device builds for itself (" << fmt(cpu_triangle_cost, 1)
       << "), what a user of each device gets. Profiled, unprofiled and reference runs interleaved.\n\n";
    TextTable csv;
    csv.header = {"scene", "row", "count", "device_ms", "ms_per_count", "share"};
    for (const NamedScene& s : scenes) {
        RenderOptions o;
        o.device = device;
        o.frame.width = opt.width;
        o.frame.height = opt.height;
        o.frame.max_depth = opt.max_depth;
        o.frame.samples = 1;
        o.commit.traversal = traversal_from_string(opt.traversal);
        o.commit.accuracy.precision = precision_from_string(opt.precision);
        o.commit.kernel_cache_dir = kernels;
        RenderOptions ref = o;
        ref.device = "cpu";
        ref.frame.threads = static_cast<int>(units);
        RenderOptions same = ref;  // the C++ twin on the OpenCL device's tree
        same.commit.tree.intersection_cost = opencl_triangle_cost;
        RenderOptions prof = o;
        prof.frame.opencl.profile_commands = true;

        // Validation (and warm-up: kernel compile, tree build), against both references.
        ref.frame.want_ids = same.frame.want_ids = o.frame.want_ids = true;
        const RenderResult ro = render(s.scene, o);
        bool valid = true;
        for (const RenderOptions* r : {&ref, &same}) {
            const RenderResult rr = render(s.scene, *r);
            const IdCheck check = compare_ids(IdMap{rr.image.width, rr.image.height, rr.ids, rr.hit_t},
                                              IdMap{ro.image.width, ro.image.height, ro.ids, ro.hit_t});
            if (!check.ok()) {
                md << "## " << s.name << "\n\nFAILED: " << device << "'s id map against the reference on "
                   << (r == &same ? "the same tree" : "the cpu device's tree") << ": " << check.summary() << "\n\n";
                valid = false;
                break;
            }
        }
        ref.frame.want_ids = same.frame.want_ids = o.frame.want_ids = false;
        if (!valid) continue;
        profiled_run(s.scene, prof);  // warm-up of the profiled queue

        std::vector<Run> runs;
        std::vector<double> plain_ms, ref_ms, same_ms;
        const Interference others;
        for (int r = 0; r < opt.runs; ++r) {
            runs.push_back(profiled_run(s.scene, prof));
            plain_ms.push_back(render(s.scene, o).stats.render_ms);
            ref_ms.push_back(render(s.scene, ref).stats.render_ms);
            same_ms.push_back(render(s.scene, same).stats.render_ms);
        }
        const double load = others.other_cores();

        std::vector<std::string> names;  // first run's order, then any later newcomer
        for (const Run& run : runs)
            for (const auto& [name, v] : run.rows)
                if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
        std::vector<double> render_ms, busy_ms, trace_ms;
        for (const Run& run : runs) {
            render_ms.push_back(run.render_ms);
            busy_ms.push_back(run.busy_ms);
            double t = 0.0;
            for (const auto& [name, v] : run.rows)
                if (is_trace(name)) t += v.second;
            trace_ms.push_back(t);
        }
        const double total = median(render_ms), busy = median(busy_ms), trace = median(trace_ms);
        const double reference = median(ref_ms), same_tree = median(same_ms), plain = median(plain_ms);

        TextTable t;
        t.header = {"command", "count", "device ms", "ms each", "share"};
        auto add = [&](const std::string& name, double count, double ms) {
            const std::string each = count > 0 ? fmt(ms / count, 3) : "-";
            t.add({name, count > 0 ? fmt(count, 0) : "-", fmt_ms(ms), each, fmt(100.0 * ms / total, 1) + " %"});
            csv.add({s.name, name, fmt(count, 0), fmt(ms, 3), count > 0 ? fmt(ms / count, 4) : "", fmt(ms / total, 4)});
        };
        for (const std::string& name : names) {
            std::vector<double> counts, ms;
            for (const Run& run : runs) {
                auto it = run.rows.find(name);
                counts.push_back(it == run.rows.end() ? 0.0 : it->second.first);
                ms.push_back(it == run.rows.end() ? 0.0 : it->second.second);
            }
            add(name, median(counts), median(ms));
        }
        add("device busy (all commands)", 0, busy);
        add("host (render - device busy)", 0, total - busy);
        add("render (profiled)", 0, total);
        md << "## " << s.name << "\n\n"
           << t.markdown() << "\nRender " << fmt_ms(plain) << " ms unprofiled, " << fmt_ms(total)
           << " ms profiled; trace kernels " << fmt_ms(trace) << " ms. C++ reference on " << units
           << " threads: " << fmt_ms(same_tree) << " ms on the same tree, " << device << " / reference "
           << fmt_ratio(plain / same_tree) << " (render), trace kernels / reference " << fmt_ratio(trace / same_tree)
           << "; " << fmt_ms(reference) << " ms on the cpu device's own tree, " << device << " / reference "
           << fmt_ratio(plain / reference) << ". Others kept " << fmt(load, 2) << " cores busy.\n\n";
        std::fprintf(stderr,
                     "%s: render %.1f ms (profiled %.1f, busy %.1f, trace %.1f), reference %.1f ms on the same tree, "
                     "%.1f ms on its own\n",
                     s.name.c_str(), plain, total, busy, trace, same_tree, reference);
        csv.add({s.name, "render unprofiled", "", fmt(plain, 3), "", ""});
        csv.add({s.name, "reference cpu same tree", "", fmt(same_tree, 3), "", ""});
        csv.add({s.name, "reference cpu", "", fmt(reference, 3), "", ""});
    }
    write_report(opt.out, "pocl_profile", "pocl-profile", md.str(), csv);
    return 0;
}

}  // namespace kdrt::bench
