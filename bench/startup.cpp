#include "startup.h"

#include "machine_info.h"
#include "report.h"
#include "scene_set.h"
#include "stats.h"
#include "subprocess.h"
#include "table.h"

#include <kdrt/error.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <limits>
#include <sstream>

namespace kdrt::bench {

namespace {

struct Launch {
    bool ok = false;
    std::string error;
    double wall_ms = kNaN, line_ms = kNaN, first_launch_ms = kNaN;
    double build_ms = kNaN, compile_ms = kNaN, render_ms = kNaN;
    bool cache_hit = false;
    double rss_mib = kNaN;
};

struct Summary {
    double wall_ms = kNaN, first_launch_ms = kNaN, build_ms = kNaN, compile_ms = kNaN, render_ms = kNaN, rss_mib = kNaN;
    std::string status;  // empty when all runs succeeded
    bool cache_hits = true;
};

Launch launch(const std::filesystem::path& exe, const NamedScene& scene, const std::string& device,
              const std::filesystem::path& kernels, const std::filesystem::path& pocl) {
    ChildOptions o;
    o.argv = {exe.string(), scene.path.string(), "--device", device, "--stats-json", "--quiet", "--kernel-cache",
              kernels.string()};
    o.env = {{"POCL_CACHE_DIR", pocl.string()}};
    o.timeout_s = 600.0;
    const ChildResult r = run_child(o);
    Launch l;
    l.wall_ms = r.wall_ms;
    l.line_ms = r.first_line_ms;
    l.rss_mib = r.max_rss_kib / 1024.0;
    if (r.exit_code != 0) {
        l.error = "kdrt-render exited with " + std::to_string(r.exit_code);
        return l;
    }
    try {
        const auto j = nlohmann::json::parse(r.out);
        l.build_ms = j.at("build_ms").get<double>();
        l.compile_ms = j.at("compile_ms").get<double>();
        l.render_ms = j.at("render_ms").get<double>();
        l.cache_hit = j.at("kernel_cache_hit").get<bool>();
        l.first_launch_ms = l.line_ms - l.render_ms;
        l.ok = true;
    } catch (const std::exception& e) {
        l.error = std::string("unreadable --stats-json output: ") + e.what();
    }
    return l;
}

Summary summarise(const std::vector<Launch>& runs) {
    Summary s;
    std::vector<double> wall, first, build, compile, render, rss;
    for (const Launch& l : runs) {
        if (!l.ok) {
            s.status = l.error;
            continue;
        }
        wall.push_back(l.wall_ms);
        first.push_back(l.first_launch_ms);
        build.push_back(l.build_ms);
        compile.push_back(l.compile_ms);
        render.push_back(l.render_ms);
        rss.push_back(l.rss_mib);
        s.cache_hits = s.cache_hits && l.cache_hit;
    }
    s.wall_ms = median(wall);
    s.first_launch_ms = median(first);
    s.build_ms = median(build);
    s.compile_ms = median(compile);
    s.render_ms = median(render);
    s.rss_mib = median(rss);
    return s;
}

}  // namespace

std::filesystem::path locate_kdrt_render(const std::filesystem::path& given) {
    if (!given.empty()) {
        const std::filesystem::path p = find_program(given.string());
        if (p.empty()) throw Error(ErrorCode::Io, given.string() + ": no such program");
        return p;
    }
    std::vector<std::filesystem::path> candidates;
#ifdef KDRT_BENCH_KDRT_RENDER
    candidates.emplace_back(KDRT_BENCH_KDRT_RENDER);
#endif
    const std::filesystem::path self = self_executable();
    if (!self.empty()) {
        candidates.push_back(self.parent_path().parent_path() / "apps" / "kdrt-render" / "kdrt-render");
        candidates.push_back(self.parent_path() / "kdrt-render");
    }
    for (const auto& c : candidates) {
        std::error_code ec;
        if (std::filesystem::is_regular_file(c, ec)) return c;
    }
    const std::filesystem::path p = find_program("kdrt-render");
    if (p.empty()) throw Error(ErrorCode::Io, "kdrt-render not found next to kdrt-bench nor in $PATH: give --kdrt-render");
    return p;
}

int run_startup(const StartupOptions& opt) {
    if (opt.runs < 1) throw Error(ErrorCode::InvalidArgument, "--runs must be at least 1");
    machine_info();
    const std::filesystem::path exe = locate_kdrt_render(opt.kdrt_render);
    std::vector<std::string> devices = opt.devices;
    if (devices.empty()) {
        for (const std::string& d : all_device_ids())
            if (d != "cpu") devices.push_back(d);
        devices.push_back("cpu");
    }
    const std::vector<NamedScene> scenes = load_scenes(opt.scenes, opt.scenes_dir);
    TempDir scratch("kdrt-bench-startup");

    // The floor: a process that loads the same shared libraries and does nothing (kdrt-render --version).
    std::vector<double> floor_ms;
    for (int r = -1; r < std::max(opt.runs, 3); ++r) {
        ChildOptions o;
        o.argv = {exe.string(), "--version"};
        const ChildResult c = run_child(o);
        if (r >= 0 && c.exit_code == 0) floor_ms.push_back(c.wall_ms);
    }
    const double floor_median = median(floor_ms);
    std::fprintf(stderr, "kdrt-render --version: %s ms (process start, dynamic linking, exit)\n", fmt_ms(floor_median).c_str());

    TextTable t, csv;
    t.header = {"scene", "device", "cold: start to first launch ms", "cold: compile ms", "cold: process ms",
                "warm: start to first launch ms", "warm: compile ms", "warm: process ms", "tree build ms",
                "render ms", "peak RSS MiB"};
    csv.add({"-", "-", "kdrt-render --version", "", "", "", "", fmt(floor_median, 3), "", "", ""});
    csv.header = {"scene", "device", "state", "start_to_first_launch_ms", "build_ms", "compile_ms", "render_ms",
                  "process_ms", "peak_rss_mib", "kernel_cache_hit", "status"};
    for (const NamedScene& s : scenes)
        for (const std::string& d : devices) {
            std::vector<Launch> cold, warm;
            for (int r = 0; r < opt.runs; ++r) cold.push_back(launch(exe, s, d, scratch.fresh("kernels"), scratch.fresh("pocl")));
            const std::filesystem::path kernels = scratch.fresh("kernels"), pocl = scratch.fresh("pocl");
            launch(exe, s, d, kernels, pocl);  // fills both caches
            for (int r = 0; r < opt.runs; ++r) warm.push_back(launch(exe, s, d, kernels, pocl));
            const Summary c = summarise(cold), w = summarise(warm);
            const bool opencl = d != "cpu";
            t.add({s.name, d, fmt_ms(c.first_launch_ms), opencl ? fmt_ms(c.compile_ms) : "-", fmt_ms(c.wall_ms),
                   fmt_ms(w.first_launch_ms), opencl ? fmt_ms(w.compile_ms) : "-", fmt_ms(w.wall_ms), fmt_ms(w.build_ms),
                   fmt_ms(w.render_ms), fmt(w.rss_mib, 0)});
            for (const auto& [state, sum] : {std::pair<std::string, Summary>{"cold", c}, {"warm", w}})
                csv.add({s.name, d, state, fmt(sum.first_launch_ms, 3), fmt(sum.build_ms, 3), fmt(sum.compile_ms, 3),
                         fmt(sum.render_ms, 3), fmt(sum.wall_ms, 3), fmt(sum.rss_mib, 1),
                         opencl ? (sum.cache_hits ? "1" : "0") : "", sum.status});
            std::fprintf(stderr,
                         "%s %s: start to first launch %s ms cold (compile %s), %s ms warm (compile %s, cache %s); "
                         "process %s / %s ms; peak RSS %s MiB%s%s\n",
                         s.name.c_str(), d.c_str(), fmt_ms(c.first_launch_ms).c_str(), fmt_ms(c.compile_ms).c_str(),
                         fmt_ms(w.first_launch_ms).c_str(), fmt_ms(w.compile_ms).c_str(),
                         d == "cpu" ? "-" : w.cache_hits ? "hit" : "MISS", fmt_ms(c.wall_ms).c_str(), fmt_ms(w.wall_ms).c_str(),
                         fmt(w.rss_mib, 0).c_str(), c.status.empty() && w.status.empty() ? "" : ": ",
                         (c.status + " " + w.status).c_str());
        }

    std::ostringstream md;
    md << markdown_preamble("kdrt-bench startup") << "`" << exe.string()
       << " SCENE --device D --stats-json --quiet --kernel-cache DIR` as a child process, at the scene's size (500x500, "
          "depth 15). Cold: an empty kernel cache and an empty POCL_CACHE_DIR for every run; warm: both filled by a "
          "previous run. Start to first launch = (arrival of the --stats-json line, read through a pseudo-terminal) "
          "- render_ms: the render clock starts right before the first kernel launch (for the cpu device: the first "
          "ray) and the line is printed right after it stops, so this is process start to first launch within a few "
          "ms (it includes loading the scene, building the tree, selecting the device and building or loading the "
          "program). Peak RSS is wait4's ru_maxrss of the child; on PoCL the device memory is host memory and is "
          "included (a GPU's device memory would not be). Medians of "
       << opt.runs << " runs; tree build, render and RSS from the warm runs.\n\n"
       << "The floor: `kdrt-render --version` (process start, loading its shared libraries, exit) takes "
       << fmt_ms(floor_median) << " ms (median of " << floor_ms.size() << ").\n\n"
       << t.markdown();
    write_report(opt.out, "startup", "startup", md.str(), csv);
    return 0;
}

}  // namespace kdrt::bench
