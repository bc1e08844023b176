// kdrt-render's command line: the options (CLI11), and everything that can
// be checked about them without reading a file or opening a device, so that
// every rank of a cluster job can agree on it before anything else
// (cluster/command_line_agreement.h).
#pragma once

#include <kdrt/image.h>
#include <kdrt/render.h>
#include <kdrt/tiled_render.h>

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace kdrt::cli {

// A usage error found after parsing: exit code 2, like CLI11's own.
struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

struct Args {
    std::string scene_path, output, aov_ids;
    RenderOptions render;
    std::string accel;  // empty: the BVH, or the kd-tree for its own traversals and builder options (fill_render_options)
    std::string traversal = "stack", tree = "sah", precision = "float", features = "scene";
    bool kd_options = false;  // --tree, --tree-depth or --sah-costs given
    std::string schedule = "persistent", ray_order = "tiles", kernel_cache;
    std::string triangle_test = "watertight", sphere_test = "careful", self_intersection = "scale-aware";
    int tree_depth = 0;
    std::vector<double> sah_costs;  // node step, triangle test, sphere test
    std::string save_tree, load_tree, tree_cache;
    bool list_devices = false, stats_json = false, tree_stats = false, quiet = false;
    bool progress = false, no_progress = false;
    bool allow_outside_files = false;  // a model's files may lie outside its folder
    std::string encoding = "linear";
    bool float_samples = false;  // --float: a TIFF with 32-bit float samples
    std::optional<int> camera;  // a model file's camera number
    int frames = 1;             // --frames: an orbit of the camera, one output per frame (frame_names.h)
    std::optional<std::string> tile;  // --tile WxH: several devices' (or cluster ranks') tile size

    // Filled by parse_command_line from the options above.
    TileSize tile_size;
    ImageWriteOptions image;
    std::vector<std::string> devices;  // --device's names when it lists several (or "all"), else empty
};

// What a command line asks for once parsed and checked.
struct CommandLine {
    enum class Action { Render, ListDevices, Exit } action = Action::Render;
    int exit_code = 0;    // Action::Exit: 0 after --help or --version, 2 for a usage error
    std::string message;  // Action::Exit: what to print (help, version, or the error, without "kdrt-render: ")
    Args args;
};

// Parses and checks argv (nothing is printed). `cluster`: under mpirun, where
// --tile applies to ranks and device names are resolved per rank.
CommandLine parse_command_line(int argc, char** argv, bool cluster);

// The --device value in force: the option, else $KDRT_DEVICE, else "cpu".
std::string device_value(const std::string& option);

}  // namespace kdrt::cli
