// kdrt-render: renders a scene file to an image (kHelpFooter lists the exit codes, 130 = interrupted too).
// Exit codes: 0 success, 1 bad input (with a message), 2 usage error.
#include "allocator_tuning.h"
#include "camera_orbit.h"
#include "enum_option.h"
#include "frame_names.h"
#include "progress_bar.h"
#include "interrupt.h"

#include "common/atomic_file.h"
#include "common/terminal_text.h"

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/image.h>
#include <kdrt/model_import.h>
#include <kdrt/render.h>
#include <kdrt/scene_loader.h>
#include <kdrt/tiled_render.h>
#include <kdrt/version.h>

#ifdef KDRT_MPI
#include "cluster/cluster_job.h"
#endif

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <optional>
#include <system_error>
#include <utility>
#include <vector>

namespace {

struct Args {
    std::string scene_path, output, aov_ids;
    kdrt::RenderOptions render;
    std::string accel = "kd", traversal = "stack", tree = "sah", precision = "float", features = "scene";
    std::string schedule = "persistent", ray_order = "tiles", kernel_cache;
    std::string triangle_test = "watertight", sphere_test = "careful", self_intersection = "scale-aware";
    int tree_depth = 0;
    std::vector<double> sah_costs;  // node step, triangle test, sphere test
    std::string save_tree, load_tree, tree_cache;
    bool list_devices = false, stats_json = false, tree_stats = false, quiet = false;
    bool progress = false, no_progress = false;
    std::string encoding = "linear";
    bool float_samples = false;  // --float: a TIFF with 32-bit float samples
    std::optional<int> camera;  // a model file's camera number
    int frames = 1;             // --frames: an orbit of the camera, one output per frame (frame_names.h)
    std::optional<std::string> tile;  // --tile WxH: several devices' (or cluster ranks') tile size
};

// A usage error found after parsing: exit code 2, like CLI11's own.
struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

using kdrt::detail::escape_for_terminal;

constexpr int kExitInterrupted = 130;  // 128 + SIGINT, as shells report it

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
  2    usage error (bad option or value, outputs that collide with inputs or each other)
  130  interrupted (SIGINT): nothing written, existing outputs untouched; a second Ctrl-C kills at once)";

