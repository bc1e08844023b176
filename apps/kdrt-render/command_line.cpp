#include "command_line.h"

#include "enum_option.h"

#include "opencl/cl_devices.h"

#include <kdrt/device.h>
#include <kdrt/model_import.h>
#include <kdrt/version.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <sstream>
#include <utility>

namespace kdrt::cli {
namespace {

const char* const kHelpFooter = R"(Examples:
  kdrt-render scenes/lens.json -o lens.png
  kdrt-render scenes/lens.json --width 1920 --height 1080 --samples 4 --encoding srgb -o lens.png
  kdrt-render scenes/lens.json --device opencl --stats-json -o lens.exr
  kdrt-render scenes/lens.json --device cpu,opencl --tile 32x32 -o lens.png   (tiles shared by two devices)
  kdrt-render model.gltf --camera 0 -o model.tif --float
  kdrt-render scene.json --tree-cache ~/.cache/kdrt-trees --aov-ids ids.bin -o out.pfm
  kdrt-render scenes/lens.json --frames 90 -o orbit.png        (orbit_0000.png ... orbit_0089.png)
  mpirun -np 4 kdrt-render scene.json --device opencl:local-rank -o out.png   (a cluster build: -DKDRT_MPI=ON)

Exit codes:
  0    success
  1    bad input, a failed render or a failed write (a message says which; no output is replaced)
  2    usage error (bad option or value, a device name that names no device, outputs that collide with
       inputs or each other)
  130  interrupted (SIGINT), 143 terminated (SIGTERM), 129 hung up (SIGHUP): nothing written, existing
       outputs untouched, no temporary left; a second signal ends it at once)";

// NaN passes every comparison-based range check; infinities are no offsets or times either.
const CLI::Validator& finite() {
    static const CLI::Validator v(
        [](std::string& text) {
            double value = 0.0;
            if (!CLI::detail::lexical_cast(text, value) || !std::isfinite(value))
                return "must be a finite number, not " + text;
            return std::string();
        },
        "FINITE");
    return v;
}

void add_input_options(CLI::App& app, Args& a) {
    app.add_option("SCENE", a.scene_path,
                   "scene file (kdrt-scene/1 JSON) or a model (obj, gltf, glb, ply, stl, off, fbx: docs/IMPORT.md)");
    app.add_option("--camera", a.camera, "a model file's camera number (default: its first, else one framing it)")
        ->check(CLI::NonNegativeNumber);
    app.add_flag("--allow-outside-files", a.allow_outside_files,
                 "models may name files outside their own folder (glTF buffers and images, an OBJ's .mtl); "
                 "by default such files are not read");
}

void add_output_options(CLI::App& app, Args& a) {
    app.add_option("-o,--output", a.output,
                   "output image; format from the extension: png, ppm, pfm (written by kdrt), exr, tif, hdr, jpg, ... "
                   "(through OpenImageIO, loaded for them)");
    app.add_option("--encoding", a.encoding,
                   "8-bit outputs: linear (FORMAT.md: round(255 c)) | srgb (the IEC 61966-2-1 sRGB curve)")
        ->check(CLI::IsMember({"linear", "srgb"}));
    app.add_flag("--float", a.float_samples, "a TIFF output gets 32-bit float samples instead of 8-bit");
    app.add_option("--aov-ids", a.aov_ids, "write the camera rays' id map (FORMAT.md) to this file");
    app.add_flag("--stats-json", a.stats_json, "print one JSON object of statistics on stdout");
    app.add_flag("-q,--quiet", a.quiet, "nothing on stderr but errors and warnings");
    auto* progress = app.add_flag("--progress", a.progress,
                                  "show progress with an estimate of the time left even when stderr is no terminal "
                                  "(default: on a terminal only, after a second)");
    app.add_flag("--no-progress", a.no_progress, "no progress display")->excludes(progress);
    app.add_option("--frames", a.frames,
                   "render N frames of a camera orbit around look_at (about the camera's up axis; frame 0 is the "
                   "scene's camera), one output per frame: out.png -> out_0000.png, out_0001.png, ...")
        ->check(CLI::Range(1, 1000000));
}

void add_picture_options(CLI::App& app, Args& a) {
    app.add_option("--width", a.render.frame.width, "image width (overrides the scene)")
        ->check(CLI::Range(1, 16384))->default_str("the scene's");
    app.add_option("--height", a.render.frame.height, "image height (overrides the scene)")
        ->check(CLI::Range(1, 16384))->default_str("the scene's");
    app.add_option("--max-depth", a.render.frame.max_depth, "longest ray chain, 1 = camera rays only")
        ->check(CLI::Range(1, 64))->default_str("the scene's");
    app.add_option("--samples", a.render.frame.samples, "camera rays per pixel")
        ->check(CLI::Range(1, 4096))->default_str("the scene's");
    app.add_option("--precision", a.precision, enum_help<Precision>())->check(is_enum_name<Precision>());
    app.add_option("--triangle-test", a.triangle_test, enum_help<TriangleTest>())->check(is_enum_name<TriangleTest>());
    app.add_option("--sphere-test", a.sphere_test, enum_help<SphereTest>())->check(is_enum_name<SphereTest>());
    app.add_option("--self-intersection", a.self_intersection, enum_help<SelfIntersection>())
        ->check(is_enum_name<SelfIntersection>());
    app.add_option("--epsilon", a.render.commit.accuracy.fixed_epsilon, "offset of --self-intersection fixed, in scene units")
        ->check(finite() & CLI::PositiveNumber);
    app.add_option("--features", a.features, "scene: kernels specialised to the scene's effects; all: the generic kernel")
        ->check(CLI::IsMember({"scene", "all"}));
}

void add_device_options(CLI::App& app, Args& a) {
    app.add_option("--device", a.render.device,
                   "device to render on (see --list-devices); a comma-separated list (cpu,opencl) or 'all' shares "
                   "the frame's tiles among several devices, each named once (PoCL is itself a CPU device: with "
                   "cpu,opencl on PoCL both use the same cores)")
        ->default_str("$KDRT_DEVICE, else cpu");
    app.add_option("--tile", a.tile,
                   "several devices, or ranks under mpirun: tile size WxH (or N for NxN) handed out one at a time "
                   "(under mpirun: default 64x64, whole frames with --frames)")
        ->default_str("64x64");
    app.add_flag("--list-devices", a.list_devices, "list the devices and exit");
    app.add_option("--threads", a.render.frame.threads, "cpu device: worker threads (0 = all cores)")->check(CLI::Range(0, 256));
    app.add_option("--accel", a.accel, enum_help<Accel>("acceleration structure: "))
        ->check(is_enum_name<Accel>())
        ->default_str("bvh; kd with a kd-tree --traversal, --tree, --tree-depth or --sah-costs");
    app.add_option("--traversal", a.traversal, enum_help<Traversal>("(a BVH has stack and none) "))
        ->check(is_enum_name<Traversal>());
    app.add_option("--schedule", a.schedule, enum_help<Schedule>("OpenCL: "))->check(is_enum_name<Schedule>());
    app.add_option("--ray-order", a.ray_order, enum_help<RayOrder>("OpenCL: camera ray order: "))
        ->check(is_enum_name<RayOrder>());
    app.add_option("--max-launch-ms", a.render.frame.opencl.max_launch_ms, "OpenCL: longest kernel launch in ms (display watchdogs)")
        ->check(finite() & CLI::Range(1.0, 1e7));
    app.add_option("--local-size", a.render.frame.opencl.local_size, "OpenCL: work-group size (0 = automatic)")->check(CLI::Range(0, 4096));
    app.add_flag("--profile-commands", a.render.frame.opencl.profile_commands,
                 "OpenCL: time each kernel and transfer with event profiling (--stats-json: command_times)");
    app.add_option("--kernel-cache", a.kernel_cache,
                   "OpenCL: directory of compiled kernels (default: the user's cache; made 0700; unusable: a warning)");
}

void add_tree_options(CLI::App& app, Args& a) {
    app.add_option("--tree", a.tree, enum_help<KdBuilderKind>("kd-tree builder: "))->check(is_enum_name<KdBuilderKind>());
    app.add_option("--tree-depth", a.tree_depth, "maximum kd-tree depth (0 = automatic; median: 10)")->check(CLI::Range(0, 64));
    app.add_option("--sah-costs", a.sah_costs,
                   "SAH cost constants STEP,TRIANGLE,SPHERE: a node step and the two object tests; the triangle's "
                   "default is the device's (cpu 0.3: it tests a leaf's triangles together; OpenCL 0.6)")
        ->delimiter(',')->expected(3)->check(CLI::PositiveNumber & finite())->default_str("1,0.3|0.6,0.6");
    app.add_flag("--tree-stats", a.tree_stats, "print kd-tree or BVH statistics as JSON");
    app.add_option("--save-tree", a.save_tree, "write the kd-tree or BVH to this file");
    app.add_option("--load-tree", a.load_tree,
                   "use the kd-tree or BVH (as --accel says) from this file (must match the scene; with --traversal "
                   "none it is only checked)");
    app.add_option("--tree-cache", a.tree_cache,
                   "directory of cached kd-trees and BVHs: a scene's structure is built once (unusable: a warning, "
                   "no cache)");
}

// --tile's value: "WxH" or "N" (N x N), each 1 .. 16384.
TileSize parse_tile(const std::string& text) {
    const auto bad = [&] { return UsageError("--tile " + text + ": expected WxH or N, sizes 1 to 16384 (e.g. 64x64)"); };
    const auto number = [&](const std::string& part) {
        if (part.empty() || part.size() > 5 || part.find_first_not_of("0123456789") != std::string::npos) throw bad();
        const int v = std::stoi(part);
        if (v < 1 || v > 16384) throw bad();
        return v;
    };
    const auto x = text.find('x');
    if (x == std::string::npos) return {number(text), number(text)};
    return {number(text.substr(0, x)), number(text.substr(x + 1))};
}

std::string trimmed(const std::string& s) {
    const auto first = s.find_first_not_of(" \t");
    if (first == std::string::npos) return {};
    return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

// The device a name selects on this machine: "cpu", or an OpenCL device's id.
// A name that selects none is a usage error, as any bad option value.
std::string selected_device(const std::string& name) {
    std::string lower = name;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (lower == "cpu") return "cpu";
    if (lower != "opencl" && lower.rfind("opencl:", 0) != 0)
        throw UsageError("--device " + name + ": unknown device (expected cpu, opencl, opencl:N, opencl:gpu, "
                         "opencl:NAME, a list of them or all; see --list-devices)");
    std::vector<DeviceInfo> opencl = list_devices();
    opencl.erase(opencl.begin());  // the cpu device comes first
    try {
        return opencl[detail::ocl::select_device_index(name, opencl)].id;
    } catch (const Error& e) {
        throw UsageError(std::string("--device: ") + e.what());
    }
}

// The ids of the devices a name of --device selects on this machine.
std::vector<std::string> selected_devices(const std::string& name) {
    if (name != "all") return {selected_device(name)};
    std::vector<std::string> ids;
    for (const DeviceInfo& d : list_devices()) ids.push_back(d.id);
    return ids;
}

// --device's names, each selecting a device of its own. Several names (or
// "all") are returned as a list; one name as an empty list.
std::vector<std::string> check_devices(const std::string& value, bool cluster) {
    const bool several = value.find(',') != std::string::npos || trimmed(value) == "all";
    std::vector<std::string> names;
    std::stringstream in(value);
    for (std::string item; std::getline(in, item, ',');) names.push_back(trimmed(item));
    if (value.empty() || value.back() == ',') names.push_back({});
    std::set<std::string> chosen;
    for (const std::string& name : names) {
        if (name.empty()) throw UsageError("--device " + value + ": an empty device name");
        // Under mpirun names are resolved per rank ("local-rank"): only their spelling is checked here.
        for (const std::string& id : cluster ? std::vector<std::string>{name} : selected_devices(name))
            if (!chosen.insert(id).second)
                throw UsageError("--device " + value + " names device " + id + " twice (" + name +
                                 " is one already named); name each device once");
    }
    return several ? names : std::vector<std::string>{};
}

// --accel, or its default: the BVH, or the kd-tree where the command line asks
// for what only the kd-tree has (a traversal, or its builder's options).
Accel chosen_accel(const Args& a, Traversal traversal) {
    const bool kd_traversal = !bvh_has_traversal(traversal);
    if (a.accel.empty()) return kd_traversal || a.kd_options ? Accel::KdTree : Accel::Bvh;
    const Accel accel = accel_from_string(a.accel);
    if (accel == Accel::Bvh && kd_traversal)
        throw UsageError("--traversal " + a.traversal + " walks a kd-tree; a BVH has stack and none (--accel kd)");
    if (accel == Accel::Bvh && a.kd_options)
        throw UsageError("--tree, --tree-depth and --sah-costs build a kd-tree; not with --accel bvh");
    return accel;
}

void fill_render_options(Args& a) {
    RenderOptions& o = a.render;
    o.commit.traversal = traversal_from_string(a.traversal);
    o.commit.accel = chosen_accel(a, o.commit.traversal);
    o.commit.tree.builder = kd_builder_from_string(a.tree);
    o.commit.tree.max_depth = a.tree_depth;
    if (!a.sah_costs.empty()) {
        o.commit.tree.traversal_cost = a.sah_costs[0];
        o.commit.tree.intersection_cost = a.sah_costs[1];
        o.commit.tree.sphere_intersection_cost = a.sah_costs[2];
    }
    o.commit.tree.threads = o.frame.threads;  // the tree builds on the same threads
    o.commit.bvh.threads = o.frame.threads;
    o.commit.accuracy.precision = precision_from_string(a.precision);
    o.frame.want_ids = !a.aov_ids.empty();
    o.frame.opencl.schedule = schedule_from_string(a.schedule);
    o.frame.opencl.ray_order = ray_order_from_string(a.ray_order);
    o.commit.all_features = a.features == "all";
    o.commit.accuracy.triangle_test = triangle_test_from_string(a.triangle_test);
    o.commit.accuracy.sphere_test = sphere_test_from_string(a.sphere_test);
    o.commit.accuracy.self_intersection = self_intersection_from_string(a.self_intersection);
    if (!a.kernel_cache.empty()) o.commit.kernel_cache_dir = a.kernel_cache;
    if (!a.save_tree.empty()) o.commit.tree_files.save = a.save_tree;
    if (!a.load_tree.empty()) o.commit.tree_files.load = a.load_tree;
    if (!a.tree_cache.empty()) o.commit.tree_files.cache_dir = a.tree_cache;
    // A tree is needed for its statistics or to save it, even with --traversal none.
    o.commit.build_tree = a.tree_stats || !a.save_tree.empty();
}

void check_image_options(Args& a) {
    a.image.encoding = a.encoding == "srgb" ? Encoding::Srgb : Encoding::Linear;
    a.image.float_samples = a.float_samples;
    if (a.output.empty()) {
        if (a.float_samples || a.encoding != "linear")
            throw UsageError(std::string(a.float_samples ? "--float" : "--encoding") + " needs an --output image");
        return;
    }
    const bool tiff = image_stores_floats(a.output, {Encoding::Linear, true}) && !image_stores_floats(a.output);
    if (a.float_samples && !tiff)
        throw UsageError("--float is for TIFF outputs (.tif, .tiff); exr, hdr and pfm are always float, not " + a.output);
    if (a.encoding == "srgb" && image_stores_floats(a.output, a.image))
        throw UsageError("--encoding srgb is for 8-bit outputs; " + a.output + " stores linear floats");
}

// The checks that need neither a file nor a device.
void check_usage(Args& a, bool cluster) {
    if (a.list_devices) {
        if (!a.scene_path.empty() || !a.output.empty() || !a.aov_ids.empty() || !a.save_tree.empty() || a.stats_json ||
            a.tree_stats)
            throw UsageError("--list-devices lists the devices and renders nothing: give it alone");
        return;
    }
    if (a.scene_path.empty()) throw CLI::RequiredError("SCENE");
    if (a.output.empty() && !a.stats_json && !a.tree_stats && a.aov_ids.empty() && a.save_tree.empty())
        throw CLI::RequiredError("--output (or --stats-json, --tree-stats, --aov-ids, --save-tree)");
    const bool json = std::filesystem::path(a.scene_path).extension() == ".json";
    if (a.camera && (json || !is_model_file(a.scene_path)))
        throw UsageError("--camera picks a camera of a model file, not of a scene file");
    fill_render_options(a);
    a.render.device = device_value(a.render.device);
    a.devices = check_devices(a.render.device, cluster);
    if (a.tile) a.tile_size = parse_tile(*a.tile);
    if (a.tile && a.devices.empty() && !cluster)
        throw UsageError("--tile is for several devices (--device a,b or --device all) or ranks (under mpirun)");
    check_image_options(a);
}

// A command line that ends the run before it starts (its args are not used).
void end_run(CommandLine& c, int exit_code, std::string message) {
    c.action = CommandLine::Action::Exit;
    c.exit_code = exit_code;
    c.message = std::move(message);
}

}  // namespace

std::string device_value(const std::string& option) {
    if (!option.empty()) return option;
    const char* env = std::getenv("KDRT_DEVICE");
    return env && *env ? env : "cpu";
}

CommandLine parse_command_line(int argc, char** argv, bool cluster) {
    CommandLine c;
    Args& a = c.args;
    CLI::App app{"kdrt-render: renders a kdrt scene file (FORMAT.md) with a BVH or kd-tree ray tracer", "kdrt-render"};
    app.footer(kHelpFooter);
    app.option_defaults()->always_capture_default();  // --help shows each option's default
    app.set_version_flag("--version", std::string("kdrt-render ") + KDRT_VERSION_STRING);
    add_input_options(app, a);
    add_output_options(app, a);
    add_picture_options(app, a);
    add_device_options(app, a);
    add_tree_options(app, a);
    try {
        app.parse(argc, argv);
        a.kd_options = app.count("--tree") + app.count("--tree-depth") + app.count("--sah-costs") > 0;
        check_usage(a, cluster);
        c.action = a.list_devices ? CommandLine::Action::ListDevices : CommandLine::Action::Render;
    } catch (const CLI::CallForHelp&) {
        end_run(c, 0, app.help());
    } catch (const CLI::CallForAllHelp&) {
        end_run(c, 0, app.help("", CLI::AppFormatMode::All));
    } catch (const CLI::CallForVersion& e) {
        end_run(c, 0, e.what());
    } catch (const CLI::ParseError& e) {
        end_run(c, 2, e.what());
    } catch (const UsageError& e) {
        end_run(c, 2, e.what());
    }
    return c;
}

}  // namespace kdrt::cli
