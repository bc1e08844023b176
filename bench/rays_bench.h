// `kdrt-bench rays`: raw ray throughput on big generated meshes (issue 5):
// tori of 100k and 1M triangles and a ~2M-triangle heightfield; coherent
// camera rays (one per pixel of a pinhole camera) and incoherent rays
// (origins uniform in the bounds, directions uniform on the sphere, seeded);
// closest hit and any hit. kdrt's public ray queries (kdrt::intersect and
// kdrt::occluded on the cpu device, over the default tree) next to Embree's
// rtcIntersect1/rtcOccluded1 and rtcIntersect16/rtcOccluded16, on as many threads;
// OpenCL devices through a depth-1 render without lights (camera rays only).
// Hit ids are validated against Embree's before anything is timed.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct RaysBenchOptions {
    bool quick = false;
    int runs = 5;
    int threads = 0;
    int camera_size = 1000;             // camera rays: camera_size^2
    std::size_t random_rays = 1000000;  // incoherent rays
    std::vector<std::string> meshes{"torus:100k", "torus:1M", "heightfield:1001"};
    std::vector<std::string> devices;   // OpenCL devices for the camera-ray render; empty: every one
    std::string embree_quality = "medium";  // Embree's build quality: low, medium (its default), high
    std::string traversal = "stack";
    double intersection_cost = 0.0;     // SAH intersection cost; 0: build_kd_tree's default
    std::filesystem::path out = "bench/results";
};

int run_rays_bench(const RaysBenchOptions& options);

}  // namespace kdrt::bench
