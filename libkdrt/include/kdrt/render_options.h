// What a render is asked for and what it returns: the options, the accuracy
// knobs, the effects a scene calls for, and the result. Devices (src/cpu,
// src/opencl) read these types; only render.h dispatches to them.
#pragma once

#include <kdrt/export.h>
#include <kdrt/image.h>
#include <kdrt/kd_tree.h>
#include <kdrt/scene.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace kdrt {

enum class Traversal { None, Restart, Ropes, Stack, ShortStack };
enum class Precision { Float, Double };
// OpenCL scheduling. Persistent: persistent threads (Aila and Laine 2009) in
// the device's best form: on a CPU device each work-item traces its camera
// rays' whole ray trees, depth first; on a GPU rays wait in a queue per
// bounce level, one launch per level. Wavefront: persistent threads with the
// queues on every device. Plain: one work-item per ray, with the queues.
enum class Schedule { Persistent, Plain, Wavefront };
// Accuracy knobs: each trades robustness for speed (see BENCHMARKS.md).
enum class TriangleTest { Watertight, MollerTrumbore };  // Woop et al. 2013 | Moller and Trumbore 1997
enum class SphereTest { Careful, Textbook };             // Haines et al. 2019 | the quadratic formula
enum class SelfIntersection { ScaleAware, FixedEpsilon };  // relative offset + self-exclusion | absolute offset

// The order camera rays are issued in (OpenCL): neighbouring work-items trace
// neighbouring pixels with tiles or a Morton curve.
enum class RayOrder { Rows, Tiles, Morton };

KDRT_API const char* to_string(Traversal t);
KDRT_API Traversal traversal_from_string(const std::string& name);  // names: kdrt/enum_names.h; throws
KDRT_API const char* to_string(Precision p);
KDRT_API Precision precision_from_string(const std::string& name);  // names: kdrt/enum_names.h; throws
KDRT_API const char* to_string(TriangleTest t);
KDRT_API TriangleTest triangle_test_from_string(const std::string& name);   // names: kdrt/enum_names.h; throws
KDRT_API const char* to_string(SphereTest t);
KDRT_API SphereTest sphere_test_from_string(const std::string& name);       // names: kdrt/enum_names.h; throws
KDRT_API const char* to_string(SelfIntersection s);
KDRT_API SelfIntersection self_intersection_from_string(const std::string& name);  // names: kdrt/enum_names.h; throws
KDRT_API const char* to_string(Schedule s);
KDRT_API Schedule schedule_from_string(const std::string& name);    // names: kdrt/enum_names.h; throws
KDRT_API const char* to_string(RayOrder o);
KDRT_API RayOrder ray_order_from_string(const std::string& name);   // names: kdrt/enum_names.h; throws

// The effects a scene calls for. Renderers simulate only these: no shadow
// rays without lights, no bounce loop without mirrors or glass, no
// refraction code without glass.
struct KDRT_API SceneFeatures {
    bool spheres = false;
    bool triangles = false;
    bool lights = false;
    bool reflection = false;  // some material has reflect > 0
    bool refraction = false;  // some material has transmit > 0
    int max_depth = 1;        // effective: 1 when nothing reflects or refracts

    static SceneFeatures of(const Scene& scene, int max_depth);
    static SceneFeatures all(int max_depth);  // the generic set: everything on
    std::vector<std::string> names() const;   // enabled features, for reports
};

// A rectangle of pixels of a frame: columns [x, x + width), rows [y, y + height),
// row 0 at the top (FORMAT.md's image order).
struct PixelRect {
    int x = 0, y = 0, width = 0, height = 0;
    friend bool operator==(const PixelRect&, const PixelRect&) = default;
};

struct RenderOptions {
    // 0 keeps the scene's settings.
    int width = 0, height = 0, max_depth = 0, samples = 0;
    // Frame-level: render only these pixels of the width x height frame. The
    // result's image, ids and hit_t are region-sized, and each pixel is bit for
    // bit what the whole frame's render gives it on the same device with the
    // same options. A region not inside the frame, or empty, is an
    // Error(InvalidArgument). Unset: the whole frame.
    std::optional<PixelRect> region;
    std::string device;                    // "cpu", "opencl", "opencl:N", ...; empty: $KDRT_DEVICE or "cpu"
    int threads = 0;                       // cpu: worker threads, 0 = all cores
    // OpenCL devices only:
    Schedule schedule = Schedule::Persistent;
    RayOrder ray_order = RayOrder::Tiles;
    double max_launch_ms = 200.0;          // split work so that no kernel launch runs longer (display watchdogs)
    int local_size = 0;                    // work-group size, 0 = the device's default choice
    int work_groups_per_unit = 0;          // persistent threads: groups per compute unit, 0 = default
    // Time every command of the frame with OpenCL event profiling, on a queue
    // of the frame's own (RenderResult::command_times). Off: no cost at all.
    bool profile_commands = false;
    std::optional<std::filesystem::path> kernel_cache_dir;  // compiled programs; default: the user's cache dir
    Traversal traversal = Traversal::Stack;
    KdBuildConfig tree;                    // builder and its parameters
    Precision precision = Precision::Float;
    TriangleTest triangle_test = TriangleTest::Watertight;
    SphereTest sphere_test = SphereTest::Careful;
    SelfIntersection self_intersection = SelfIntersection::ScaleAware;
    double fixed_epsilon = 1e-4;           // SelfIntersection::FixedEpsilon: offset in scene units
    bool all_features = false;             // ignore the scene's feature set (for comparison)
    bool want_ids = false;                 // fill RenderResult::ids / hit_t
    bool build_tree = false;               // build the kd-tree even for Traversal::None (statistics, saving)
    // Only Traversal::Ropes gets ropes, built after loading a rope-less file;
    // save_tree writes the tree as used, the cache keeps trees without ropes
    // and removes its own temporary files left by killed saves (> 10 min old).
    std::optional<std::filesystem::path> load_tree, save_tree, tree_cache_dir;
    // A tree built in memory (build_scene_tree, build_kd_tree) for this scene's
    // geometry; checked like a loaded one. Takes precedence over load_tree.
    std::shared_ptr<const KdTree> tree_in_memory;
    // Called with the finished fraction in [0, 1] of the build, upload or
    // render at hand, from the calling thread (a kd-tree build calls it from
    // one builder thread at a time); returning false cancels: the
    // call then throws kdrt::Error(Cancelled) soon after (within ~100 ms),
    // having joined its workers and written nothing.
    std::function<bool(double)> progress;
};

