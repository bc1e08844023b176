// Building BVHs: binned SAH over the objects' boxes (bvh_binned_sah_builder.cpp),
// then the collapse to a wide BVH (bvh_collapse.cpp). Builders see only boxes.
#pragma once

#include "bvh/bvh.h"

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

struct BvhBuildConfig {
    // Binned SAH (Wald 2007): centroid bins per axis for a node's split, [4, 256].
    // A node of n objects bins into min(bins, max(n, 8)).
    int bins = 32;
    // The most objects in a leaf, [1, 64]; a node of at most this many becomes
    // a leaf when the SAH finds no cheaper split.
    int max_leaf_size = 8;
    // SAH cost constants, in units of one box test of a binary node (> 0,
    // at most 1e6). A node's split costs traversal_cost plus its children's
    // object costs weighted by their area; a leaf costs its objects'.
    // Leaves are tested leaf_block triangles at a time (the cpu device's leaf
    // test batches 4 or 8, as Embree's leaves hold blocks of 4): a leaf of n
    // triangles costs ceil(n / leaf_block) triangle tests; 1, 2, 4, 8 or 16.
    double traversal_cost = 1.0;
    double intersection_cost = 1.0;         // one triangle test (one block of leaf_block)
    double sphere_intersection_cost = 1.0;  // one sphere test
    int leaf_block = 4;
    int threads = 0;  // build threads, [0, 1024], 0 = all; the BVH is the same for any count
    // Called now and then with the fraction done, from one builder thread at a
    // time; returning false cancels the build, which then throws kdrt::Error(Cancelled).
    std::function<bool(double)> progress;

    void validate() const;  // throws kdrt::Error(InvalidArgument) naming the bad field
};

// The binary BVH. Throws kdrt::Error(InvalidArgument) for a bad config or a box
// out of range, Unsupported beyond 2^31 - 1 objects, Cancelled when cancelled.
Bvh2 build_bvh2(const BvhBuildInput& input, const BvhBuildConfig& config = {});

// Collapses a binary BVH to N children per node, greedily as Embree does: a
// node's slots start as its two children, and the inner slot of largest area
// is replaced by its two children until N are filled or only leaves remain.
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
