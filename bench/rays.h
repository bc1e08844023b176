// `kdrt-bench rays`: ray throughput on meshes, without shading. Coherent
// camera rays (one per pixel of the scene's camera) and incoherent rays
// (origins uniform in the bounds, directions uniform on the sphere, seeded),
// closest hit and any hit: kdrt's public queries (kdrt::intersect and
// kdrt::occluded on a CommittedScene) on the cpu device and on an OpenCL
// device, on the kd-tree and on the BVH, beside Embree's
// rtcIntersect1/rtcOccluded1 and their 16-wide packets (and rtcIntersect1 on
// Embree's spatial-split build). Every tracer's ids are checked against rtcIntersect1's before
// anything is timed; then the tracers take turns, one pass each per round.
#pragma once

#include "common.h"

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct RaysOptions {
    int runs = 5;
    int threads = 0;                     // every tracer; 0: every logical CPU
    int camera_size = 1000;              // camera rays: camera_size^2
    std::size_t random_rays = 1000000;   // incoherent rays
    std::vector<std::string> meshes{"torus:100k", "torus:1M", "heightfield:1001", "layers:32"};
    std::vector<std::string> accels{"kd", "bvh"};  // kdrt's structures, each on every device
    std::vector<std::string> scenes;     // scene files or names besides the meshes (none by default)
    std::filesystem::path scenes_dir;
    std::vector<std::string> devices;    // kdrt devices; empty: cpu and the first OpenCL device
    std::string embree_quality = "medium";
    // Also Embree's rtcIntersect1 on its high-quality build, which uses spatial
    // splits (SBVH), beside the medium one: what they would give these meshes.
    bool embree_high = true;
    double intersection_cost = 0.0;      // SAH triangle cost for every device's tree; 0: each device's own
    // Where each one-mesh input's triangles, rays and Embree's hits are written
    // for another tracer (bench/warp_rays.py); empty: nowhere.
    std::filesystem::path export_dir;
    // Each OpenCL device also on rays already in its memory (kdrt/opencl_interop.h):
    // the query alone, without the upload and read-back of host arrays.
    bool device_buffers = false;
};

// {"settings", "trees": the cpu device's structures, one per mesh and accel, "rows": one per mesh, ray set and query}.
Json run_rays(const RaysOptions& options);

}  // namespace kdrt::bench
