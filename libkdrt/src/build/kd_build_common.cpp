#include "build/kd_build_common.h"

#include <kdrt/error.h>

#include <limits>
#include <string>

namespace kdrt::detail {

Aabb kd_root_cell(const KdBuildInput& input) {
    if (input.bounds.size() > std::numeric_limits<std::uint32_t>::max())
        throw Error(ErrorCode::Unsupported, "kd-tree input: " + std::to_string(input.bounds.size()) +
                                                " objects exceed the 32-bit object id range");
    constexpr double kFloatMax = std::numeric_limits<float>::max();
    Aabb root;
    for (std::size_t id = 0; id < input.bounds.size(); ++id) {
        const Aabb& b = input.bounds[id];
        if (b.empty()) continue;
        for (int k = 0; k < 3; ++k)
            if (!(b.lo[k] >= -kFloatMax && b.hi[k] <= kFloatMax))
                throw Error(ErrorCode::InvalidArgument, "kd-tree input: object " + std::to_string(id) +
                                                            " has bounds that are not finite or exceed the float range");
        root.extend(b);
    }
    return root.empty() ? Aabb{} : round_out_to_float(root);
}

void kd_emit_leaf(KdTree& tree, std::span<const std::uint32_t> ids) {
    auto leaf_index = static_cast<std::uint32_t>(tree.leaves.size());
    auto count = static_cast<std::uint32_t>(ids.size());
    tree.nodes.push_back(kd_make_leaf(leaf_index, count));
    if (tree.leaf_objects.size() + ids.size() > std::numeric_limits<std::uint32_t>::max())
        throw Error(ErrorCode::Unsupported, "kd-tree too large: more than 2^32-1 leaf references");
    tree.leaves.push_back({static_cast<std::uint32_t>(tree.leaf_objects.size()), count});
    tree.leaf_objects.insert(tree.leaf_objects.end(), ids.begin(), ids.end());
}

}  // namespace kdrt::detail
