// `kdrt-bench table`: the study's table on its five scenes. Rows: each device x
// (no tree, or each traversal over the study's median tree at depth 10 and
// over the SAH tree), and Embree 3 under the same shading (embree_render.h).
// Before anything is timed, every row's camera id map is checked against the
// cpu device without a tree, Embree's image against the cpu device's, and the
// harness against the cpu device (the same shader over kdrt's own traversal).
// Then the rows take turns, one render each per round, so that a change in the
// machine's load hits all of them: each figure is a median of the rounds.
#pragma once

#include "common.h"

#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct TableOptions {
    int runs = 5;
    int width = 500, height = 500;
    int max_depth = 15;
    int threads = 0;                   // cpu device and Embree; 0: every logical CPU
    std::vector<std::string> devices;  // empty: every device
    std::vector<std::string> scenes;   // empty: the study's five
    std::filesystem::path scenes_dir;
    double none_limit_s = 60.0;        // brute force is left out where a render would take longer
};

// {"settings", "rows": one per scene and configuration, "embree": one per scene,
// "failures": the rows and Embree renders that failed validation or threw}.
Json run_table(const TableOptions& options);

}  // namespace kdrt::bench
