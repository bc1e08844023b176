// kdrt-bench: the measurements behind BENCHMARKS.md (issue 5).
// Exit codes: 0 success, 1 failure (with a message), 2 usage error.
#include "accuracy.h"
#include "build_bench.h"
#include "compile_probe.h"
#include "embree_compare.h"
#include "embree_renderer.h"
#include "frames_bench.h"
#include "mesh_generator.h"
#include "pocl_profile.h"
#include "pov/povray_compare.h"
#include "rays_bench.h"
#include "report.h"
#include "scene_set.h"
#include "schedules.h"
#include "startup.h"
#include "subprocess.h"
#include "table.h"

#include <kdrt/device.h>
#include <kdrt/enum_names.h>
#include <kdrt/error.h>
#include <kdrt/version.h>

#include <CLI/CLI.hpp>

#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>

namespace {

using namespace kdrt::bench;

// Options most commands share; `quick` lowers the defaults that were not given.
struct Common {
    bool quick = false;
    int runs = 0;
    std::string size;
    int depth = 15;
    int threads = 0;
    std::vector<std::string> devices, scenes;
    std::string scenes_dir, out = "bench/results";
};

void add_common(CLI::App* cmd, Common& c, bool with_size = true, bool with_depth = true) {
    cmd->add_flag("--quick", c.quick, "small images and one run: a smoke test, not a measurement");
    cmd->add_option("--runs", c.runs, "timed runs per figure, after one warm-up (the median is reported)")
        ->check(CLI::Range(1, 1000));
    if (with_size) cmd->add_option("--size", c.size, "image size WxH");
    if (with_depth) cmd->add_option("--depth", c.depth, "ray depth (1 = camera rays)")->check(CLI::Range(1, 64));
    cmd->add_option("--devices", c.devices, "devices, comma separated (cpu, opencl:0, ...)")->delimiter(',');
    cmd->add_option("--scenes", c.scenes, "scene names (in --scenes-dir) or files, comma separated")->delimiter(',');
    cmd->add_option("--scenes-dir", c.scenes_dir, "where scene names are looked up (default: the source tree's scenes/)");
    cmd->add_option("--out", c.out, "output directory")->capture_default_str();
}

// Size from --size, else quick's or the default.
void size_of(const Common& c, int quick_size, int full_size, int& w, int& h) {
    if (!c.size.empty()) parse_size(c.size, w, h);
    else w = h = c.quick ? quick_size : full_size;
}

int runs_of(const Common& c, int quick_runs, int full_runs) { return c.runs > 0 ? c.runs : c.quick ? quick_runs : full_runs; }

// The traversals over a kd-tree, as <kdrt/enum_names.h> names them.
std::vector<std::string> tree_traversal_names() {
    std::vector<std::string> names;
    for (const kdrt::EnumName<kdrt::Traversal>& n : kdrt::enum_names<kdrt::Traversal>())
        if (n.value != kdrt::Traversal::None) names.emplace_back(n.name);
    return names;
}

// PoCL reads POCL_CACHE_DIR when it starts; pointing it at an empty directory
// of our own keeps the user's cache out of the figures (and ours out of it).
std::unique_ptr<TempDir> g_session;

void isolate_pocl_cache() {
    g_session = std::make_unique<TempDir>("kdrt-bench-session");
    setenv("POCL_CACHE_DIR", g_session->fresh("pocl").c_str(), 1);
}

}  // namespace

