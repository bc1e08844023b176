// kdrt-bench: the measurements of BENCHMARKS.md that must call the library
// (the study's table, rays, builds, later frames: each beside Embree), and the
// helpers the scripts need (generated meshes as files, a scene in POV-Ray's
// language, an Embree-based kdrt-render). Each measurement writes OUT/NAME.json;
// bench/write_benchmarks.py turns those into tables. bench/run_all.sh runs it all.
// Exit codes: 0 success, 1 failure (with a message), 2 usage error.
#include "builds.h"
#include "common.h"
#include "frames.h"
#include "mesh_generator.h"
#include "povray_export.h"
#include "rays.h"
#include "table.h"

#ifdef KDRT_BENCH_HAVE_EMBREE
#include "embree_render.h"
#endif

#include <kdrt/scene_loader.h>
#include <kdrt/version.h>

#include <CLI/CLI.hpp>

#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <type_traits>

namespace {

using namespace kdrt::bench;

// Every command's options, and what the command line chose to do.
struct Commands {
    bool quick = false;
    std::filesystem::path out = "bench/results", scenes_dir;
    TableOptions table;
    std::string table_size, pov_scene, pov_out, pov_size, mesh_spec, mesh_dir, embree_scene, embree_out, embree_size;
    RaysOptions rays;
    BuildOptions build;
    FramesOptions frames;
    int embree_threads = 0;

