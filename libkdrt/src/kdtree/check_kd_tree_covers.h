// check_kd_tree_covers (kdrt/kd_tree.h) for callers whose object boxes are
// costly to list: a big mesh's 2M boxes took longer than loading its tree.
// Only the objects that no leaf references have their box asked for.
#pragma once

#include <kdrt/kd_tree.h>

#include <cstdint>
#include <functional>

namespace kdrt::detail {

// Throws kdrt::Error(CorruptTree) as check_kd_tree_covers does; object_box(id)
// gives the bounds the builder was given for object `id` < tree.object_count.
// The caller has checked that the scene has tree.object_count objects.
void check_kd_tree_covers(const KdTree& tree, const std::function<Aabb(std::uint32_t)>& object_box);

}  // namespace kdrt::detail
