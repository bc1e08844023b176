// What the cpu device's ray queries hand to their work (ray_query_tracer.h),
// and that work in each instruction set (cpu_isa.h): CpuRayQueries
// (ray_queries.h) picks one per call.
#pragma once

#include "scene/prepared_scene.h"

#include <kdrt/commit_options.h>
#include <kdrt/layout.h>

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

// The queries in one instruction set.
void ray_queries_intersect_baseline(const RayQuerySetup& setup, std::span<const QueryRay> rays,
                                    std::span<QueryHit> hits);
void ray_queries_occluded_baseline(const RayQuerySetup& setup, std::span<const QueryRay> rays,
                                   std::span<std::uint8_t> occluded);
void ray_queries_intersect_avx2(const RayQuerySetup& setup, std::span<const QueryRay> rays, std::span<QueryHit> hits);
void ray_queries_occluded_avx2(const RayQuerySetup& setup, std::span<const QueryRay> rays,
                               std::span<std::uint8_t> occluded);

}  // namespace kdrt::detail
