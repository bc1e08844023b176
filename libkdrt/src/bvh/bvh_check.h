// Checks of a BVH: everything a traversal relies on, so that a BVH read from a
// file can never make an index go out of bounds, loop or overflow a stack,
// and, given the objects' boxes, that it holds every object it should.
// Each throws kdrt::Error(CorruptTree) naming the first violation.
#pragma once

#include "bvh/bvh.h"

#include <kdrt/aabb.h>

#include <span>

namespace kdrt {

// The structure: at least one node; every child index in range and after
// its parent's, each node reached once from the root (no cycles, no sharing),
// at most kBvhMaxDepth below it; used slots before empty ones, empty slots
// exactly as bvh.h defines them; every leaf range inside leaf_objects, the
// ranges disjoint and covering it; every object id below object_count and
// listed once; boxes finite floats with lo <= hi (or, for a slot whose
// objects all lost their boxes in a refit, the empty box), each enclosing its
// child node's boxes; bounds the union of the root's boxes.
template <int N>
void check_bvh(const WideBvhN<N>& bvh);

// check_bvh, and against the objects' boxes (as given to the builder or the
// refit, one per object id): every object with a non-empty box is in a leaf
// whose box encloses that box rounded outward to floats.
template <int N>
void check_bvh(const WideBvhN<N>& bvh, std::span<const Aabb> object_bounds);

// The same for a binary BVH: structure, then (with the boxes) coverage.
void check_bvh2(const Bvh2& bvh);
void check_bvh2(const Bvh2& bvh, std::span<const Aabb> object_bounds);

extern template void check_bvh<4>(const WideBvhN<4>&);
extern template void check_bvh<8>(const WideBvhN<8>&);
extern template void check_bvh<4>(const WideBvhN<4>&, std::span<const Aabb>);
extern template void check_bvh<8>(const WideBvhN<8>&, std::span<const Aabb>);

}  // namespace kdrt
