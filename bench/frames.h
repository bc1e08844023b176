// `kdrt-bench frames`: what a later frame of a CommittedScene costs against
// the first. A device is opened, the scene committed and frame 1 rendered;
// then the camera orbits its look-at point a few degrees per frame, update()
// takes it and render() draws frames 2..k. Per frame: the wall time an
// application waits (open + commit, or update, plus render), update()'s own
// time, and the frame's builds, compiles and geometry upload as RenderStats
// reports them; each sequence on a fresh device, medians per frame.
#pragma once

#include "common.h"

#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct FramesOptions {
    int frames = 4;  // frame 1 and frames - 1 with a moved camera
    int runs = 3;    // sequences
    int size = 0;    // square image side; 0: the scenes' own size
    double step_degrees = 10.0;
    std::vector<std::string> devices;  // empty: cpu and the first OpenCL device
    std::vector<std::string> scenes{"ball-o-calypse"};
    std::filesystem::path scenes_dir;
    std::vector<std::string> meshes{"torus:1M"};
};

// {"settings", "sequences": one per input and device, each with its frames}.
Json run_frames(const FramesOptions& options);

}  // namespace kdrt::bench
