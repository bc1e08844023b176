// What a committed scene's rays are traced through: its kd-tree or its BVH
// (CommitOptions::accel), or neither (Traversal::None without build_tree).
// The dispatch layer owns both; devices see them through this view.
#pragma once

#include "bvh/bvh.h"

#include <kdrt/kd_tree.h>

namespace kdrt::detail {

struct AccelRef {
    const KdTree* kd = nullptr;
    const WideBvh* bvh = nullptr;

    AccelRef() = default;
    AccelRef(const KdTree* tree) : kd(tree) {}  // NOLINT: a kd-tree alone is the common case
    AccelRef(const KdTree* tree, const WideBvh* hierarchy) : kd(tree), bvh(hierarchy) {}
};

}  // namespace kdrt::detail
