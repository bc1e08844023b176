// kdrt::intersect / kdrt::occluded on host spans: the sizes checked, the
// device's queries run, internal ids mapped to the public ones.
#include "render/committed_scene_state.h"

#include <kdrt/error.h>
#include <kdrt/ray_query.h>

namespace kdrt {

void intersect(const CommittedScene& scene, std::span<const QueryRay> rays, std::span<QueryHit> hits) {
    if (rays.size() != hits.size())
        throw Error(ErrorCode::InvalidArgument, "intersect: " + std::to_string(rays.size()) + " rays but room for " +
                                                    std::to_string(hits.size()) + " hits");
    const detail::CommittedSceneState& s = detail::CommittedSceneAccess::state(scene, "intersect");
    s.ready_backend().intersect(rays, hits);
    if (!s.prepared.public_ids.empty())
        for (QueryHit& h : hits)
            if (h.object != KDRT_NO_HIT) h.object = s.prepared.public_id(h.object);
}

void occluded(const CommittedScene& scene, std::span<const QueryRay> rays, std::span<std::uint8_t> occluded) {
    if (rays.size() != occluded.size())
        throw Error(ErrorCode::InvalidArgument, "occluded: " + std::to_string(rays.size()) +
                                                    " rays but room for " + std::to_string(occluded.size()) +
                                                    " results");
    detail::CommittedSceneAccess::state(scene, "occluded").ready_backend().occluded(rays, occluded);
}

}  // namespace kdrt
