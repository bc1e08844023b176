// The SAH cost constants of KdBuildConfig measured on the C++ stack traversal
// (kdrt::measure_traversal_costs, kdrt/working_scene.h).
#pragma once

#include "cpu/ray.h"
#include "scene/prepared_scene.h"

#include <kdrt/kd_tree.h>
#include <kdrt/working_scene.h>

#include <vector>

namespace kdrt::detail {

TraversalCosts probe_traversal_costs(const SceneGeometry<float>& geometry, const KdTree& tree,
                                     const std::vector<Ray<float>>& rays, int runs);

}  // namespace kdrt::detail
