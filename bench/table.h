// `kdrt-bench table`: the study's table rebuilt. Rows: device (cpu, each
// OpenCL device) x traversal (none, restart, ropes, stack) x tree (the study's
// median builder at depth 10, SAH; none has no tree), plus Embree under the
// same shading contract and the study's own figures for reference. Columns:
// the scenes. Each configuration's camera id map is validated against the
// cpu/none reference before it is timed; each cell is the median of N runs
// after one warm-up.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct TableOptions {
    bool quick = false;               // 64x64, 1 run, ball-o-calypse's none skipped
    int runs = 5;
    int width = 500, height = 500;
    int max_depth = 15;
    int threads = 0;                  // cpu device and Embree: 0 = every logical CPU
    std::vector<std::string> devices;  // empty: cpu and every OpenCL device
    std::vector<std::string> scenes;   // empty: the study's five
    std::filesystem::path scenes_dir;
    std::filesystem::path out = "bench/results";
    double none_limit_s = 60.0;       // brute force cells estimated above this are not run
    bool embree = true;               // the Embree row, when built with Embree
    bool cold_compile = true;         // measure cold kernel compiles in child processes
};

int run_table(const TableOptions& options);

// "500x500" -> 500, 500; throws kdrt::Error(InvalidArgument).
void parse_size(const std::string& text, int& width, int& height);

// cpu followed by every OpenCL device's id.
std::vector<std::string> all_device_ids();

}  // namespace kdrt::bench
