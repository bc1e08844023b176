// `kdrt-bench build`: the kd-tree builders measured on their own. For the
// five scenes and generated meshes (a tessellated torus of 100k, 1M, 4M
// triangles): median (the study's, depth 10), exact SAH (serial) and binned
// SAH (the default, on 1 and 2 threads) build time and peak RSS, ropes time,
// time per N log2 N, quality (SAH cost under the default cost constants,
// nodes, depth, leaf sizes), bytes per object for nodes, leaf lists and
// ropes, render time at 250x250 (scenes: the cpu device, stack traversal;
// meshes: camera rays only through kdrt::intersect), the cost probe
// behind the SAH constants, and Embree's BVH build (rtcCommitScene) beside it.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct BuildBenchOptions {
    bool quick = false;                 // scenes only and 100k; 1 run
    int runs = 3;
    int render_size = 250;
    int threads = 0;
    std::vector<std::string> scenes;
    std::filesystem::path scenes_dir;
    std::vector<std::string> meshes{"100k", "1M", "4M"};  // triangle counts; k and M suffixes
    std::filesystem::path out = "bench/results";
};

int run_build_bench(const BuildBenchOptions& options);

}  // namespace kdrt::bench
