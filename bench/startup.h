// `kdrt-bench startup`: from process start to the first kernel launch, by
// running the kdrt-render binary: cold (an empty --kernel-cache directory and
// an empty POCL_CACHE_DIR) and warm (both filled by a previous run), with the
// peak resident memory of the process (wait4's ru_maxrss). The first launch
// is placed at (arrival of the --stats-json line) - render_ms: the render
// clock starts right before the first launch and stops right before the line
// is printed.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct StartupOptions {
    bool quick = false;
    int runs = 3;
    std::filesystem::path kdrt_render;  // empty: found next to kdrt-bench's build dir, or in $PATH
    std::vector<std::string> devices;   // empty: every OpenCL device, then cpu
    std::vector<std::string> scenes;
    std::filesystem::path scenes_dir;
    std::filesystem::path out = "bench/results";
};

int run_startup(const StartupOptions& options);

// The kdrt-render to run: `given` if not empty, else next to this build's
// kdrt-bench, else $PATH. Throws kdrt::Error(Io) when there is none.
std::filesystem::path locate_kdrt_render(const std::filesystem::path& given);

}  // namespace kdrt::bench
