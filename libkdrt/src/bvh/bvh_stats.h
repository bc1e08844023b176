// Statistics of a wide BVH, and its SAH cost.
#pragma once

#include "bvh/bvh.h"

#include <kdrt/bvh_config.h>

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


template <int N>
BvhStats bvh_stats(const WideBvhN<N>& bvh);

// The deepest leaf of a binary BVH (the root alone: 0; none: -1).
int bvh2_depth(const Bvh2& bvh);

extern template double bvh_sah_cost<4>(const WideBvhN<4>&);
extern template double bvh_sah_cost<8>(const WideBvhN<8>&);
extern template BvhStats bvh_stats<4>(const WideBvhN<4>&);
extern template BvhStats bvh_stats<8>(const WideBvhN<8>&);

}  // namespace kdrt
