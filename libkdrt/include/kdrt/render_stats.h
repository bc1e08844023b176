// What a frame cost and how it ran: rays, times, the work a commit or update
// left to report, the tree, OpenCL's kernels and commands, the devices'
// shares of a tiled frame. RenderResult::stats (kdrt/render_result.h).
#pragma once

#include <kdrt/bvh_config.h>
#include <kdrt/kd_tree.h>
#include <kdrt/scene_features.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace kdrt {

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
// OpenClStats::traversal_stack_bytes for kdrt's own figure.
struct KernelResources {
    std::string kernel;
    std::uint64_t private_bytes = 0;  // CL_KERNEL_PRIVATE_MEM_SIZE, per work-item
    std::uint64_t local_bytes = 0;    // CL_KERNEL_LOCAL_MEM_SIZE, per work-group
    std::size_t work_group_size = 0;  // CL_KERNEL_WORK_GROUP_SIZE: the most this kernel allows
    std::size_t preferred_multiple = 0;  // CL_KERNEL_PREFERRED_WORK_GROUP_SIZE_MULTIPLE
};

// OpenCL event profiling (OpenClExecution::profile_commands): the device time
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
    std::string device_name;  // as RenderStats::device_name; for a rank, prefixed "rank N (host): "
    std::uint64_t tiles = 0, pixels = 0;
    double busy_ms = 0.0;     // wall time spent rendering its tiles
    RayCounts rays;
};

// An OpenCL device's frame (empty on the cpu device).
struct OpenClStats {
    bool kernel_cache_hit = false;
    std::string kernel_options;  // the -D options the kernels were specialised with
    int launches = 0;            // kernel launches
    // Each kernel of the program, in name order; and kdrt's estimate of the
    // traversal's stack per work-item in bytes (entry size x entries).
    std::vector<KernelResources> kernel_resources;
    std::uint64_t traversal_stack_bytes = 0;
    // With OpenClExecution::profile_commands: one entry per command and
    // level, in the order first seen; device_busy_ms is the union of their
    // run times, so RenderStats::render_ms - device_busy_ms is the host's
    // share (launch, synchronisation, idle device).
    std::vector<CommandTime> command_times;
    double device_busy_ms = 0.0;
};

struct RenderStats {
    RayCounts rays;
    SceneFeatures features;
    std::string device_name;
    double build_ms = 0.0;     // the structure's build (or load, or refit) time
    double render_ms = 0.0;    // tracing and shading
    double compile_ms = 0.0;   // OpenCL program build, or load from the kernel cache
    double upload_ms = 0.0;    // OpenCL: copying the scene and the tree to the device
    bool tree_loaded = false;  // the structure came from a file, the cache or memory
    // This frame's own work (a CommittedScene's later frames: 0 when nothing was redone).
    std::uint64_t builds = 0;                 // structure builds (kd-tree or BVH)
    std::uint64_t refits = 0;                 // BVH refits (CommittedScene::update of moved geometry)
    std::uint64_t compiles = 0;               // OpenCL programs built or loaded from the kernel cache
    std::uint64_t geometry_upload_bytes = 0;  // geometry and tree copied to the device
    std::optional<KdTreeStats> tree_stats;  // Accel::KdTree
    std::optional<BvhStats> bvh_stats;      // Accel::Bvh
    OpenClStats opencl;
    // A frame rendered in tiles by several devices or ranks: one entry each.
    std::vector<DeviceShare> device_shares;
};

}  // namespace kdrt
