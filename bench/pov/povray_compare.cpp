#include "pov/povray_compare.h"

#include "machine_info.h"
#include "pov/povray_export.h"
#include "report.h"
#include "scene_set.h"
#include "startup.h"
#include "stats.h"
#include "subprocess.h"
#include "table.h"

#include <kdrt/error.h>
#include <kdrt/image.h>
#include <kdrt/scene_loader.h>

#include <cstdio>
#include <limits>
#include <sstream>

namespace kdrt::bench {

namespace {

// Median wall time of `runs` runs after one warm-up; NaN (and `error`) if any run fails.
double time_process(const ChildOptions& o, int runs, std::string& error) {
    std::vector<double> ms;
    for (int r = -1; r < runs; ++r) {
        const ChildResult c = run_child(o);
        if (c.exit_code != 0) {
            error = o.argv.front() + " exited with " + std::to_string(c.exit_code);
            return kNaN;
        }
        if (r >= 0) ms.push_back(c.wall_ms);
    }
    return median(ms);
}

std::string povray_version(const std::filesystem::path& povray) {
    ChildOptions o;
    o.argv = {povray.string(), "--version"};
    o.merge_stderr = true;
    const ChildResult r = run_child(o);
    std::istringstream in(r.out);
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("POV-Ray", 0) == 0) return line;
    return "POV-Ray (version unknown)";
}

}  // namespace

int run_povray_export(const std::filesystem::path& scene, const std::filesystem::path& out, int width, int height) {
    write_povray(load_scene(scene), out, width, height);
    std::fprintf(stderr, "kdrt-bench povray: wrote %s\n", out.c_str());
    return 0;
}

