// `kdrt-bench povray` (the converter's command) and `kdrt-bench
// povray-compare`: POV-Ray 3.7 (`povray +W +H -D -A`, no anti-aliasing, all
// cores) against kdrt-render, both timed as whole processes from start to
// PNG, kdrt with its kernels cached (a warm-up run fills the cache first).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

int run_povray_export(const std::filesystem::path& scene, const std::filesystem::path& out, int width, int height);

struct PovrayCompareOptions {
    bool quick = false;
    int runs = 3;
    int width = 500, height = 500;
    std::filesystem::path kdrt_render;   // empty: located as for `startup`
    std::filesystem::path povray = "povray";
    std::vector<std::string> devices;    // kdrt devices; empty: every OpenCL device, then cpu
    std::vector<std::string> scenes;
    std::filesystem::path scenes_dir;
    std::filesystem::path out = "bench/results";
};

int run_povray_compare(const PovrayCompareOptions& options);

}  // namespace kdrt::bench
