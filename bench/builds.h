// `kdrt-bench build`: the kd-tree and BVH builders on their own, against Embree's BVH
// builds over the same float geometry. For each input: the study's median
// builder at depth 10, the exact SAH sweep (serial), and the binned SAH
// builder (the default) on one thread and on every logical CPU; each build's
// time, its peak memory (the process's high-water mark reset before it), the
// ropes' time apart, and the tree's statistics (nodes, depth, SAH cost, bytes).
// The SAH constants are the cpu device's, as its renders and queries build.
// Beside them the BVH builder (a commit with Accel::Bvh on the cpu device,
// its CommitStats::build_ms) on one thread and on every logical CPU.
#pragma once

#include "common.h"

#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct BuildOptions {
    int runs = 3;  // medians of `runs` builds after one warm-up (one build, no warm-up, from 2M objects)
    std::vector<std::string> scenes{"ball-o-calypse"};
    std::filesystem::path scenes_dir;
    std::vector<std::string> meshes{"torus:100k", "torus:1M", "torus:4M"};
};

// {"settings", "rows": one per input and builder, "embree": one per input, "skipped"}.
Json run_build(const BuildOptions& options);

}  // namespace kdrt::bench
