// The library's way in to a kdrt::WorkingScene (kdrt/working_scene.h
// declares WorkingSceneAccess its friend), for kdrt-bench's measurements.
#pragma once

#include "cpu/traversal_costs.h"
#include "scene/prepared_scene.h"

#include <kdrt/kd_tree.h>
#include <kdrt/working_scene.h>

namespace kdrt::detail {

struct WorkingSceneAccess {
    static const PreparedScene& prepared(const WorkingScene& scene);
};

// The SAH constants of KdBuildConfig as probe_traversal_costs measures them
// over `scene`'s camera rays (one per pixel centre) in `tree`.
TraversalCosts traversal_costs(const WorkingScene& scene, const KdTree& tree, int runs);

}  // namespace kdrt::detail
