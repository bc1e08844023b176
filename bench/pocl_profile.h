// `kdrt-bench pocl-profile`: where an OpenCL device's render time goes, per
// scene and command (camera generation, the trace-and-shade kernel per bounce
// level, the queue counters' transfers, the image read), from OpenCL event
// profiling (RenderOptions::profile_commands), beside the host's share
// (render time minus device-busy time: launches, synchronisation, idle) and
// the C++ reference on as many threads as the device has compute units, on
// the same traversal and tree. Profiled, unprofiled and reference runs are
// interleaved; every figure is a median. Each configuration's id map is
// checked against the reference's before it is timed.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct PoclProfileOptions {
    bool quick = false;
    int runs = 5;
    int width = 500, height = 500;
    int max_depth = 15;
    std::string device;                // empty: the first OpenCL device
    std::string traversal = "stack";   // kdrt/enum_names.h names
    std::string precision = "float";
    std::vector<std::string> scenes;
    std::filesystem::path scenes_dir;
    std::filesystem::path out = "bench/results";
};

int run_pocl_profile(const PoclProfileOptions& options);

}  // namespace kdrt::bench
