// Statistics of a wide BVH, and its SAH cost.
#pragma once

#include "bvh/bvh.h"

#include <cstddef>

namespace kdrt {

// The surface area heuristic's estimate of a ray's work (Goldsmith and Salmon
// 1987, MacDonald and Booth 1990): the wide-node visits plus object tests of a
// ray that crosses the root's box and never stops at a hit. The root costs
// one visit; each used slot, entered with probability area(slot) /
// area(root), one node visit (inner slot) or one test per object (leaf). Does
// not depend on the scene's scale. For a BVH whose root box has no area (all
// objects in a point or a line), every slot counts as entered.
template <int N>
double bvh_sah_cost(const WideBvhN<N>& bvh);

struct BvhStats {
    std::size_t nodes = 0;        // wide nodes
    std::size_t leaves = 0;       // leaf slots
    std::size_t empty_slots = 0;  // slots holding nothing
    int depth = 0;                // wide levels from the root to the deepest leaf (a root alone: 1)
    double mean_leaf_size = 0.0;  // objects per leaf
    double sah_cost = 0.0;        // bvh_sah_cost
    double build_sah_cost = 0.0;  // the BVH's build_sah_cost (after a refit they differ)
    std::size_t node_bytes = 0, leaf_object_bytes = 0;
    std::size_t objects = 0;  // the BVH's object count, the "per object" denominator
    std::size_t total_bytes() const { return node_bytes + leaf_object_bytes; }
    // Bytes per object (per triangle in a mesh scene); 0 for a BVH over no objects.
    double per_object(std::size_t bytes) const {
        return objects ? static_cast<double>(bytes) / static_cast<double>(objects) : 0.0;
    }
};

template <int N>
BvhStats bvh_stats(const WideBvhN<N>& bvh);

// The deepest leaf of a binary BVH (the root alone: 0; none: -1).
int bvh2_depth(const Bvh2& bvh);

extern template double bvh_sah_cost<4>(const WideBvhN<4>&);
extern template double bvh_sah_cost<8>(const WideBvhN<8>&);
extern template BvhStats bvh_stats<4>(const WideBvhN<4>&);
extern template BvhStats bvh_stats<8>(const WideBvhN<8>&);

}  // namespace kdrt
