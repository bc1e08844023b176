// Ray queries on the C++ reference (kdrt/ray_query.h on device "cpu"):
// closest hit and any hit of world-space QueryRays, in parallel with oneTBB,
// through the committed traversal and precision.
//
// A ray is taken into the working frame in double (origin - frame_origin)
// and traced with its unit direction; t is reported in units of the given
// direction, and the window (t_min, t_max] is applied to that t. Hits have
// t > 0 as well. Invalid rays (a NaN or infinite component, a zero
// direction, a NaN bound, t_min > t_max) miss.
#pragma once

#include "cpu/ray_query_setup.h"
#include "scene/prepared_scene.h"

#include <kdrt/commit_options.h>
#include <kdrt/layout.h>

#include <cstdint>
#include <span>
#include <vector>

namespace kdrt::detail {

class CpuRayQueries {
public:
    // `scene` and `tree` (null for Traversal::None) must outlive this object.
    CpuRayQueries(const PreparedScene& scene, const KdTree* tree, const CommitOptions& options);

    // hits[i] / occluded[i] for rays[i]; object ids are internal (positions
    // in SceneGeometry). The spans have equal sizes. Thread-safe.
    void intersect(std::span<const QueryRay> rays, std::span<QueryHit> hits) const;
    void occluded(std::span<const QueryRay> rays, std::span<std::uint8_t> occluded) const;

private:
    const PreparedScene& scene_;
    const KdTree* tree_;
    Traversal traversal_;
    Precision precision_;
    bool moller_, textbook_;
    std::vector<std::uint32_t> all_ids_;  // Traversal::None: every object
};

}  // namespace kdrt::detail
