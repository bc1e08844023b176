// kdrt::intersect / occluded / count_hits / all_hits / closest_points on host
// spans: the sizes checked, the device's queries run, internal ids mapped to
// the public object, geometry and primitive ids.
#include "render/committed_scene_state.h"

#include <kdrt/error.h>
#include <kdrt/ray_query.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>

namespace kdrt {

namespace {

void check_sizes(const char* call, std::size_t inputs, const char* input_name, std::size_t outputs) {
    if (inputs != outputs)
        throw Error(ErrorCode::InvalidArgument, std::string(call) + ": " + std::to_string(inputs) + " " + input_name +
                                                    " but room for " + std::to_string(outputs) + " results");
}

// Names hits by their public object, geometry and primitive ids, in parallel for big batches.
void name_hits(const detail::PreparedScene& prepared, std::span<QueryHit> hits) {
    auto name = [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            QueryHit& h = hits[i];
            if (h.object == KDRT_NO_HIT) {
                h.geometry = h.primitive = KDRT_NO_HIT;
                continue;
            }
            prepared.name_object(h.object, h.object, h.geometry, h.primitive);
        }
    };
    if (hits.size() < 65536) return name(0, hits.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, hits.size(), 16384),
                      [&](const tbb::blocked_range<std::size_t>& r) { name(r.begin(), r.end()); });
}

// Drops each hit whose geometry and t equal the hit kept before it on its
// ray (the lists are sorted by t, then object), in place.
void merge_coincident(RayHitLists& lists) {
    const std::size_t rays = lists.ray_splits.size() - 1;
    std::vector<std::uint64_t> kept(rays + 1, 0);
    auto merge_ray = [&](std::size_t r) {
        const std::uint64_t begin = lists.ray_splits[r], end = lists.ray_splits[r + 1];
        std::uint64_t out = begin;
        for (std::uint64_t k = begin; k < end; ++k) {
            const QueryHit& h = lists.hits[k];
            const bool same = out > begin && lists.hits[out - 1].geometry == h.geometry && lists.hits[out - 1].t == h.t;
            if (!same) lists.hits[out++] = h;
        }
        kept[r + 1] = out - begin;
    };
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays, 4096), [&](const tbb::blocked_range<std::size_t>& b) {
        for (std::size_t r = b.begin(); r < b.end(); ++r) merge_ray(r);
    });
    // Compact: ray r's kept hits move down to the sum of the counts before it.
    std::uint64_t to = 0;
    for (std::size_t r = 0; r < rays; ++r) {
        const std::uint64_t from = lists.ray_splits[r], n = kept[r + 1];
        std::copy(lists.hits.begin() + static_cast<std::ptrdiff_t>(from),
                  lists.hits.begin() + static_cast<std::ptrdiff_t>(from + n),
                  lists.hits.begin() + static_cast<std::ptrdiff_t>(to));
        lists.ray_splits[r] = to;
        to += n;
    }
    lists.ray_splits[rays] = to;
    lists.hits.resize(to);
}

}  // namespace

const std::vector<std::uint32_t>& detail::CommittedSceneState::geometry_of() const {
    const std::lock_guard lock(geometry_of_mutex_);
    if (!geometry_of_) {
        std::vector<std::uint32_t> table(prepared.geometry_f.object_count());
        // Isolated: a thread waiting here under the lock must not take up a
        // task of the application's that asks for this table too.
        tbb::this_task_arena::isolate([&] {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, table.size(), 16384),
                              [&](const tbb::blocked_range<std::size_t>& r) {
                                  std::uint32_t object = 0, primitive = 0;
                                  for (std::size_t id = r.begin(); id < r.end(); ++id)
                                      prepared.name_object(static_cast<std::uint32_t>(id), object, table[id],
                                                           primitive);
                              });
        });
        geometry_of_ = std::move(table);
    }
    return *geometry_of_;
}

void intersect(const CommittedScene& scene, std::span<const QueryRay> rays, std::span<QueryHit> hits) {
    check_sizes("intersect", rays.size(), "rays", hits.size());
    const detail::CommittedSceneState& s = detail::CommittedSceneAccess::state(scene, "intersect");
    s.ready_backend().intersect(rays, hits);
    name_hits(s.prepared, hits);
}

void occluded(const CommittedScene& scene, std::span<const QueryRay> rays, std::span<std::uint8_t> occluded) {
    check_sizes("occluded", rays.size(), "rays", occluded.size());
    detail::CommittedSceneAccess::state(scene, "occluded").ready_backend().occluded(rays, occluded);
}

void count_hits(const CommittedScene& scene, std::span<const QueryRay> rays, std::span<std::uint32_t> counts,
                CoincidentHits coincident) {
    check_sizes("count_hits", rays.size(), "rays", counts.size());
    const detail::CommittedSceneState& s = detail::CommittedSceneAccess::state(scene, "count_hits");
    if (coincident == CoincidentHits::EachPrimitive) return s.ready_backend().count_hits(rays, counts);
    // A backend that merges as it counts, given each internal id's geometry.
    if (s.ready_backend().count_hits_once_per_geometry(rays, counts, s.geometry_of())) return;
    // Otherwise the lists, merged and counted.
    const RayHitLists lists = all_hits(scene, rays, coincident);
    for (std::size_t i = 0; i < rays.size(); ++i)
        counts[i] = static_cast<std::uint32_t>(lists.ray_splits[i + 1] - lists.ray_splits[i]);
}

RayHitLists all_hits(const CommittedScene& scene, std::span<const QueryRay> rays, CoincidentHits coincident) {
    const detail::CommittedSceneState& s = detail::CommittedSceneAccess::state(scene, "all_hits");
    RayHitLists lists;
    s.ready_backend().all_hits(rays, lists.ray_splits, lists.hits);
    name_hits(s.prepared, lists.hits);
    if (coincident == CoincidentHits::OncePerGeometry) merge_coincident(lists);
    return lists;
}

void closest_points(const CommittedScene& scene, std::span<const std::array<float, 3>> points,
                    std::span<ClosestPoint> out) {
    check_sizes("closest_points", points.size(), "points", out.size());
    const detail::CommittedSceneState& s = detail::CommittedSceneAccess::state(scene, "closest_points");
    s.ready_backend().closest_points(points, out);
    for (ClosestPoint& c : out)
        if (c.object != KDRT_NO_HIT) s.prepared.name_object(c.object, c.object, c.geometry, c.primitive);
}

}  // namespace kdrt
