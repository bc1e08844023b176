// kdrt-obj-bench: OBJ load time of kdrt::load_obj_mesh against tinyobjloader's
// own LoadObj (the yardstick of the scale issue), on the same file.
// Runs alternate between the two loaders (A B A B ...) so that machine load
// affects both alike; prints every run and the medians, wall-clock and
// process CPU time (all threads: kdrt parses in parallel, tinyobjloader does not).
//
// Usage: kdrt-obj-bench FILE.obj [RUNS]   (make one with `kdrt-bench generate heightfield:1001 DIR`)
#include "stats.h"

#include <kdrt/error.h>
#include <kdrt/scene_loader.h>

#include <tiny_obj_loader.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

using kdrt::bench::median;

namespace {

struct Times {
    double wall, cpu;
};

template <typename F>
Times seconds(F&& f) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    f();
    return {std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
            double(std::clock() - c0) / CLOCKS_PER_SEC};
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2 || argc > 3) {
        std::fprintf(stderr, "usage: %s FILE.obj [RUNS]\n", argv[0]);
        return 2;
    }
    const std::string path = argv[1];
    const int runs = argc == 3 ? std::max(1, std::atoi(argv[2])) : 5;
    const std::array<double, 16> identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    std::vector<double> kdrt_s, tiny_s, kdrt_cpu, tiny_cpu;
    std::size_t kdrt_triangles = 0, tiny_triangles = 0;
    try {
        for (int r = 0; r < runs; ++r) {
            const Times k = seconds([&] { kdrt_triangles = kdrt::load_obj_mesh(path, identity, 0).size(); });
            const Times t = seconds([&] {
                tinyobj::attrib_t attrib;
                std::vector<tinyobj::shape_t> shapes;
                std::vector<tinyobj::material_t> materials;
                std::string warn, err;
                if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, path.c_str()))
                    throw kdrt::Error(kdrt::ErrorCode::Io, "tinyobjloader: " + err);
                tiny_triangles = 0;
                for (const auto& s : shapes) tiny_triangles += s.mesh.num_face_vertices.size();
            });
            kdrt_s.push_back(k.wall);
            kdrt_cpu.push_back(k.cpu);
            tiny_s.push_back(t.wall);
            tiny_cpu.push_back(t.cpu);
            std::printf("run %d: kdrt %.3f s (cpu %.3f s), tinyobjloader %.3f s (cpu %.3f s)\n", r + 1, k.wall, k.cpu,
                        t.wall, t.cpu);
        }
    } catch (const kdrt::Error& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
    std::printf("%s: %zu triangles (tinyobjloader: %zu)\n", path.c_str(), kdrt_triangles, tiny_triangles);
    std::printf("median of %d interleaved runs: kdrt %.3f s, tinyobjloader %.3f s, ratio %.2f\n", runs,
                median(kdrt_s), median(tiny_s), median(kdrt_s) / median(tiny_s));
    std::printf("median cpu time:               kdrt %.3f s, tinyobjloader %.3f s, ratio %.2f\n",
                median(kdrt_cpu), median(tiny_cpu), median(kdrt_cpu) / median(tiny_cpu));
    return 0;
}
