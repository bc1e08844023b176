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

// Closest hit of each ray. hits.size() must equal rays.size().
KDRT_API void intersect(const CommittedScene& scene, std::span<const QueryRay> rays, std::span<QueryHit> hits);

// Any hit on (t_min, t_max]: occluded[i] = 1 if ray i hits something, else 0.
KDRT_API void occluded(const CommittedScene& scene, std::span<const QueryRay> rays, std::span<std::uint8_t> occluded);

}  // namespace kdrt
