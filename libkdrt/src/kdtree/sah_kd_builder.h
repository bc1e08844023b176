// The surface area heuristic kd-tree builder, O(N log N) after Wald and Havran
// 2006 (see sah_kd_builder.cpp).
#pragma once

#include "kdtree/kd_build_common.h"

#include <kdrt/kd_tree.h>

#include <span>

namespace kdrt::detail {

// Uses the SAH constants of config (traversal_cost, intersection_cost,
// empty_bonus) and config.max_depth (0: sah_automatic_max_depth). Splits
// "perfectly" with input.clip when it is set. Builds nodes, leaves and leaf
// lists; no ropes. At most 2^30 objects (kdrt::Error(Unsupported) beyond).
KdTree build_exact_sah_kd_tree(const KdBuildInput& input, const KdBuildConfig& config);

// The automatic depth limit for n objects: round(8 + 1.3 log2 n), at most 64.
int sah_automatic_max_depth(std::size_t n);

// The exact sweep over one subtree (the binned builder's small nodes): refs
// are the node's objects clipped to `cell`; the subtree is appended to `out`
// depth-first, with the depth limit and allowance it inherits.
void build_exact_sah_subtree(KdBuildContext& ctx, int max_depth, double empty_bonus, std::span<const KdRef> refs,
                             const Aabb& cell, int depth, double allowance, KdTree& out);

}  // namespace kdrt::detail
