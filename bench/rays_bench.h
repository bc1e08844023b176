// `kdrt-bench rays`: raw ray throughput (issue 5, issue 10) over the study's
// scenes and big generated meshes (tori of 100k and 1M triangles, a ~2M-triangle
// heightfield): coherent camera rays (one per pixel of the scene's camera) and
// incoherent rays (origins uniform in the bounds, directions uniform on the
// sphere, seeded); closest hit and any hit. kdrt's public ray queries
// (kdrt::intersect / kdrt::occluded on a CommittedScene) on the cpu device and
// on an OpenCL device (host spans, and the application's cl_mem buffers), next
// to Embree's rtcIntersect1/rtcOccluded1 and rtcIntersect16/rtcOccluded16.
// Every tracer's hit ids are validated against rtcIntersect1's before
// anything is timed.
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
    std::vector<std::string> scenes;    // study scenes (names or files); empty: the study's five; "none": none
    std::filesystem::path scenes_dir;
    std::vector<std::string> meshes{"torus:100k", "torus:1M", "heightfield:1001"};
    std::vector<std::string> devices;   // the OpenCL device for the queries ("opencl", "opencl:1", ...), or "cpu"
                                        // only; empty: "opencl" when there is one
    std::string embree_quality = "medium";  // Embree's build quality: low, medium (its default), high
    std::string traversal = "stack";
    double intersection_cost = 0.0;     // SAH intersection cost; 0: build_kd_tree's default
    std::filesystem::path out = "bench/results";
};

int run_rays_bench(const RaysBenchOptions& options);

}  // namespace kdrt::bench