int main(int argc, char** argv) {
    set_invocation(argc, argv);
    CLI::App app{"kdrt-bench: kdrt's benchmarks (the study's table, Embree side by side, tree builds, schedules, "
                 "start-up, POV-Ray)",
                 "kdrt-bench"};
    app.set_version_flag("--version", std::string("kdrt-bench ") + KDRT_VERSION_STRING);
    app.require_subcommand(1);
    std::function<int()> action;
    bool probing = false;  // a child process (or a plain render) that must not isolate PoCL's cache

    // ---- table
    Common tc;
    TableOptions to;
    bool no_embree = false, no_cold = false;
    auto* table = app.add_subcommand("table", "the study's table: device x traversal x tree on the five scenes");
    add_common(table, tc);
    table->add_option("--threads", tc.threads, "cpu device and Embree threads (0 = all)")->check(CLI::Range(0, 256));
    table->add_option("--none-limit-s", to.none_limit_s, "brute force: not run when estimated above this (s)")
        ->capture_default_str();
    table->add_flag("--no-embree", no_embree, "leave out the Embree row");
    table->add_flag("--no-cold-compile", no_cold, "skip the cold kernel compiles (child processes)");
    table->callback([&] {
        action = [&] {
            to.quick = tc.quick;
            size_of(tc, 64, 500, to.width, to.height);
            to.runs = runs_of(tc, 1, 5);
            to.max_depth = tc.depth;
            to.threads = tc.threads;
            to.devices = tc.devices;
            to.scenes = tc.scenes;
            to.scenes_dir = tc.scenes_dir;
            to.out = tc.out;
            to.embree = !no_embree;
            to.cold_compile = !no_cold;
            return run_table(to);
        };
    });

    // ---- embree
    Common ec;
    EmbreeCompareOptions eo;
    auto* embree = app.add_subcommand("embree", "kdrt against Embree 3 in the same run: whole render and camera rays");
    add_common(embree, ec);
    embree->add_option("--threads", ec.threads, "threads of both sides (0 = all)")->check(CLI::Range(0, 256));
    embree->add_option("--traversal", eo.traversal, "kdrt traversal for the whole render")
        ->check(CLI::IsMember(tree_traversal_names()))->capture_default_str();
    embree->add_option("--tree", eo.tree, "kdrt tree")->check(CLI::IsMember({"median", "sah"}))->capture_default_str();
    embree->callback([&] {
        action = [&] {
            eo.quick = ec.quick;
            size_of(ec, 64, 500, eo.width, eo.height);
            eo.runs = runs_of(ec, 1, 5);
            eo.max_depth = ec.depth;
            eo.threads = ec.threads;
            eo.devices = ec.devices;
            eo.scenes = ec.scenes;
            eo.scenes_dir = ec.scenes_dir;
            eo.out = ec.out;
            return run_embree_compare(eo);
        };
    });

    // ---- rays
    Common rc;
    RaysBenchOptions ro;
    std::vector<std::string> ray_meshes;
    auto* rays = app.add_subcommand("rays", "ray throughput on the study's scenes and big meshes: kdrt cpu and OpenCL queries, Embree 1 and 16");
    add_common(rays, rc, false, false);
    rays->add_option("--threads", rc.threads, "threads of every cpu tracer (0 = all)")->check(CLI::Range(0, 256));
    rays->add_option("--meshes", ray_meshes, "torus:COUNT or heightfield:POINTS, comma separated "
                                             "(default torus:100k,torus:1M,heightfield:1001)")->delimiter(',');
    rays->add_option("--camera-size", ro.camera_size, "camera rays: N x N")->check(CLI::Range(1, 16384));
    rays->add_option("--random-rays", ro.random_rays, "incoherent rays")->check(CLI::Range(1, 100000000));
    rays->add_option("--embree-quality", ro.embree_quality, "Embree build quality")
        ->check(CLI::IsMember({"low", "medium", "high"}))->capture_default_str();
    rays->add_option("--intersection-cost", ro.intersection_cost, "SAH intersection cost (default: the builder's)")
        ->check(CLI::Range(0.0, 1000.0));
    rays->add_option("--traversal", ro.traversal, "kdrt traversal")
        ->check(CLI::IsMember(tree_traversal_names()))->capture_default_str();
    rays->callback([&] {
        action = [&] {
            ro.quick = rc.quick;
            ro.runs = runs_of(rc, 1, 5);
            ro.threads = rc.threads;
            ro.devices = rc.devices;
            ro.scenes = rc.scenes;
            ro.scenes_dir = rc.scenes_dir;
            ro.out = rc.out;
            if (!ray_meshes.empty()) ro.meshes = ray_meshes;
            else if (rc.quick) ro.meshes = {"torus:100k"};
            if (rc.quick) {
                if (!rays->count("--camera-size")) ro.camera_size = 256;
                if (!rays->count("--random-rays")) ro.random_rays = 65536;
            }
            return run_rays_bench(ro);
        };
    });

    // ---- frames
    Common fc;
    FramesBenchOptions fo;
    std::vector<std::string> frame_meshes;
    auto* frames = app.add_subcommand("frames", "a second frame with a moved camera against the first: CommittedScene");
    add_common(frames, fc, true, false);
    frames->add_option("--frames", fo.frames, "frames per sequence (frame 1 and the moved ones)")
        ->check(CLI::Range(2, 1000))->capture_default_str();
    frames->add_option("--step", fo.step_degrees, "camera orbit per frame, degrees")->capture_default_str();
    frames->add_option("--intersection-cost", fo.intersection_cost,
                       "SAH intersection cost, the same tree on every device (default: each device's own)");
    frames->add_option("--meshes", frame_meshes, "generated meshes, torus:COUNT or heightfield:POINTS (default torus:1M)")
        ->delimiter(',');
    frames->callback([&] {
        action = [&] {
            fo.runs = runs_of(fc, 1, 3);
            fo.devices = fc.devices;
            fo.scenes = fc.scenes;
            fo.scenes_dir = fc.scenes_dir;
            fo.out = fc.out;
            int w = 0, h = 0;
            size_of(fc, 128, 0, w, h);
            if (w != h) throw kdrt::Error(kdrt::ErrorCode::InvalidArgument, "--size: frames renders square images");
            fo.size = w;
            if (!frame_meshes.empty()) fo.meshes = frame_meshes;
            else if (fc.quick) fo.meshes = {"torus:100k"};
            if (fc.quick && fc.scenes.empty()) fo.scenes = {"2x2x4", "lens"};
            return run_frames_bench(fo);
        };
    });

    // ---- build
    Common bc;
    BuildBenchOptions bo;
    std::vector<std::string> meshes;
    auto* build = app.add_subcommand("build", "kd-tree builders: time, N log N scaling, quality, bytes; Embree's BVH build");
    add_common(build, bc, false, false);
    build->add_option("--meshes", meshes, "generated torus meshes, triangle counts (100k,1M,4M)")->delimiter(',');
    build->add_option("--render-size", bo.render_size, "square image for the render-time column")->capture_default_str();
    build->add_option("--threads", bc.threads, "cpu device threads for the renders (0 = all)");
    build->callback([&] {
        action = [&] {
            bo.quick = bc.quick;
            bo.runs = runs_of(bc, 1, 3);
            bo.threads = bc.threads;
            bo.scenes = bc.scenes;
            bo.scenes_dir = bc.scenes_dir;
            bo.out = bc.out;
            if (!meshes.empty()) bo.meshes = meshes;
            else if (bc.quick) bo.meshes = {"100k"};
            return run_build_bench(bo);
        };
    });

    // ---- schedules
    Common sc;
    SchedulesOptions so;
    auto* schedules = app.add_subcommand("schedules", "OpenCL: persistent/plain, specialised/generic, ray orders, local sizes");
    add_common(schedules, sc);
    schedules->callback([&] {
        action = [&] {
            so.quick = sc.quick;
            size_of(sc, 64, 500, so.width, so.height);
            so.runs = runs_of(sc, 1, 3);
            so.max_depth = sc.depth;
            so.devices = sc.devices;
            so.scenes = sc.scenes;
            so.scenes_dir = sc.scenes_dir;
            so.out = sc.out;
            return run_schedules(so);
        };
    });

    // ---- pocl-profile
    Common plc;
    PoclProfileOptions plo;
    auto* pocl = app.add_subcommand("pocl-profile", "OpenCL: device time per kernel and transfer (event profiling) "
                                                    "against the C++ reference, per scene");
    add_common(pocl, plc);
    pocl->add_option("--traversal", plo.traversal, "traversal (restart, ropes, stack, short-stack)")->capture_default_str();
    pocl->add_option("--precision", plo.precision, "float or double")->capture_default_str();
    pocl->callback([&] {
        action = [&] {
            plo.quick = plc.quick;
            size_of(plc, 64, 500, plo.width, plo.height);
            plo.runs = runs_of(plc, 1, 5);
            plo.max_depth = plc.depth;
            if (plc.devices.size() > 1) throw kdrt::Error(kdrt::ErrorCode::InvalidArgument, "pocl-profile: one device");
            if (!plc.devices.empty()) plo.device = plc.devices[0];
            plo.scenes = plc.scenes;
            plo.scenes_dir = plc.scenes_dir;
            plo.out = plc.out;
            return run_pocl_profile(plo);
        };
    });

    // ---- startup
    Common uc;
    StartupOptions uo;
    std::string startup_render;
    auto* startup = app.add_subcommand("startup", "process start to first kernel launch, cold and warm, and peak memory");
    add_common(startup, uc, false, false);
    startup->add_option("--kdrt-render", startup_render, "the kdrt-render binary (default: next to kdrt-bench)");
    startup->callback([&] {
        action = [&] {
            uo.quick = uc.quick;
            uo.runs = runs_of(uc, 1, 3);
            uo.kdrt_render = startup_render;
            uo.devices = uc.devices;
            uo.scenes = uc.scenes;
            uo.scenes_dir = uc.scenes_dir;
            uo.out = uc.out;
            return run_startup(uo);
        };
    });

    // ---- povray (converter)
    std::string pov_scene, pov_out, pov_size;
    auto* povray = app.add_subcommand("povray", "convert a scene to POV-Ray 3.7's language");
    povray->add_option("SCENE", pov_scene, "scene file (kdrt-scene/1 JSON)")->required();
    povray->add_option("OUT", pov_out, "the .pov file to write")->required();
    povray->add_option("--size", pov_size, "image size WxH the camera is set up for (default: the scene's)");
    povray->callback([&] {
        action = [&] {
            int w = 0, h = 0;
            if (!pov_size.empty()) parse_size(pov_size, w, h);
            return run_povray_export(pov_scene, pov_out, w, h);
        };
    });

    // ---- povray-compare
    Common pc;
    PovrayCompareOptions po;
    std::string pc_render, pc_povray = "povray";
    auto* povcmp = app.add_subcommand("povray-compare", "POV-Ray 3.7 against kdrt-render, process start to PNG");
    add_common(povcmp, pc, true, false);
    povcmp->add_option("--kdrt-render", pc_render, "the kdrt-render binary (default: next to kdrt-bench)");
    povcmp->add_option("--povray", pc_povray, "the povray binary")->capture_default_str();
    povcmp->callback([&] {
        action = [&] {
            po.quick = pc.quick;
            size_of(pc, 64, 500, po.width, po.height);
            po.runs = runs_of(pc, 1, 3);
            po.kdrt_render = pc_render;
            po.povray = pc_povray;
            po.devices = pc.devices;
            po.scenes = pc.scenes;
            po.scenes_dir = pc.scenes_dir;
            po.out = pc.out;
            return run_povray_compare(po);
        };
    });

    // ---- accuracy (issue 6): what each step of accuracy costs
    Common ac;
    AccuracyConfig acfg;
    auto* accuracy = app.add_subcommand("accuracy", "every accuracy knob: render time against the error to a reference");
    add_common(accuracy, ac, true, false);
    accuracy->add_option("--reference-samples", acfg.reference_samples, "samples per pixel of the reference")
        ->check(CLI::Range(1, 4096));
    accuracy->callback([&] {
        action = [&] {
            size_of(ac, 64, 250, acfg.width, acfg.height);
            acfg.runs = runs_of(ac, 1, 3);
            if (ac.quick && acfg.reference_samples == 16) acfg.reference_samples = 4;
            acfg.scenes = load_scenes(split_list(ac.scenes), ac.scenes_dir);
            acfg.devices = split_list(ac.devices);
            if (acfg.devices.empty())
                for (const kdrt::DeviceInfo& d : kdrt::list_devices()) acfg.devices.push_back(d.id);
            acfg.out = ac.out;
            return run_accuracy(acfg);
        };
    });

    // ---- generate: the big meshes as files, for whole-process timings
    std::string gen_spec, gen_dir;
    auto* generate = app.add_subcommand("generate", "write a generated mesh (torus:1M, heightfield:1001) as OBJ + "
                                                    "scene JSON");
    generate->add_option("MESH", gen_spec, "torus:COUNT or heightfield:POINTS (per side)")->required();
    generate->add_option("DIR", gen_dir, "output directory")->required();
    generate->callback([&] {
        probing = true;
        action = [&] {
            std::printf("%s\n", write_scene_files(make_generated_scene(gen_spec), gen_dir).c_str());
            return 0;
        };
    });

#ifdef KDRT_BENCH_HAVE_EMBREE
    // ---- embree-render: the Embree-based equivalent of kdrt-render, for
    // whole-process comparisons (same loader, same shading, same PNG writer).
    std::string er_scene, er_out;
    int er_threads = 0;
    auto* erender = app.add_subcommand("embree-render", "render a scene with Embree 3 and kdrt's Whitted shading, "
                                                        "start to image: kdrt-render's yardstick");
    erender->add_option("SCENE", er_scene, "scene file (kdrt-scene/1 JSON)")->required();
    erender->add_option("-o,--output", er_out, "image to write")->required();
    erender->add_option("--threads", er_threads, "threads (0 = all)")->check(CLI::Range(0, 256));
    erender->callback([&] {
        probing = true;  // no OpenCL in this process: leave PoCL's cache alone
        action = [&] { return run_embree_render(er_scene, er_out, er_threads); };
    });
#endif

    // ---- probe-compile (hidden: a child of `table`, for cold compiles)
    std::string probe_scene, probe_device = "opencl", probe_traversal = "stack", probe_cache;
    int probe_depth = 15;
    auto* probe = app.add_subcommand("probe-compile", "");
    probe->group("");
    probe->add_option("SCENE", probe_scene)->required();
    probe->add_option("--device", probe_device);
    probe->add_option("--traversal", probe_traversal);
    probe->add_option("--depth", probe_depth);
    probe->add_option("--kernel-cache", probe_cache)->required();
    probe->callback([&] {
        probing = true;
        action = [&] { return run_compile_probe(probe_scene, probe_device, probe_traversal, probe_depth, probe_cache); };
    });

    try {
        app.parse(argc, argv);
        if (!probing) isolate_pocl_cache();
        return action ? action() : 2;
    } catch (const CLI::ParseError& e) {
        return app.exit(e) == 0 ? 0 : 2;
    } catch (const kdrt::Error& e) {
        std::fprintf(stderr, "kdrt-bench: %s\n", e.what());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "kdrt-bench: error: %s\n", e.what());
        return 1;
    }
}
