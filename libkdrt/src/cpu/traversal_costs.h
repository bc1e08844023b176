// The SAH cost constants of KdBuildConfig measured on the C++ stack traversal
// (kdrt-bench's build table, through detail::traversal_costs in
// render/working_scene_access.h).
#pragma once

#include "cpu/ray.h"
#include "scene/prepared_scene.h"

#include <kdrt/kd_tree.h>

#include <vector>

namespace kdrt::detail {

// What probe_traversal_costs() found: the SAH constants of KdBuildConfig.
struct TraversalCosts {
    double ns_per_step = 0.0;  // one iteration of the stack traversal's loop (inner node or leaf)
    double ns_per_test = 0.0;  // one object test in the visited leaves
    double steps_per_ray = 0.0, tests_per_ray = 0.0;
};

// `rays` walk `tree` with the stack traversal, never stopping at a hit, once
// with the leaves skipped and once testing every object listed; the first
// time per step is the node step, the difference per test the object test.
// Best of `runs`, one thread.
TraversalCosts probe_traversal_costs(const SceneGeometry<float>& geometry, const KdTree& tree,
                                     const std::vector<Ray<float>>& rays, int runs);

}  // namespace kdrt::detail
