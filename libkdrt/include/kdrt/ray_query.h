// Ray queries on a CommittedScene, the API of Embree's rtcIntersect /
// rtcOccluded and RadeonRays' QueryIntersection / QueryOcclusion, on every
// device. Rays and hits are kdrt::QueryRay and kdrt::QueryHit
// (kdrt/layout.h): world space, 32 bytes each.
//
// The same rays give the same hits on every device, with one exception: when
// two objects are hit at the same t (coplanar or shared edges), which of them
// is reported may differ between devices and traversals.
//
// Rays with a NaN or infinite origin or direction component, a zero
// direction, a NaN bound or t_min > t_max are invalid: they hit nothing (as
// Open3D's and Embree's do), and count no hits.
#pragma once

#include <kdrt/export.h>
#include <kdrt/committed_scene.h>
#include <kdrt/layout.h>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace kdrt {

// A ray hits on (max(t_min, 0), t_max]: nothing behind its origin is ever
// reported (as in Embree, whose tnear must be >= 0); a negative t_min acts as 0.

// Closest hit of each ray. hits.size() must equal rays.size().
KDRT_API void intersect(const CommittedScene& scene, std::span<const QueryRay> rays, std::span<QueryHit> hits);

// Any hit in the window: occluded[i] = 1 if ray i hits something, else 0.
KDRT_API void occluded(const CommittedScene& scene, std::span<const QueryRay> rays, std::span<std::uint8_t> occluded);

// Hits at one point of several primitives of a geometry (a ray through an
// edge or vertex that triangles of a mesh share): the watertight test finds
// at least one of them, and either
//  - EachPrimitive: each primitive's hit counts (a ray through the shared
//    edge of two triangles counts two), or
//  - OncePerGeometry: hits of one geometry at the same t count once (the
//    lowest object id is kept), as Open3D's count_intersections and
//    list_intersections do; a ray through a closed mesh's edge then counts
//    one crossing, so the count's parity tells inside from outside.
enum class CoincidentHits { EachPrimitive, OncePerGeometry };

// How many hits ray i has on (t_min, t_max], into counts[i]: each triangle
// once, however many kd-tree leaves hold it; a sphere once per crossing of
// its surface (twice for a ray through it); coincident hits as `coincident`
// says. counts.size() must equal rays.size().
KDRT_API void count_hits(const CommittedScene& scene, std::span<const QueryRay> rays, std::span<std::uint32_t> counts,
                         CoincidentHits coincident = CoincidentHits::EachPrimitive);

// Every hit of every ray, as count_hits() counts them: ray i's are
// hits[ray_splits[i] .. ray_splits[i + 1]), nearest first (equal t: lower
// object id first).
struct RayHitLists {
    std::vector<std::uint64_t> ray_splits;  // rays.size() + 1 entries, from 0
    std::vector<QueryHit> hits;
};
KDRT_API RayHitLists all_hits(const CommittedScene& scene, std::span<const QueryRay> rays,
                              CoincidentHits coincident = CoincidentHits::EachPrimitive);

// The point of the scene's surface nearest to each point (world space), by a
// nearest-first search of the kd-tree or the BVH (every object without one):
// out[i] for points[i]. Ties aside (points equally near two primitives), the
// same as testing every primitive; in double, or in float on an OpenCL device
// without fp64. A point with a NaN or infinite coordinate, or a scene without
// objects, gets distance +inf and KDRT_NO_HIT ids. out.size() must equal
// points.size().
KDRT_API void closest_points(const CommittedScene& scene, std::span<const std::array<float, 3>> points,
                             std::span<ClosestPoint> out);

}  // namespace kdrt
