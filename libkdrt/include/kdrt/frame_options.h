// What each frame asks for (CommittedScene::render, MultiDeviceScene::render,
// render_tiles, the one-call render()): its size, depth and samples, the
// pixels wanted, the id map, the threads, the OpenCL execution, progress.
// What is fixed at commit is in kdrt/commit_options.h.
#pragma once

#include <kdrt/export.h>

#include <functional>
#include <optional>
#include <string>

namespace kdrt {

// OpenCL scheduling. Persistent: persistent threads (Aila and Laine 2009) in
// the device's best form: on a CPU device each work-item traces its camera
// rays' whole ray trees, depth first; on a GPU rays wait in a queue per
// bounce level, one launch per level. Wavefront: persistent threads with the
// queues on every device. Plain: one work-item per ray, with the queues.
enum class Schedule { Persistent, Plain, Wavefront };
// The order camera rays are issued in (OpenCL): neighbouring work-items trace
// neighbouring pixels with tiles or a Morton curve.
enum class RayOrder { Rows, Tiles, Morton };

KDRT_API const char* to_string(Schedule s);
KDRT_API Schedule schedule_from_string(const std::string& name);    // names: kdrt/enum_names.h; throws
KDRT_API const char* to_string(RayOrder o);
KDRT_API RayOrder ray_order_from_string(const std::string& name);   // names: kdrt/enum_names.h; throws

// A rectangle of pixels of a frame: columns [x, x + width), rows [y, y + height),
// row 0 at the top (FORMAT.md's image order).
struct PixelRect {
    int x = 0, y = 0, width = 0, height = 0;
    friend bool operator==(const PixelRect&, const PixelRect&) = default;
};

// How a frame runs on an OpenCL device (ignored by the cpu device).
struct OpenClExecution {
    Schedule schedule = Schedule::Persistent;
    RayOrder ray_order = RayOrder::Tiles;
    double max_launch_ms = 200.0;   // split work so that no kernel launch runs longer (display watchdogs)
    int local_size = 0;             // work-group size, 0 = the device's default choice
    int work_groups_per_unit = 0;   // persistent threads: groups per compute unit, 0 = default (4)
    // Time every command of the frame with OpenCL event profiling, on a queue
    // of the frame's own (OpenClStats::command_times). Off: no cost at all.
    bool profile_commands = false;
};

struct FrameOptions {
    // 0 keeps the scene's settings.
    int width = 0, height = 0, max_depth = 0, samples = 0;
    // Render only these pixels of the width x height frame. The result's
    // image, ids and hit_t are region-sized, and each pixel is bit for bit
    // what the whole frame's render gives it on the same device with the same
    // options. A region not inside the frame, or empty, is an
    // Error(InvalidArgument). Unset: the whole frame.
    std::optional<PixelRect> region;
    bool want_ids = false;     // fill RenderResult::ids / hit_t
    int threads = 0;           // cpu device: worker threads, 0 = all cores
    OpenClExecution opencl;
    // Called with the finished fraction in [0, 1] of the frame, from the
    // calling thread; returning false cancels: the render then throws
    // kdrt::Error(Cancelled) soon after (within ~100 ms), having joined its
    // workers and written nothing.
    std::function<bool(double)> progress;
};

}  // namespace kdrt
