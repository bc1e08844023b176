#include "kdtree/leaf_blocks.h"

namespace kdrt::detail {

LeafBlocks plan_leaf_blocks(const KdTree& tree, std::uint32_t sphere_count, int lanes, std::size_t max_refs) {
    LeafBlocks plan;
    if (lanes < 1 || lanes > 32 || tree.leaf_objects.empty() || tree.leaf_objects.size() > max_refs) return plan;
    const auto n = static_cast<std::uint32_t>(lanes);
    plan.lanes = lanes;
    plan.leaf_at.assign(tree.leaf_objects.size(), LeafBlocks::kNoLeaf);
    for (const KdNode& node : tree.nodes) {
        if (!kd_is_leaf(node) || kd_leaf_count(node) == 0) continue;
        const std::uint32_t first = kd_leaf_first(node), count = kd_leaf_count(node);
        if (plan.leaf_at[first] != LeafBlocks::kNoLeaf) return LeafBlocks{};
        plan.leaf_at[first] = static_cast<std::uint32_t>(plan.leaves.size());
        LeafBlocks::Leaf leaf{static_cast<std::uint32_t>(plan.block_count()), 0,
                              static_cast<std::uint32_t>(plan.spheres.size()), 0};
        std::uint32_t lane = n;  // no open block
        for (std::uint32_t k = first; k < first + count; ++k) {
            const std::uint32_t id = tree.leaf_objects[k];
            if (id < sphere_count) {
                plan.spheres.push_back(id);
                ++leaf.sphere_count;
                continue;
            }
            if (lane == n) {  // a new block, its every lane this triangle until filled
                plan.block_ids.insert(plan.block_ids.end(), n, id);
                plan.block_lanes.push_back(0);
                ++leaf.block_count;
                lane = 0;
            }
            plan.block_ids[plan.block_ids.size() - n + lane] = id;
            plan.block_lanes.back() |= 1u << lane;
            ++lane;
        }
        plan.leaves.push_back(leaf);
    }
    return plan;
}

}  // namespace kdrt::detail
