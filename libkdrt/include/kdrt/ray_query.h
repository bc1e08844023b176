// Ray queries on a CommittedScene, the API of Embree's rtcIntersect /
// rtcOccluded and RadeonRays' QueryIntersection / QueryOcclusion, on every
// device. Rays and hits are kdrt::QueryRay and kdrt::QueryHit
// (kdrt/layout.h): world space, 32 bytes each.
//
// The same rays give the same hits on every device, with one exception: when
// two objects are hit at the same t (coplanar or shared edges), which of them
// is reported may differ between devices and traversals.
#pragma once

#include <kdrt/export.h>
#include <kdrt/committed_scene.h>
#include <kdrt/layout.h>

#include <cstdint>
#include <span>

namespace kdrt {

// A ray hits on (max(t_min, 0), t_max]: nothing behind its origin is ever
// reported (as in Embree, whose tnear must be >= 0); a negative t_min acts as 0.

// Closest hit of each ray. hits.size() must equal rays.size().
KDRT_API void intersect(const CommittedScene& scene, std::span<const QueryRay> rays, std::span<QueryHit> hits);

// Any hit in the window: occluded[i] = 1 if ray i hits something, else 0.
KDRT_API void occluded(const CommittedScene& scene, std::span<const QueryRay> rays, std::span<std::uint8_t> occluded);

}  // namespace kdrt
