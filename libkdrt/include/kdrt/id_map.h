// Comparing camera id maps (FORMAT.md's --aov-ids): how kdrt checks one device
// or traversal against another. Ids may differ only where the reference is on
// a knife's edge: both rays hit and the distances agree to 1e-4 (relative), or
// the pixel lies on a silhouette (a neighbour in the reference sees another
// object), where a one-ulp change in a ray's direction picks the other side.
#pragma once

#include <kdrt/export.h>
#include <kdrt/render_result.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace kdrt {

struct KDRT_API IdMapComparison {
    std::size_t pixels = 0;
    std::size_t mismatches = 0;   // ids that differ
    std::size_t ties = 0;         // ...of which near-equal distances
    std::size_t edges = 0;        // ...of which silhouette pixels (and not ties)
    std::size_t unexplained = 0;  // ...of which neither: a real disagreement
    bool ok() const { return pixels > 0 && unexplained == 0; }
    std::string summary() const;  // "ok, identical" / "ok, 3 of 250000 differ (2 silhouette, 1 tie)" / "FAILED, ..."
};

// Maps of different sizes compare as entirely unexplained.
KDRT_API IdMapComparison compare_id_maps(int width, int height, std::span<const std::int32_t> reference_ids,
                                         std::span<const float> reference_t, std::span<const std::int32_t> ids,
                                         std::span<const float> t);

// The id maps of two renders made with FrameOptions::want_ids.
KDRT_API IdMapComparison compare_id_maps(const RenderResult& reference, const RenderResult& candidate);

}  // namespace kdrt