int run_povray_compare(const PovrayCompareOptions& opt) {
    if (opt.runs < 1) throw Error(ErrorCode::InvalidArgument, "--runs must be at least 1");
    machine_info();
    const std::filesystem::path povray = find_program(opt.povray.string());
    if (povray.empty()) throw Error(ErrorCode::Io, opt.povray.string() + ": not found (scripts/install-deps.sh --bench installs POV-Ray)");
    const std::filesystem::path kdrt = locate_kdrt_render(opt.kdrt_render);
    std::vector<std::string> devices = opt.devices;
    if (devices.empty()) {
        for (const std::string& d : all_device_ids())
            if (d != "cpu") devices.push_back(d);
        devices.push_back("cpu");
    }
    const std::vector<NamedScene> scenes = load_scenes(opt.scenes, opt.scenes_dir);
    const std::filesystem::path dir = std::filesystem::absolute(opt.out / "pov");
    std::filesystem::create_directories(dir);
    TempDir scratch("kdrt-bench-povray");
    const std::filesystem::path kernels = scratch.fresh("kernels"), pocl = scratch.fresh("pocl");
    const std::string version = povray_version(povray);

    TextTable t, csv;
    t.header = {"scene", "POV-Ray ms", "POV-Ray 1x1 ms"};
    for (const std::string& d : devices)
        t.header.insert(t.header.end(), {"kdrt-render " + d + " ms", "kdrt-render " + d + " 1x1 ms",
                                         "POV-Ray / kdrt " + d, "same, net of 1x1"});
    t.header.push_back("image RMSE POV-Ray vs kdrt (orientation only)");
    csv.header = {"scene", "program", "device", "process_ms", "process_1x1_ms", "povray_over_this",
                  "povray_over_this_net_of_1x1", "status"};
    const std::string size = std::to_string(opt.width) + "x" + std::to_string(opt.height);
    // POV-Ray may only write in the current directory (Debian's povray.conf): it runs in `dir`.
    auto povray_run = [&](const std::string& pov, const std::string& png, int w, int h) {
        ChildOptions o;
        o.argv = {povray.string(), "+I" + pov, "+O" + png, "+W" + std::to_string(w), "+H" + std::to_string(h), "-D",
                  "-A", "+FN", "-GA", "File_Gamma=1.0"};
        o.cwd = dir;
        o.capture_stdout = false;
        return o;
    };
    auto kdrt_run = [&](const NamedScene& s, const std::string& d, const std::filesystem::path& png, int w, int h) {
        ChildOptions o;
        o.argv = {kdrt.string(), s.path.string(), "-o", png.string(), "--device", d, "--width", std::to_string(w),
                  "--height", std::to_string(h), "--kernel-cache", kernels.string(), "--quiet"};
        o.env = {{"POCL_CACHE_DIR", pocl.string()}};
        o.capture_stdout = false;
        return o;
    };
    for (const NamedScene& s : scenes) {
        const std::string pov = s.name + ".pov", pov_png = s.name + "-povray.png";
        write_povray(s.scene, dir / pov, opt.width, opt.height);
        std::string pov_error;
        const double pov_ms = time_process(povray_run(pov, pov_png, opt.width, opt.height), opt.runs, pov_error);
        const double pov_1 = time_process(povray_run(pov, s.name + "-povray-1x1.png", 1, 1), opt.runs, pov_error);
        csv.add({s.name, "povray", "", fmt(pov_ms, 3), fmt(pov_1, 3), "1", "1", pov_error});
        std::vector<std::string> row{s.name, pov_error.empty() ? fmt_ms(pov_ms) : pov_error, fmt_ms(pov_1)};
        std::string rmse = "-";
        for (const std::string& d : devices) {
            const std::string tag = s.name + "-kdrt-" + (d == "cpu" ? std::string("cpu") : "opencl");
            const std::filesystem::path png = dir / (tag + ".png");
            std::string error;
            // The warm-ups fill the kernel caches.
            const double ms = time_process(kdrt_run(s, d, png, opt.width, opt.height), opt.runs, error);
            const double ms_1 = time_process(kdrt_run(s, d, dir / (tag + "-1x1.png"), 1, 1), opt.runs, error);
            const double ratio = pov_ms / ms;
            // Below the noise (a tiny image) the differences can be <= 0: no net figure then.
            const double net = pov_ms > pov_1 && ms > ms_1 ? (pov_ms - pov_1) / (ms - ms_1) : kNaN;
            row.insert(row.end(), {error.empty() ? fmt_ms(ms) : error, fmt_ms(ms_1), fmt_ratio(ratio), fmt_ratio(net)});
            csv.add({s.name, "kdrt-render", d, fmt(ms, 3), fmt(ms_1, 3), fmt(ratio, 4), fmt(net, 4), error});
            if (rmse == "-" && error.empty() && pov_error.empty()) {
                try {
                    rmse = fmt(image_rmse(read_image(dir / pov_png), read_image(png)), 4);
                } catch (const std::exception&) {
                }
            }
            std::fprintf(stderr, "%s: POV-Ray %s ms (1x1: %s), kdrt-render %s %s ms (1x1: %s): POV-Ray / kdrt = %s, net %s\n",
                         s.name.c_str(), fmt_ms(pov_ms).c_str(), fmt_ms(pov_1).c_str(), d.c_str(), fmt_ms(ms).c_str(),
                         fmt_ms(ms_1).c_str(), fmt_ratio(ratio).c_str(), fmt_ratio(net).c_str());
        }
        row.push_back(rmse);
        t.add(row);
    }

    std::ostringstream md;
    md << markdown_preamble("kdrt-bench povray-compare") << "- POV-Ray: " << version << "\n\n"
       << "Whole processes, start to PNG written, " << size << ", median of " << opt.runs
       << " runs after a warm-up. POV-Ray: `povray +ISCENE.pov +OSCENE-povray.png +W" << opt.width << " +H"
       << opt.height
       << " -D -A +FN -GA File_Gamma=1.0` (no anti-aliasing, no display, all cores, its default adaptive depth "
          "control), on the scene written by `kdrt-bench povray` (bench/pov/). kdrt-render: `kdrt-render SCENE.json "
          "-o OUT.png --device D --kernel-cache DIR` with the kernel cache (and PoCL's) filled by the warm-up; the "
          "tree is built in every run. A ratio above 1 means kdrt is faster. The 1x1 runs (same scene, one pixel) "
          "measure what a process costs before it traces: start-up, parsing, tree or bounding-hierarchy build, "
          "writing the PNG; \"net of 1x1\" compares the rest, (POV-Ray - its 1x1) / (kdrt - its 1x1), the "
          "tracing itself. The pictures are similar, not equal "
          "(POV-Ray lets light through glass for shadows, scales a transparent surface's diffuse term, and "
          "samples pixels its own way); the RMSE column is for orientation only. The .pov files and both images "
          "are in "
       << dir.string() << ".\n\n"
       << t.markdown();
    write_report(opt.out, "povray", "povray-compare", md.str(), csv);
    return 0;
}

}  // namespace kdrt::bench
