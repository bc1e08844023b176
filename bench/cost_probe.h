// The SAH cost constants measured on the cpu device: what one kd-tree node
// step, one ray-triangle test and one ray-sphere test cost, in nanoseconds,
// over the leaves a real traversal visits (see cost_probe.cpp).
#pragma once

#include "cpu/ray.h"
#include "scene/prepared_scene.h"

#include <kdrt/kd_tree.h>

#include <vector>

namespace kdrt::bench {

struct CostProbe {
    double ns_per_step = 0.0;    // one iteration of the stack traversal's loop (inner node or leaf)
    double ns_per_test = 0.0;    // one object test in the visited leaves
    double steps_per_ray = 0.0, tests_per_ray = 0.0;
};

// Traces `rays` through `tree` (stack traversal, never stopping at a hit) once
// with leaves skipped and once testing every listed object: the first run's
// time per step is the node step, the difference per test the object test.
// Best of `runs`.
CostProbe probe_costs(const detail::PreparedScene& scene, const KdTree& tree,
                      const std::vector<detail::Ray<float>>& rays, int runs);

}  // namespace kdrt::bench