struct RayCounts {
    std::uint64_t camera = 0, shadow = 0, secondary = 0;
    std::uint64_t total() const { return camera + shadow + secondary; }
    RayCounts& operator+=(const RayCounts& o) {
        camera += o.camera; shadow += o.shadow; secondary += o.secondary;
        return *this;
    }
};

// What the OpenCL implementation says one kernel of the program needs
// (clGetKernelWorkGroupInfo). Implementations that keep private memory in
// registers or on the host stack (PoCL) may report 0 private bytes: see
// RenderResult::traversal_stack_bytes for kdrt's own figure.
struct KernelResources {
    std::string kernel;
    std::uint64_t private_bytes = 0;  // CL_KERNEL_PRIVATE_MEM_SIZE, per work-item
    std::uint64_t local_bytes = 0;    // CL_KERNEL_LOCAL_MEM_SIZE, per work-group
    std::size_t work_group_size = 0;  // CL_KERNEL_WORK_GROUP_SIZE: the most this kernel allows
    std::size_t preferred_multiple = 0;  // CL_KERNEL_PREFERRED_WORK_GROUP_SIZE_MULTIPLE
};

// OpenCL event profiling (RenderOptions::profile_commands): the device time
// (CL_PROFILING_COMMAND_START to _END) of one kind of command in a frame.
struct CommandTime {
    // A kernel's name, or "write counters", "read counters", "read image"; where a frame sums
    // pixels in an accumulator (several samples, or bounces on a GPU), "fill image" and "resolve image".
    std::string command;
    int level = 0;        // a trace kernel's bounce level (1: camera rays); 0 for every other command
    std::uint64_t count = 0;  // launches or transfers
    double device_ms = 0.0;   // summed over them
};

// What one device (or one cluster rank) did for a frame rendered in tiles
// (kdrt/tiled_render.h).
struct DeviceShare {
    std::string device_name;  // as RenderResult::device_name; for a rank, prefixed "rank N (host): "
    std::uint64_t tiles = 0, pixels = 0;
    double busy_ms = 0.0;     // wall time spent rendering its tiles
    RayCounts rays;
};

struct RenderResult {
    Image image;
    std::vector<std::int32_t> ids;  // first sample's camera hit ids, -1 = none; if want_ids
    std::vector<float> hit_t;       // their distances along the normalised ray
    RayCounts rays;
    SceneFeatures features;
    std::string device_name;
    double build_ms = 0.0;   // kd-tree build (or load) time
    double render_ms = 0.0;  // tracing and shading
    bool tree_loaded = false;  // the tree came from a file or the cache
    double compile_ms = 0.0;   // OpenCL program build, or load from the kernel cache
    double upload_ms = 0.0;    // OpenCL: copying the scene and the tree to the device
    bool kernel_cache_hit = false;
    std::string kernel_options;  // the -D options the kernels were specialised with
    int launches = 0;            // OpenCL kernel launches
    // This frame's own work (a CommittedScene's later frames: 0 when nothing was redone).
    std::uint64_t builds = 0;                 // kd-tree builds
    std::uint64_t compiles = 0;               // OpenCL programs built or loaded from the kernel cache
    std::uint64_t geometry_upload_bytes = 0;  // geometry and tree copied to the device
    std::optional<KdTreeStats> tree_stats;
    std::vector<std::string> warnings;  // what did not stop the render: an unusable tree or kernel cache
    // OpenCL: each kernel of the program, in name order; and kdrt's estimate
    // of the traversal's stack per work-item in bytes (entry size x entries).
    std::vector<KernelResources> kernel_resources;
    std::uint64_t traversal_stack_bytes = 0;
    // OpenCL with RenderOptions::profile_commands: one entry per command and
    // level, in the order first seen; device_busy_ms is the union of their
    // run times, so render_ms - device_busy_ms is the host's share (launch,
    // synchronisation, idle device).
    std::vector<CommandTime> command_times;
    double device_busy_ms = 0.0;
    // A frame rendered in tiles by several devices or ranks: one entry each.
    std::vector<DeviceShare> device_shares;
};

}  // namespace kdrt
