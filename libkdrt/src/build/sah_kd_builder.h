// The surface area heuristic kd-tree builder, O(N log N) after Wald and Havran
// 2006 (see sah_kd_builder.cpp).
#pragma once

#include <kdrt/kd_tree.h>

namespace kdrt {

class SahKdBuilder {
public:
    // Uses the SAH constants of config (traversal_cost, intersection_cost,
    // empty_bonus) and config.max_depth (0: 8 + 1.3 log2 N, rounded). Splits
    // "perfectly" with input.clip when it is set. Builds nodes, leaves and leaf
    // lists; no ropes. At most 2^30 objects (kdrt::Error(Unsupported) beyond).
    static KdTree build(const KdBuildInput& input, const KdBuildConfig& config);

    // The automatic depth limit for n objects: round(8 + 1.3 log2 n), at most 64.
    static int automatic_max_depth(std::size_t n);
};

}  // namespace kdrt
