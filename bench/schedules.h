// `kdrt-bench schedules`: what each OpenCL execution choice saves, per scene
// and device, against the default (persistent threads, kernels specialised to
// the scene, tiled ray order, the device's default work-group size; stack
// traversal over the SAH tree): plain scheduling, the generic kernel
// (RenderOptions::all_features), rows and Morton ray orders, and work-group
// sizes 8, 16, 32 and 64. Every variant's id map is checked against the
// default's before it is timed.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct SchedulesOptions {
    bool quick = false;
    int runs = 3;
    int width = 500, height = 500;
    int max_depth = 15;
    std::vector<std::string> devices;  // empty: every OpenCL device
    std::vector<std::string> scenes;
    std::filesystem::path scenes_dir;
    std::filesystem::path out = "bench/results";
};

int run_schedules(const SchedulesOptions& options);

}  // namespace kdrt::bench
