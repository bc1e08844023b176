// Validation before timing: a configuration's camera id map against the
// reference's (the C++ renderer without a tree), with the library's
// kdrt::compare_id_maps (ties and silhouette pixels allowed, nothing else).
#pragma once

#include <kdrt/id_map.h>

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

using IdCheck = IdMapComparison;

inline IdCheck compare_ids(const IdMap& reference, const IdMap& candidate) {
    if (candidate.width != reference.width || candidate.height != reference.height) {
        IdCheck c;
        c.pixels = c.mismatches = c.unexplained = std::max<std::size_t>(reference.ids.size(), 1);
        return c;
    }
    return compare_id_maps(reference.width, reference.height, reference.ids, reference.t, candidate.ids, candidate.t);
}

}  // namespace kdrt::bench
