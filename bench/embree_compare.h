// `kdrt-bench embree`: kdrt side by side with Embree 3 in one run, per scene.
//  - whole render: kdrt on each device (one traversal and tree) against the
//    Embree renderer (same shading contract, same thread count), runs
//    interleaved, medians, ratios;
//  - raw closest-hit throughput of the camera rays: kdrt's public ray
//    queries per traversal (single- and multi-threaded) against
//    rtcIntersect1 on the same rays, and the same queries on each OpenCL
//    device;
//  - images: Embree's against kdrt's (RMSE), and the harness itself
//    (WorkingScene::shade over kdrt's own traversal) against the cpu device.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct EmbreeCompareOptions {
    bool quick = false;
    int runs = 5;
    int width = 500, height = 500;
    int max_depth = 15;
    int threads = 0;
    std::string traversal = "stack";
    std::string tree = "sah";
    std::vector<std::string> devices;  // kdrt devices; empty: cpu and every OpenCL device
    std::vector<std::string> scenes;
    std::filesystem::path scenes_dir;
    std::filesystem::path out = "bench/results";
};

int run_embree_compare(const EmbreeCompareOptions& options);

}  // namespace kdrt::bench
