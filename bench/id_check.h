// Validation before timing: a configuration's camera id map against the
// reference's (the C++ renderer without a tree). Ids may differ only where the
// reference itself is on a knife's edge: both rays hit and the distances
// agree to 1e-4 (relative), or the pixel lies on a silhouette (a neighbour in
// the reference sees another object). Anything else is unexplained and fails.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace kdrt::bench {

struct IdMap {
    int width = 0, height = 0;
    std::vector<std::int32_t> ids;  // -1: no hit
    std::vector<float> t;
};

struct IdCheck {
    std::size_t pixels = 0;
    std::size_t mismatches = 0;   // ids that differ
    std::size_t ties = 0;         // ...of which near-equal distances
    std::size_t edges = 0;        // ...of which silhouette pixels (and not ties)
    std::size_t unexplained = 0;  // ...of which neither: a failure
    bool ok() const { return pixels > 0 && unexplained == 0; }
    std::string summary() const;  // "ok, 3 differ (2 silhouette, 1 tie)" / "FAILED: ..."
};

IdCheck compare_ids(const IdMap& reference, const IdMap& candidate);

}  // namespace kdrt::bench
