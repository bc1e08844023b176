// `kdrt-bench frames`: what a second frame with a moved camera costs against
// the first (issue 10). A device is opened, a CommittedScene committed on it
// and frame 1 rendered; then the camera orbits its look-at point by a few degrees per frame,
// CommittedScene::update() takes it and frames 2..k are rendered. For each
// frame: the wall time of open() and commit(), or update(), plus render(), update()'s
// own time, and the frame's own builds, compiles and geometry upload bytes (RenderResult), on the cpu
// device and on OpenCL, for the study's scenes and a big mesh.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct FramesBenchOptions {
    int frames = 4;            // frame 1 and k - 1 frames with a moved camera
    int runs = 3;              // the whole sequence, each on a fresh device; medians per frame
    int size = 0;              // square image side; 0: the scenes' own size
    double step_degrees = 10.0;
    std::vector<std::string> devices;  // empty: cpu, and "opencl" when there is one
    std::vector<std::string> scenes;   // empty: the study's five; "none": none
    std::filesystem::path scenes_dir;
    std::vector<std::string> meshes{"torus:1M"};
    double intersection_cost = 0.0;  // SAH triangle cost for every device's tree; 0: each device's own
    std::filesystem::path out = "bench/results";
};

int run_frames_bench(const FramesBenchOptions& options);

}  // namespace kdrt::bench
