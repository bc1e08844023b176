// kdrt's side of the ray-throughput figures through the public API: the rays
// as kdrt::QueryRay (world space), traced by kdrt::intersect / kdrt::occluded
// on a CommittedScene in one call per pass, on a oneTBB arena of the bench's
// thread count (the cpu device runs its queries on oneTBB).
#pragma once

#include <kdrt/committed_scene.h>
#include <kdrt/ray_query.h>
#include <kdrt/working_scene.h>

#include <glm/vec3.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace kdrt::bench {

// The bench's working-frame rays in world space (the frame's origin added
// back), on (0, inf).
std::vector<QueryRay> to_query_rays(const std::vector<ShadingRay>& rays, const glm::dvec3& frame_origin);

// One closest-hit pass: ids[i] (the object, or -1) and ts[i]. Returns the milliseconds.
double time_intersect(const CommittedScene& scene, std::span<const QueryRay> rays, int threads, std::int32_t* ids,
                      float* ts);

// One any-hit pass: ids[i] = 1 if ray i hits something, else 0. Returns the milliseconds.
double time_occluded(const CommittedScene& scene, std::span<const QueryRay> rays, int threads, std::int32_t* ids);

}  // namespace kdrt::bench
