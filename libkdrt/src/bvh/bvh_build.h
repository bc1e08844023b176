// Building BVHs: binned SAH over the objects' boxes (bvh_binned_sah_builder.cpp),
// then the collapse to a wide BVH (bvh_collapse.cpp). Builders see only boxes.
#pragma once

#include "bvh/bvh.h"

#include <kdrt/bvh_config.h>

#include <kdrt/aabb.h>

#include <cstdint>
#include <functional>
#include <span>

namespace kdrt {

// What the builder sees of the scene: one box per object id, and which ids
// are spheres (the SAH costs their tests apart). Objects with an empty box
// (Aabb{}) are left out of the hierarchy (no ray can hit them); every other
// object is in exactly one leaf. A box with a NaN, or reaching beyond the
// float range, is refused.
struct BvhBuildInput {
    std::span<const Aabb> bounds;  // conservative bounds of each object id; must outlive the build
    std::uint32_t sphere_count = 0;  // objects [0, sphere_count) are spheres, the rest triangles
};


// The binary BVH. Throws kdrt::Error(InvalidArgument) for a bad config or a box
// out of range, Unsupported beyond 2^31 - 1 objects, Cancelled when cancelled.
Bvh2 build_bvh2(const BvhBuildInput& input, const BvhBuildConfig& config = {});

// Collapses a binary BVH to N children per node: each wide node's slots are
// the cut of at most N binary nodes below it that makes the summed area of
// all wide nodes least (found by dynamic programming over the whole tree).
// Leaves and leaf_objects stay as they are. Sets build_sah_cost, summed on
// `threads` (as in BvhBuildConfig); the rest is serial, a few percent of a build.
template <int N>
WideBvhN<N> collapse_bvh(const Bvh2& bvh, int threads = 0);

// build_bvh2 then collapse_bvh: the BVH the cpu device traverses.
template <int N = kWideBvhWidth>
WideBvhN<N> build_wide_bvh(const BvhBuildInput& input, const BvhBuildConfig& config = {}) {
    return collapse_bvh<N>(build_bvh2(input, config), config.threads);
}

extern template WideBvhN<4> collapse_bvh<4>(const Bvh2&, int);
extern template WideBvhN<8> collapse_bvh<8>(const Bvh2&, int);

}  // namespace kdrt
