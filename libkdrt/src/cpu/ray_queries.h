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

#include "scene/prepared_scene.h"

#include <kdrt/render_options.h>
#include <kdrt/shared/kdrt_shared.h>

#include <cstdint>
#include <span>
#include <vector>

namespace kdrt::detail {

// What the queries' loops need (ray_query_tracer.h).
struct RayQuerySetup {
    const PreparedScene& scene;
    const KdTree* tree;
    Traversal traversal;
    Precision precision;
    bool moller, textbook;
    const std::vector<std::uint32_t>& all_ids;  // Traversal::None: every object
};

// The queries in one instruction set (cpu_isa.h); CpuRayQueries picks one.
void ray_queries_intersect_baseline(const RayQuerySetup& setup, std::span<const QueryRay> rays,
                                    std::span<QueryHit> hits);
void ray_queries_occluded_baseline(const RayQuerySetup& setup, std::span<const QueryRay> rays,
                                   std::span<std::uint8_t> occluded);
void ray_queries_intersect_avx2(const RayQuerySetup& setup, std::span<const QueryRay> rays, std::span<QueryHit> hits);
void ray_queries_occluded_avx2(const RayQuerySetup& setup, std::span<const QueryRay> rays,
                               std::span<std::uint8_t> occluded);

class CpuRayQueries {
public:
    // `scene` and `tree` (null for Traversal::None) must outlive this object.
    CpuRayQueries(const PreparedScene& scene, const KdTree* tree, const RenderOptions& options);

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
