// The SAH cost constants of KdBuildConfig measured on the C++ stack traversal
// (behind kdrt::WorkingScene::traversal_costs, kdrt/working_scene.h, which
// also defines the TraversalCosts it returns).
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