    std::string name;              // a measurement's result file,
    std::function<Json()> measure;  // and the measurement;
    std::function<int()> helper;    // or a helper's action
};

CLI::App* measurement(CLI::App& app, const char* name, const char* what, Commands& c) {
    CLI::App* cmd = app.add_subcommand(name, what);
    cmd->add_flag("--quick", c.quick, "small sizes and one run: a smoke test, not a measurement");
    cmd->add_option("--out", c.out, "directory of the result (NAME.json)")->capture_default_str();
    cmd->add_option("--scenes-dir", c.scenes_dir, "where scene names are looked up (default: the source tree's scenes/)");
    return cmd;
}

// Sets `value` to the quick default when --quick is given and the option is not.
template <class T>
void quick_default(const CLI::App* cmd, const Commands& c, const char* option, T& value, std::type_identity_t<T> quick) {
    if (c.quick && cmd->count(option) == 0) value = quick;
}

// "--scenes none" gives no scenes.
std::vector<std::string> scene_list(std::vector<std::string> names) {
    if (names.size() == 1 && names.front() == "none") names.clear();
    return names;
}

void add_table(CLI::App& app, Commands& c) {
    TableOptions& o = c.table;
    CLI::App* cmd = measurement(app, "table", "the study's table: every device, traversal and tree, and Embree", c);
    cmd->add_option("--runs", o.runs, "rounds of renders (their median)")->capture_default_str();
    cmd->add_option("--size", c.table_size, "image size WxH (default 500x500)");
    cmd->add_option("--depth", o.max_depth, "ray depth")->capture_default_str();
    cmd->add_option("--threads", o.threads, "cpu device and Embree threads (0: all)");
    cmd->add_option("--devices", o.devices, "devices (default: all)")->delimiter(',');
    cmd->add_option("--scenes", o.scenes, "scenes (default: the study's five)")->delimiter(',');
    cmd->add_option("--none-limit-s", o.none_limit_s, "no brute force where a render would take longer")
        ->capture_default_str();
    cmd->callback([&c, cmd] {
        c.name = "table";
        c.measure = [&c, cmd] {
            TableOptions& t = c.table;
            t.scenes_dir = c.scenes_dir;
            quick_default(cmd, c, "--runs", t.runs, 1);
            quick_default(cmd, c, "--size", c.table_size, std::string("64x64"));
            quick_default(cmd, c, "--scenes", t.scenes, {"lens", "purple-wall"});
            if (!c.table_size.empty()) parse_size(c.table_size, t.width, t.height);
            return run_table(t);
        };
    });
}

void add_rays(CLI::App& app, Commands& c) {
    RaysOptions& o = c.rays;
    CLI::App* cmd = measurement(app, "rays", "ray throughput on meshes: kdrt's queries against Embree 1 and 16", c);
    cmd->add_option("--runs", o.runs, "rounds of passes (their median)")->capture_default_str();
    cmd->add_option("--threads", o.threads, "threads of every tracer (0: all)");
    cmd->add_option("--meshes", o.meshes, "torus:COUNT, heightfield:POINTS or layers:COUNT")
        ->delimiter(',')->capture_default_str();
    cmd->add_option("--accels", o.accels, "kdrt's structures: kd, bvh")->delimiter(',')->capture_default_str();
    cmd->add_option("--scenes", o.scenes, "scenes besides the meshes")->delimiter(',');
    cmd->add_option("--devices", o.devices, "kdrt devices (default: cpu and the first OpenCL device)")->delimiter(',');
    cmd->add_option("--camera-size", o.camera_size, "camera rays: N x N")->capture_default_str();
    cmd->add_option("--random-rays", o.random_rays, "incoherent rays")->capture_default_str();
    cmd->add_option("--embree-quality", o.embree_quality, "low, medium or high")->capture_default_str();
    cmd->add_flag("--embree-high,!--no-embree-high", o.embree_high,
                  "with --embree-quality medium, also rtcIntersect1 on Embree's high-quality (spatial-split) build")
        ->capture_default_str();
    cmd->add_option("--intersection-cost", o.intersection_cost, "SAH triangle cost of every device's tree");
    cmd->add_option("--export", o.export_dir,
                    "write each mesh's triangles, rays and Embree's hits here (raw arrays and NAME.json) for bench/warp_rays.py");
    cmd->add_flag("--device-buffers", o.device_buffers,
                  "also time each OpenCL device's queries on rays already in its memory (no upload or read-back)");
    cmd->callback([&c, cmd] {
        c.name = "rays";
        c.measure = [&c, cmd] {
            RaysOptions& r = c.rays;
            r.scenes = scene_list(r.scenes);
            r.scenes_dir = c.scenes_dir;
            quick_default(cmd, c, "--runs", r.runs, 1);
            quick_default(cmd, c, "--meshes", r.meshes, {"torus:100k"});
            quick_default(cmd, c, "--camera-size", r.camera_size, 256);
            quick_default(cmd, c, "--random-rays", r.random_rays, std::size_t{65536});
            return run_rays(r);
        };
    });
}

void add_build(CLI::App& app, Commands& c) {
    BuildOptions& o = c.build;
    CLI::App* cmd = measurement(app, "build", "kd-tree and BVH builds: time, memory, bytes; Embree's BVH builds", c);
    cmd->add_option("--runs", o.runs, "builds per figure (their median)")->capture_default_str();
    cmd->add_option("--scenes", o.scenes, "scenes")->delimiter(',')->capture_default_str();
    cmd->add_option("--meshes", o.meshes, "torus:COUNT or heightfield:POINTS")->delimiter(',')->capture_default_str();
    cmd->callback([&c, cmd] {
        c.name = "build";
        c.measure = [&c, cmd] {
            BuildOptions& b = c.build;
            b.scenes = scene_list(b.scenes);
            b.scenes_dir = c.scenes_dir;
            quick_default(cmd, c, "--runs", b.runs, 1);
            quick_default(cmd, c, "--meshes", b.meshes, {"torus:100k"});
            return run_build(b);
        };
    });
}

void add_frames(CLI::App& app, Commands& c) {
    FramesOptions& o = c.frames;
    CLI::App* cmd = measurement(app, "frames", "later frames of a committed scene against the first", c);
    cmd->add_option("--runs", o.runs, "sequences (medians per frame)")->capture_default_str();
    cmd->add_option("--frames", o.frames, "frames per sequence")->capture_default_str();
    cmd->add_option("--step", o.step_degrees, "camera orbit per frame, degrees")->capture_default_str();
    cmd->add_option("--size", o.size, "square image side (0: the scene's)");
    cmd->add_option("--devices", o.devices, "devices (default: cpu and the first OpenCL device)")->delimiter(',');
    cmd->add_option("--scenes", o.scenes, "scenes")->delimiter(',')->capture_default_str();
    cmd->add_option("--meshes", o.meshes, "torus:COUNT or heightfield:POINTS")->delimiter(',')->capture_default_str();
    cmd->callback([&c, cmd] {
        c.name = "frames";
        c.measure = [&c, cmd] {
            FramesOptions& f = c.frames;
            f.scenes = scene_list(f.scenes);
            f.scenes_dir = c.scenes_dir;
            quick_default(cmd, c, "--runs", f.runs, 1);
            quick_default(cmd, c, "--frames", f.frames, 3);
            quick_default(cmd, c, "--size", f.size, 128);
            quick_default(cmd, c, "--meshes", f.meshes, {"torus:100k"});
            return run_frames(f);
        };
    });
}

// The scripts' helpers: no result file, no isolated kernel caches.
void add_helpers(CLI::App& app, Commands& c) {
    CLI::App* generate = app.add_subcommand("generate", "write a generated mesh as OBJ + scene JSON (prints its path)");
    generate->add_option("MESH", c.mesh_spec, "torus:COUNT, heightfield:POINTS (per side) or layers:COUNT")->required();
    generate->add_option("DIR", c.mesh_dir, "output directory")->required();
    generate->callback([&c] {
        c.helper = [&c] {
            std::printf("%s\n", write_scene_files(make_generated_scene(c.mesh_spec), c.mesh_dir).c_str());
            return 0;
        };
    });

    CLI::App* povray = app.add_subcommand("povray", "write a scene in POV-Ray 3.7's language");
    povray->add_option("SCENE", c.pov_scene, "scene file")->required();
    povray->add_option("OUT", c.pov_out, "the .pov file to write")->required();
    povray->add_option("--size", c.pov_size, "image size WxH the camera is set up for (default: the scene's)");
    povray->callback([&c] {
        c.helper = [&c] {
            int w = 0, h = 0;
            if (!c.pov_size.empty()) parse_size(c.pov_size, w, h);
            write_povray(kdrt::load_scene(c.pov_scene), c.pov_out, w, h);
            return 0;
        };
    });

#ifdef KDRT_BENCH_HAVE_EMBREE
    CLI::App* render = app.add_subcommand("embree-render", "render a scene with Embree 3 and kdrt's shading: "
                                                           "kdrt-render's yardstick for whole processes");
    render->add_option("SCENE", c.embree_scene, "scene file")->required();
    render->add_option("-o,--output", c.embree_out, "image to write")->required();
    render->add_option("--threads", c.embree_threads, "threads (0: all)");
    render->add_option("--size", c.embree_size, "image size WxH (default: the scene's)");
    render->callback([&c] {
        c.helper = [&c] {
            int w = 0, h = 0;
            if (!c.embree_size.empty()) parse_size(c.embree_size, w, h);
            return run_embree_render(c.embree_scene, c.embree_out, c.embree_threads, w, h);
        };
    });
#endif
}

// PoCL and kdrt read their kernel caches' places when they start: empty
// directories of our own keep the user's caches out of the figures.
std::unique_ptr<TempDir> g_caches;

void isolate_kernel_caches() {
    g_caches = std::make_unique<TempDir>("kdrt-bench");
    std::filesystem::create_directory(g_caches->path() / "pocl");
    std::filesystem::create_directory(g_caches->path() / "kdrt");
    setenv("POCL_CACHE_DIR", (g_caches->path() / "pocl").c_str(), 1);
    setenv("KDRT_KERNEL_CACHE", (g_caches->path() / "kdrt").c_str(), 1);
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"kdrt-bench: kdrt beside Embree on the study's scenes and on meshes (BENCHMARKS.md)", "kdrt-bench"};
    app.set_version_flag("--version", std::string("kdrt-bench ") + KDRT_VERSION_STRING);
    app.require_subcommand(1);
    Commands c;
    add_table(app, c);
    add_rays(app, c);
    add_build(app, c);
    add_frames(app, c);
    add_helpers(app, c);
    try {
        app.parse(argc, argv);
        if (c.helper) return c.helper();
        isolate_kernel_caches();
        Json result = result_header(argc, argv);
        result["quick"] = c.quick;
        result.update(c.measure());
        write_result(c.out, c.name, result);
        if (result.value("failures", 0) == 0) return 0;
        std::fprintf(stderr, "kdrt-bench: %d configuration(s) failed (see the result's rows)\n", result["failures"].get<int>());
        return 1;
    } catch (const CLI::ParseError& e) {
        return app.exit(e) == 0 ? 0 : 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "kdrt-bench: %s\n", e.what());
        return 1;
    }
}