// --tile's value: "WxH" or "N" (N x N), each 1 .. 16384.
kdrt::TileSize parse_tile(const std::string& text) {
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

// A --device value naming several devices: a list or "all".
bool names_device_list(const std::string& device) {
    return device.find(',') != std::string::npos || device == "all";
}

// Throws kdrt::Error(Cancelled) once SIGINT has arrived.
void stop_if_interrupted() {
    if (kdrt::cli::interrupted()) throw kdrt::Error(kdrt::ErrorCode::Cancelled, "interrupted");
}

void print_devices() {
    for (const kdrt::DeviceInfo& d : kdrt::list_devices()) {
        // Driver strings are printed escaped: they are not ours.
        std::printf("%-10s %s | %s | %s | %s | driver %s | %u compute units | %.1f GiB global, %.1f GiB max alloc | fp64 %s\n",
                    escape_for_terminal(d.id).c_str(), escape_for_terminal(d.platform).c_str(),
                    escape_for_terminal(d.name).c_str(), escape_for_terminal(d.vendor).c_str(),
                    escape_for_terminal(d.type).c_str(), escape_for_terminal(d.driver_version).c_str(),
                    d.compute_units, d.global_memory / 1073741824.0,
                    d.max_allocation / 1073741824.0, d.fp64 ? "yes" : "no");
    }
}

nlohmann::ordered_json bvh_stats_json(const kdrt::BvhStats& s) {
    return {{"nodes", s.nodes},
            {"leaves", s.leaves},
            {"empty_slots", s.empty_slots},
            {"depth", s.depth},
            {"mean_leaf_size", s.mean_leaf_size},
            {"sah_cost", s.sah_cost},
            {"build_sah_cost", s.build_sah_cost},
            {"bytes", {{"nodes", s.node_bytes}, {"leaf_objects", s.leaf_object_bytes}, {"total", s.total_bytes()}}},
            {"bytes_per_object", {{"nodes", s.per_object(s.node_bytes)},
                                  {"leaf_lists", s.per_object(s.leaf_object_bytes)},
                                  {"total", s.per_object(s.total_bytes())}}}};
}

nlohmann::ordered_json tree_stats_json(const kdrt::KdTreeStats& s) {
    return {{"nodes", s.nodes},
            {"inner_nodes", s.inner_nodes},
            {"leaves", s.leaves},
            {"empty_leaves", s.empty_leaves},
            {"max_leaf_depth", s.max_leaf_depth},
            {"mean_leaf_depth", s.mean_leaf_depth},
            {"mean_objects_per_leaf", s.mean_objects_per_leaf},
            {"duplication", s.duplication},
            {"sah_cost", s.sah_cost},
            {"bytes", {{"nodes", s.node_bytes},
                       {"leaf_objects", s.leaf_object_bytes},
                       {"ropes", s.rope_bytes},
                       {"total", s.total_bytes()}}},
            // Per object of the scene (per triangle in a mesh): leaf lists are the object ids (a leaf node
            // holds its list's range, there are no leaf records).
            {"bytes_per_object", {{"nodes", s.per_object(s.node_bytes)},
                                  {"leaf_lists", s.per_object(s.leaf_object_bytes)},
                                  {"ropes", s.per_object(s.rope_bytes)},
                                  {"total", s.per_object(s.total_bytes())}}}};
}

// Two paths name the same file: the same inode when both exist, else the same
// normalised absolute path.
bool same_file(const std::filesystem::path& a, const std::filesystem::path& b) {
    std::error_code ec;
    if (std::filesystem::exists(a, ec) && std::filesystem::exists(b, ec)) {
        const bool same = std::filesystem::equivalent(a, b, ec);
        if (!ec) return same;
    }
    const auto ca = std::filesystem::weakly_canonical(std::filesystem::absolute(a, ec), ec);
    if (ec) return false;
    const auto cb = std::filesystem::weakly_canonical(std::filesystem::absolute(b, ec), ec);
    return !ec && ca == cb;
}

// A scene file (JSON), or a model file rendered as it is (docs/IMPORT.md):
// its camera (--camera N), lights and materials, or the documented defaults.
kdrt::Scene load_input(const Args& a) {
    const bool json = std::filesystem::path(a.scene_path).extension() == ".json";
    if (json || !kdrt::is_model_file(a.scene_path)) {
        if (a.camera) throw UsageError("--camera picks a camera of a model file, not of a scene file");
        return kdrt::load_scene(a.scene_path);
    }
    kdrt::ImportStats stats;
    kdrt::Scene scene = kdrt::scene_from_model(a.scene_path, {a.camera}, &stats);
    for (const std::string& w : stats.warnings)
        std::fprintf(stderr, "kdrt-render: warning: %s\n", escape_for_terminal(w, true).c_str());
    if (!a.quiet && (stats.skipped_points || stats.skipped_lines))
        std::fprintf(stderr, "kdrt-render: %s: skipped %zu points and %zu lines (triangles only)\n",
                     escape_for_terminal(a.scene_path).c_str(), stats.skipped_points, stats.skipped_lines);
    return scene;
}

// --width, --height, --max-depth and --samples override the scene's own
// settings, so that a scene committed once is made for them (the OpenCL
// kernels are specialised for the depth); the frames ask for them too.
void override_settings(kdrt::Scene& scene, const kdrt::FrameOptions& frame) {
    if (frame.width) scene.settings.width = frame.width;
    if (frame.height) scene.settings.height = frame.height;
    if (frame.max_depth) scene.settings.max_depth = frame.max_depth;
    if (frame.samples) scene.settings.samples = frame.samples;
}

// Every file the run would write is checked before any work: a writable
// directory, no symlink or special file to replace, and no output that is an
// input or another output (either would be destroyed).
void check_outputs(const Args& a) {
    std::vector<std::pair<std::string, std::string>> outputs, inputs;  // option, path
    if (!a.output.empty()) outputs.emplace_back("--output", kdrt::cli::frame_file_name(a.output, 0, a.frames));
    if (!a.aov_ids.empty()) outputs.emplace_back("--aov-ids", kdrt::cli::frame_file_name(a.aov_ids, 0, a.frames));
    if (!a.save_tree.empty()) outputs.emplace_back("--save-tree", a.save_tree);
    inputs.emplace_back("the scene", a.scene_path);
    if (!a.load_tree.empty()) inputs.emplace_back("--load-tree", a.load_tree);
    for (std::size_t i = 0; i < outputs.size(); ++i) {
        const auto& [option, path] = outputs[i];
        try {
            kdrt::detail::check_output_target(path);
        } catch (const kdrt::Error& e) {
            throw UsageError(option + " " + e.what());
        }
        for (const auto& [input_option, input] : inputs)
            if (same_file(path, input))
                throw UsageError(option + " " + path + " is " + input_option + " " + input +
                                 ": writing it would destroy the input");
        for (std::size_t j = 0; j < i; ++j)
            if (same_file(path, outputs[j].second))
                throw UsageError(option + " " + path + " and " + outputs[j].first + " " + outputs[j].second +
                                 " are the same file");
    }
}

// Runs a write to `file`'s temporary; its errors name the target, the file the user asked for.
template <class Write>
void naming_target(const kdrt::detail::AtomicFile& file, Write&& write) {
    try {
        write();
    } catch (const kdrt::Error& e) {
        std::string message = e.what();
        const std::string temporary = file.temporary().string(), target = file.target().string();
        for (std::size_t at = message.find(temporary); at != std::string::npos; at = message.find(temporary, at))
            message.replace(at, temporary.size(), target);
        throw kdrt::Error(e.code(), message);
    }
}

// The --stats-json object of one frame.
nlohmann::ordered_json stats_json(const Args& a, const kdrt::Scene& scene, const kdrt::RenderOptions& o,
                                  const kdrt::RenderResult& r, const kdrt::TileSize& tile, double write_ms) {
    const kdrt::RenderStats& st = r.stats;
    const double mrays = st.render_ms > 0 ? st.rays.total() / (st.render_ms * 1000.0) : 0.0;
    nlohmann::ordered_json j = {
        {"scene", scene.name},
        {"device", st.device_name},
        {"width", r.image.width},
        {"height", r.image.height},
        {"max_depth", o.frame.max_depth ? o.frame.max_depth : scene.settings.max_depth},
        {"samples", o.frame.samples ? o.frame.samples : scene.settings.samples},
        {"accel", kdrt::to_string(o.commit.accel)},
        {"traversal", kdrt::to_string(o.commit.traversal)},
        {"precision", kdrt::to_string(o.commit.accuracy.precision)},
        {"triangle_test", kdrt::to_string(o.commit.accuracy.triangle_test)},
        {"sphere_test", kdrt::to_string(o.commit.accuracy.sphere_test)},
        {"self_intersection", kdrt::to_string(o.commit.accuracy.self_intersection)},
        // The builder named by --tree only when it made the tree; "file" for --load-tree, "none" without a tree.
        {"tree", !a.load_tree.empty()                      ? std::string("file")
                 : st.tree_stats                           ? a.tree
                 : st.bvh_stats                            ? std::string("bvh")
                                                           : std::string("none")},
        {"tree_file", a.load_tree.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(a.load_tree)},
        {"tree_loaded", st.tree_loaded},
        {"features", st.features.names()},
        {"build_ms", st.build_ms},
        {"compile_ms", st.compile_ms},
        {"upload_ms", st.upload_ms},
        {"kernel_cache_hit", st.opencl.kernel_cache_hit},
        {"kernel_options", st.opencl.kernel_options},
        {"launches", st.opencl.launches},
        {"render_ms", st.render_ms},
        {"write_ms", write_ms},  // encoding and writing the image and id map
        {"rays", {{"camera", st.rays.camera}, {"shadow", st.rays.shadow}, {"secondary", st.rays.secondary},
                  {"total", st.rays.total()}}},
        {"mrays_per_s", mrays}};
    if (st.tree_stats) j["tree_stats"] = tree_stats_json(*st.tree_stats);
    if (st.bvh_stats) j["bvh_stats"] = bvh_stats_json(*st.bvh_stats);
    if (st.refits) j["refits"] = st.refits;
    if (!st.device_shares.empty()) {
        j["tile"] = {{"width", tile.width}, {"height", tile.height}};
        nlohmann::ordered_json shares = nlohmann::ordered_json::array();
        for (const kdrt::DeviceShare& d : st.device_shares)
            shares.push_back({{"device", d.device_name},
                              {"tiles", d.tiles},
                              {"pixels", d.pixels},
                              {"busy_ms", d.busy_ms},
                              {"rays", {{"camera", d.rays.camera}, {"shadow", d.rays.shadow},
                                        {"secondary", d.rays.secondary}, {"total", d.rays.total()}}}});
        j["device_shares"] = shares;
    }
    if (!st.opencl.kernel_resources.empty()) {
        // As the OpenCL implementation reports them (PoCL: 0 private bytes), with kdrt's stack estimate.
        nlohmann::ordered_json kernels = nlohmann::ordered_json::array();
        for (const kdrt::KernelResources& k : st.opencl.kernel_resources)
            kernels.push_back({{"kernel", k.kernel},
                               {"private_bytes", k.private_bytes},
                               {"local_bytes", k.local_bytes},
                               {"work_group_size", k.work_group_size},
                               {"preferred_multiple", k.preferred_multiple}});
        j["kernel_resources"] = kernels;
        j["traversal_stack_bytes"] = st.opencl.traversal_stack_bytes;
    }
    if (!st.opencl.command_times.empty()) {
        nlohmann::ordered_json commands = nlohmann::ordered_json::array();
        for (const kdrt::CommandTime& c : st.opencl.command_times)
            commands.push_back({{"command", c.command}, {"level", c.level}, {"count", c.count},
                                {"device_ms", c.device_ms}});
        j["command_times"] = commands;
        j["device_busy_ms"] = st.opencl.device_busy_ms;
    }
    return j;
}

// Writes a frame's image and id map (frame_names.h names them when there are
// several frames). Returns the milliseconds it took (--stats-json's write_ms).
double write_outputs(const Args& a, const kdrt::ImageWriteOptions& image_options, const kdrt::RenderResult& r,
                   int frame) {
    // Both files are written in full beside their targets before either
    // replaces its target, so a failing id map does not leave a new image
    // next to an old id map (or the reverse).
    const auto start = std::chrono::steady_clock::now();
    std::optional<kdrt::detail::AtomicFile> image_file, ids_file;
    if (!a.output.empty()) {
        const std::string path = kdrt::cli::frame_file_name(a.output, frame, a.frames);
        image_file.emplace(path, std::filesystem::path(path).extension().string());
        naming_target(*image_file, [&] { kdrt::write_image(image_file->temporary(), r.image, image_options); });
    }
    if (!a.aov_ids.empty()) {
        ids_file.emplace(kdrt::cli::frame_file_name(a.aov_ids, frame, a.frames));
        naming_target(*ids_file, [&] { kdrt::write_id_map(ids_file->temporary(), r); });
    }
    stop_if_interrupted();  // the temporaries are removed as the AtomicFiles go
    if (image_file) image_file->commit();
    if (ids_file) ids_file->commit();
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// What follows a frame's render: warnings, outputs, the summary line (not
// --stats-json, which the caller prints). Returns write_outputs' milliseconds.
double finish_frame(const Args& a, const kdrt::ImageWriteOptions& image_options, const kdrt::Scene& scene,
                    const kdrt::RenderResult& r, int frame) {
    for (const std::string& w : r.warnings)
        std::fprintf(stderr, "kdrt-render: warning: %s\n", escape_for_terminal(w, true).c_str());
    const double write_ms = write_outputs(a, image_options, r, frame);
    if (a.tree_stats && !a.stats_json && frame == 0) {
        if (r.stats.tree_stats) std::cout << tree_stats_json(*r.stats.tree_stats).dump(2) << "\n";
        if (r.stats.bvh_stats) std::cout << bvh_stats_json(*r.stats.bvh_stats).dump(2) << "\n";
    }
    if (!a.stats_json && !a.quiet && !a.output.empty()) {
        const std::string output = kdrt::cli::frame_file_name(a.output, frame, a.frames);
        std::fprintf(stderr, "%s: %dx%d, %.1f ms (%.2f Mrays/s) on %s -> %s\n", escape_for_terminal(scene.name).c_str(),
                     r.image.width, r.image.height, r.stats.render_ms,
                     r.stats.render_ms > 0 ? r.stats.rays.total() / (r.stats.render_ms * 1000.0) : 0.0,
                     escape_for_terminal(r.stats.device_name).c_str(), escape_for_terminal(output).c_str());
        const double pixels = static_cast<double>(r.image.width) * r.image.height;
        for (const kdrt::DeviceShare& d : r.stats.device_shares)
            std::fprintf(stderr, "  %s: %llu tiles, %.1f%% of the pixels, %.1f ms busy, %.2f Mrays\n",
                         escape_for_terminal(d.device_name).c_str(), static_cast<unsigned long long>(d.tiles),
                         pixels > 0 ? 100.0 * static_cast<double>(d.pixels) / pixels : 0.0, d.busy_ms,
                         static_cast<double>(d.rays.total()) / 1e6);
    }
    return write_ms;
}

// A frame's JSON line: "frame" added when there are several.
void print_stats(const Args& a, nlohmann::ordered_json j, int frame) {
    if (a.frames > 1) j["frame"] = frame;
    std::cout << j.dump() << "\n";
}

#ifdef KDRT_MPI
kdrt::cluster::MpiSession* mpi_session = nullptr;  // set by main() under mpirun

nlohmann::ordered_json cluster_json(const kdrt::cluster::JobStats& s) {
    nlohmann::ordered_json shares = nlohmann::ordered_json::array();
    for (const kdrt::DeviceShare& d : s.shares)
        shares.push_back({{"device", d.device_name}, {"tiles", d.tiles}, {"pixels", d.pixels}, {"busy_ms", d.busy_ms},
                          {"rays", d.rays.total()}});
    return {{"ranks", s.ranks},           {"prepare_ms", s.prepare_ms},   {"commit_ms", s.commit_ms},
            {"serialize_ms", s.serialize_ms}, {"broadcast_ms", s.broadcast_ms}, {"broadcast_bytes", s.broadcast_bytes},
            {"render_ms", s.render_ms},   {"receive_ms", s.receive_ms},   {"assemble_ms", s.assemble_ms},
            {"output_ms", s.output_ms},   {"tiles", s.tiles},             {"decoded_ms", s.decoded_ms},
            {"ready_ms", s.ready_ms},
            {"shares", shares}};
}

// Under mpirun every rank runs the job (cluster/cluster_job.h); rank 0
// checks the outputs, loads the scene, writes the frames and the statistics.
int run_cluster(const Args& a, const kdrt::RenderOptions& o, const kdrt::ImageWriteOptions& image_options) {
    kdrt::cluster::JobSpec spec;
    spec.options = o;
    spec.options.commit.progress = nullptr;
    spec.options.frame.progress = nullptr;
    spec.frames = a.frames;
    spec.camera = [frames = a.frames](const kdrt::Camera& c, int frame) {
        return kdrt::cli::orbit_camera(c, frame, frames);
    };
    spec.exit_code_of = [](const std::exception_ptr& error) {  // as main() below returns for it
        try {
            std::rethrow_exception(error);
        } catch (const UsageError&) {
            return 2;
        } catch (const kdrt::Error& e) {
            return e.code() == kdrt::ErrorCode::Cancelled && kdrt::cli::interrupted() ? kExitInterrupted : 1;
        } catch (...) {
            return 1;
        }
    };
    if (a.tile) {
        const kdrt::TileSize tile = parse_tile(*a.tile);
        spec.tile_width = tile.width;
        spec.tile_height = tile.height;
    }
    auto prepare = [&a] {
        check_outputs(a);
        if (!a.output.empty()) kdrt::check_image_output(a.output);
        kdrt::Scene scene = load_input(a);
        override_settings(scene, a.render.frame);
        return scene;
    };
    std::vector<std::pair<int, nlohmann::ordered_json>> frame_stats;
    auto frame_done = [&](int frame, const kdrt::Scene& scene, kdrt::RenderResult&& r) {
        stop_if_interrupted();
        const double write_ms = finish_frame(a, image_options, scene, r, frame);
        if (a.stats_json) frame_stats.emplace_back(frame, stats_json(a, scene, o, r, {}, write_ms));
    };
    kdrt::cluster::JobStats stats;
    kdrt::cluster::run_job(*mpi_session, spec, prepare, frame_done, stats);
    std::sort(frame_stats.begin(), frame_stats.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    for (auto& [frame, j] : frame_stats) {
        j["cluster"] = cluster_json(stats);
        print_stats(a, std::move(j), frame);
    }
    return 0;
}
#endif

bool running_as_cluster() {
#ifdef KDRT_MPI
    return mpi_session != nullptr;
#else
    return false;
#endif
}

// Names the rank in messages of a rank other than 0 (rank 0 names the others itself).
std::string rank_prefix() {
#ifdef KDRT_MPI
    if (mpi_session && mpi_session->rank() != 0) return mpi_session->name() + ": ";
#endif
    return {};
}

int run(Args& a) {
    if (a.list_devices) {
        if (!a.scene_path.empty() || !a.output.empty() || !a.aov_ids.empty() || !a.save_tree.empty() ||
            a.stats_json || a.tree_stats)
            throw UsageError("--list-devices lists the devices and renders nothing: give it alone");
        print_devices();
        return 0;
    }
    if (a.scene_path.empty()) throw CLI::RequiredError("SCENE");
    if (a.output.empty() && !a.stats_json && !a.tree_stats && a.aov_ids.empty() && a.save_tree.empty())
        throw CLI::RequiredError("--output (or --stats-json, --tree-stats, --aov-ids, --save-tree)");

    kdrt::RenderOptions& o = a.render;
    o.commit.accel = kdrt::accel_from_string(a.accel);
    o.commit.traversal = kdrt::traversal_from_string(a.traversal);
    o.commit.tree.builder = kdrt::kd_builder_from_string(a.tree);
    o.commit.tree.max_depth = a.tree_depth;
    if (!a.sah_costs.empty()) {
        o.commit.tree.traversal_cost = a.sah_costs[0];
        o.commit.tree.intersection_cost = a.sah_costs[1];
        o.commit.tree.sphere_intersection_cost = a.sah_costs[2];
    }
    o.commit.tree.threads = a.render.frame.threads;  // the tree builds on the same threads
    o.commit.bvh.threads = a.render.frame.threads;
    o.commit.accuracy.precision = kdrt::precision_from_string(a.precision);
    o.frame.want_ids = !a.aov_ids.empty();
    o.frame.opencl.schedule = kdrt::schedule_from_string(a.schedule);
    o.frame.opencl.ray_order = kdrt::ray_order_from_string(a.ray_order);
    o.commit.all_features = a.features == "all";
    o.commit.accuracy.triangle_test = kdrt::triangle_test_from_string(a.triangle_test);
    o.commit.accuracy.sphere_test = kdrt::sphere_test_from_string(a.sphere_test);
    o.commit.accuracy.self_intersection = kdrt::self_intersection_from_string(a.self_intersection);
    if (!a.kernel_cache.empty()) o.commit.kernel_cache_dir = a.kernel_cache;
    if (!a.save_tree.empty()) o.commit.tree_files.save = a.save_tree;
    if (!a.load_tree.empty()) o.commit.tree_files.load = a.load_tree;
    if (!a.tree_cache.empty()) o.commit.tree_files.cache_dir = a.tree_cache;
    // A tree is needed for its statistics or to save it, even with --traversal none.
    o.commit.build_tree = a.tree_stats || !a.save_tree.empty();

    const kdrt::TileSize tile = a.tile ? parse_tile(*a.tile) : kdrt::TileSize{};
    if (a.tile && !names_device_list(o.device) && !running_as_cluster())
        throw UsageError("--tile is for several devices (--device a,b or --device all) or ranks (under mpirun)");

    kdrt::ImageWriteOptions image_options;
    image_options.encoding = a.encoding == "srgb" ? kdrt::Encoding::Srgb : kdrt::Encoding::Linear;
    image_options.float_samples = a.float_samples;
    if (!a.output.empty()) {
        const bool tiff = kdrt::image_stores_floats(a.output, {kdrt::Encoding::Linear, true}) &&
                          !kdrt::image_stores_floats(a.output);
        if (a.float_samples && !tiff)
            throw UsageError("--float is for TIFF outputs (.tif, .tiff); exr, hdr and pfm are always float, not " +
                             a.output);
        if (a.encoding == "srgb" && kdrt::image_stores_floats(a.output, image_options))
            throw UsageError("--encoding srgb is for 8-bit outputs; " + a.output + " stores linear floats");
    } else if (a.float_samples || a.encoding != "linear") {
        throw UsageError(std::string(a.float_samples ? "--float" : "--encoding") + " needs an --output image");
    }

#ifdef KDRT_MPI
    if (mpi_session) return run_cluster(a, o, image_options);
#endif
    // Fail before a long render, not after it, when an output cannot be written.
    check_outputs(a);
    if (!a.output.empty()) kdrt::check_image_output(a.output);
    kdrt::Scene scene = load_input(a);
    override_settings(scene, o.frame);
    const kdrt::cli::ProgressMode mode = a.no_progress ? kdrt::cli::ProgressMode::Never
                                         : a.progress  ? kdrt::cli::ProgressMode::Always
                                         : a.quiet || a.output.empty() ? kdrt::cli::ProgressMode::Never
                                                                       : kdrt::cli::ProgressMode::Auto;
    kdrt::cli::ProgressBar bar(mode);
    int frame = 0;
    // Returning false cancels the render (kdrt::Error(Cancelled)).
    o.commit.progress = o.frame.progress = [&bar, &frame, &a](double f) {
        bar.update((frame + f) / a.frames);
        return !kdrt::cli::interrupted();
    };
    // Several devices: tiles handed out to each (kdrt/tiled_render.h).
    std::vector<kdrt::Device> devices;
    if (names_device_list(o.device)) devices = kdrt::open_devices(o.device);
    if (devices.size() == 1) o.device = devices[0].info().id;  // "all" on a machine with one device
    stop_if_interrupted();
    if (a.frames == 1) {
        kdrt::RenderResult r = devices.size() > 1
                                   ? kdrt::MultiDeviceScene::commit(devices, scene, o.commit).render(o.frame, tile)
                                   : kdrt::render(scene, o);
        bar.finish();
        stop_if_interrupted();  // a library that finished its phase anyway: write nothing
        const double write_ms = finish_frame(a, image_options, scene, r, 0);
        if (a.stats_json) print_stats(a, stats_json(a, scene, o, r, tile, write_ms), 0);
        return 0;
    }
    // A camera path: the scene is committed once, each frame only moves the camera.
    std::optional<kdrt::MultiDeviceScene> several;
    std::optional<kdrt::CommittedScene> one;
    if (devices.size() > 1)
        several = kdrt::MultiDeviceScene::commit(devices, scene, o.commit);
    else
        one = kdrt::CommittedScene::commit(kdrt::Device::open(o.device), scene, o.commit);
    kdrt::Scene moved = scene;
    for (; frame < a.frames; ++frame) {
        moved.camera = kdrt::cli::orbit_camera(scene.camera, frame, a.frames);
        if (frame > 0) several ? several->update(moved) : one->update(moved);
        kdrt::RenderResult r = several ? several->render(o.frame, tile) : one->render(o.frame);
        stop_if_interrupted();
        if (frame == a.frames - 1) bar.finish();
        const double write_ms = finish_frame(a, image_options, moved, r, frame);
        if (a.stats_json) print_stats(a, stats_json(a, moved, o, r, tile, write_ms), frame);
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    kdrt::cli::tune_allocator();
    bool report_errors = true;  // under mpirun, rank 0 alone reports what every rank would
#ifdef KDRT_MPI
    std::optional<kdrt::cluster::MpiSession> session;
    try {
        if (kdrt::cluster::launched_by_mpirun()) session.emplace(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "kdrt-render: MPI: %s\n", e.what());
        return 1;
    }
    if (session) {
        mpi_session = &*session;
        report_errors = session->rank() == 0;
    }
#endif
    Args a;
    a.render.device.clear();
    // NaN passes every comparison-based range check; infinities are no offsets or times either.
    const CLI::Validator finite(
        [](std::string& text) {
            double v = 0.0;
            if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v)) return "must be a finite number, not " + text;
            return std::string();
        },
        "FINITE");
    CLI::App app{"kdrt-render: renders a kdrt scene file (FORMAT.md) with a kd-tree ray tracer", "kdrt-render"};
    app.footer(kHelpFooter);
    app.option_defaults()->always_capture_default();  // --help shows each option's default
    app.set_version_flag("--version", std::string("kdrt-render ") + KDRT_VERSION_STRING);
    app.add_option("SCENE", a.scene_path,
                   "scene file (kdrt-scene/1 JSON) or a model (obj, gltf, glb, ply, stl, off, fbx: docs/IMPORT.md)");
    app.add_option("--camera", a.camera, "a model file's camera number (default: its first, else one framing it)")
        ->check(CLI::NonNegativeNumber);
    app.add_option("-o,--output", a.output,
                   "output image; format from the extension: png, ppm, pfm (written by kdrt), exr, tif, hdr, jpg, ... "
                   "(through OpenImageIO, loaded for them)");
    app.add_option("--encoding", a.encoding,
                   "8-bit outputs: linear (FORMAT.md: round(255 c)) | srgb (the IEC 61966-2-1 sRGB curve)")
        ->check(CLI::IsMember({"linear", "srgb"}));
    app.add_flag("--float", a.float_samples, "a TIFF output gets 32-bit float samples instead of 8-bit");
    app.add_option("--width", a.render.frame.width, "image width (overrides the scene)")
        ->check(CLI::Range(1, 16384))->default_str("the scene's");
    app.add_option("--height", a.render.frame.height, "image height (overrides the scene)")
        ->check(CLI::Range(1, 16384))->default_str("the scene's");
    app.add_option("--max-depth", a.render.frame.max_depth, "longest ray chain, 1 = camera rays only")
        ->check(CLI::Range(1, 64))->default_str("the scene's");
    app.add_option("--samples", a.render.frame.samples, "camera rays per pixel")
        ->check(CLI::Range(1, 4096))->default_str("the scene's");
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
    app.add_option("--accel", a.accel, kdrt::cli::enum_help<kdrt::Accel>("acceleration structure: "))
        ->check(kdrt::cli::is_enum_name<kdrt::Accel>());
    app.add_option("--traversal", a.traversal, kdrt::cli::enum_help<kdrt::Traversal>("(a BVH has stack and none) "))
        ->check(kdrt::cli::is_enum_name<kdrt::Traversal>());
    app.add_option("--tree", a.tree, kdrt::cli::enum_help<kdrt::KdBuilderKind>("kd-tree builder: "))
        ->check(kdrt::cli::is_enum_name<kdrt::KdBuilderKind>());
    app.add_option("--tree-depth", a.tree_depth, "maximum kd-tree depth (0 = automatic; median: 10)")->check(CLI::Range(0, 64));
    app.add_option("--sah-costs", a.sah_costs,
                   "SAH cost constants STEP,TRIANGLE,SPHERE: a node step and the two object tests; the triangle's "
                   "default is the device's (cpu 0.3: it tests a leaf's triangles together; OpenCL 0.6)")
        ->delimiter(',')->expected(3)->check(CLI::PositiveNumber & finite)->default_str("1,0.3|0.6,0.6");
    app.add_flag("--tree-stats", a.tree_stats, "print kd-tree or BVH statistics as JSON");
    app.add_option("--save-tree", a.save_tree, "write the kd-tree or BVH to this file");
    app.add_option("--load-tree", a.load_tree,
                   "use the kd-tree or BVH (as --accel says) from this file (must match the scene; with --traversal "
                   "none it is only checked)");
    app.add_option("--tree-cache", a.tree_cache,
                   "directory of cached kd-trees and BVHs: a scene's structure is built once (unusable: a warning, "
                   "no cache)");
    app.add_option("--schedule", a.schedule, kdrt::cli::enum_help<kdrt::Schedule>("OpenCL: "))
        ->check(kdrt::cli::is_enum_name<kdrt::Schedule>());
    app.add_option("--ray-order", a.ray_order, kdrt::cli::enum_help<kdrt::RayOrder>("OpenCL: camera ray order: "))
        ->check(kdrt::cli::is_enum_name<kdrt::RayOrder>());
    app.add_option("--max-launch-ms", a.render.frame.opencl.max_launch_ms, "OpenCL: longest kernel launch in ms (display watchdogs)")
        ->check(finite & CLI::Range(1.0, 1e7));
    app.add_option("--local-size", a.render.frame.opencl.local_size, "OpenCL: work-group size (0 = automatic)")->check(CLI::Range(0, 4096));
    app.add_flag("--profile-commands", a.render.frame.opencl.profile_commands,
                 "OpenCL: time each kernel and transfer with event profiling (--stats-json: command_times)");
    app.add_option("--kernel-cache", a.kernel_cache,
                   "OpenCL: directory of compiled kernels (default: the user's cache; made 0700; unusable: a warning)");
    app.add_option("--features", a.features, "scene: kernels specialised to the scene's effects; all: the generic kernel")
        ->check(CLI::IsMember({"scene", "all"}));
    app.add_option("--precision", a.precision, kdrt::cli::enum_help<kdrt::Precision>())
        ->check(kdrt::cli::is_enum_name<kdrt::Precision>());
    app.add_option("--triangle-test", a.triangle_test, kdrt::cli::enum_help<kdrt::TriangleTest>())
        ->check(kdrt::cli::is_enum_name<kdrt::TriangleTest>());
    app.add_option("--sphere-test", a.sphere_test, kdrt::cli::enum_help<kdrt::SphereTest>())
        ->check(kdrt::cli::is_enum_name<kdrt::SphereTest>());
    app.add_option("--self-intersection", a.self_intersection, kdrt::cli::enum_help<kdrt::SelfIntersection>())
        ->check(kdrt::cli::is_enum_name<kdrt::SelfIntersection>());
    app.add_option("--epsilon", a.render.commit.accuracy.fixed_epsilon, "offset of --self-intersection fixed, in scene units")
        ->check(finite & CLI::PositiveNumber);
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

    try {
        app.parse(argc, argv);
        kdrt::cli::install_interrupt_handler();
        return run(a);
    } catch (const CLI::ParseError& e) {
        if (!report_errors) return e.get_exit_code() == 0 ? 0 : 2;
        return app.exit(e) == 0 ? 0 : 2;
#ifdef KDRT_MPI
    } catch (const kdrt::cluster::JobStopped& e) {
        return e.exit_code;  // rank 0 says why
#endif
    } catch (const UsageError& e) {
        if (!report_errors) return 2;
        std::fprintf(stderr, "kdrt-render: %s\nRun with --help for more information.\n",
                     escape_for_terminal(e.what(), true).c_str());
        return 2;
    } catch (const kdrt::Error& e) {
        if (e.code() == kdrt::ErrorCode::Cancelled && kdrt::cli::interrupted()) {
            std::fprintf(stderr, "kdrt-render: interrupted\n");
            return kExitInterrupted;
        }
        std::fprintf(stderr, "kdrt-render: %s%s\n", rank_prefix().c_str(), escape_for_terminal(e.what(), true).c_str());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "kdrt-render: %serror: %s\n", rank_prefix().c_str(),
                     escape_for_terminal(e.what(), true).c_str());
        return 1;
    }
}
