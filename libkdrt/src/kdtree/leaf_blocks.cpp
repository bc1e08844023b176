#include "kdtree/leaf_blocks.h"

#include "device/kernel_records.h"

namespace kdrt::detail {

std::vector<LeafRange> leaf_ranges(const KdTree& tree) {
    std::vector<LeafRange> leaves;
    for (const KdNode& node : tree.nodes)
        if (kd_is_leaf(node) && kd_leaf_count(node) > 0) leaves.push_back({kd_leaf_first(node), kd_leaf_count(node)});
    return leaves;
}

std::vector<LeafRange> leaf_ranges(const WideBvh& bvh) {
    std::vector<LeafRange> leaves;
    for (const WideBvhNode& node : bvh.nodes)
        for (int slot = 0; slot < WideBvhNode::kWidth; ++slot)
            if (node.is_leaf(slot) && node.leaf_count(slot) > 0) leaves.push_back({node.child[slot], node.leaf_count(slot)});
    return leaves;
}

LeafBlocks plan_leaf_blocks(std::span<const std::uint32_t> leaf_objects, std::span<const LeafRange> leaves,
                            std::uint32_t sphere_count, int lanes, std::size_t max_refs) {
    LeafBlocks plan;
    if (lanes < 1 || lanes > 32 || leaf_objects.empty() || leaf_objects.size() > max_refs) return plan;
    const auto n = static_cast<std::uint32_t>(lanes);
    plan.lanes = lanes;
    plan.leaf_at.assign(leaf_objects.size(), LeafBlocks::kNoLeaf);
    for (const LeafRange& range : leaves) {
        if (plan.leaf_at[range.first] != LeafBlocks::kNoLeaf) return LeafBlocks{};
        plan.leaf_at[range.first] = static_cast<std::uint32_t>(plan.leaves.size());
        LeafBlocks::Leaf leaf{static_cast<std::uint32_t>(plan.block_count()), 0,
                              static_cast<std::uint32_t>(plan.spheres.size()), 0};
        std::uint32_t lane = n;  // no open block
        for (std::uint32_t k = range.first; k < range.first + range.count; ++k) {
            const std::uint32_t id = leaf_objects[k];
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

LeafBlocks plan_leaf_blocks(const KdTree& tree, std::uint32_t sphere_count, int lanes, std::size_t max_refs) {
    if (tree.leaf_objects.empty() || tree.leaf_objects.size() > max_refs) return LeafBlocks{};
    return plan_leaf_blocks(tree.leaf_objects, leaf_ranges(tree), sphere_count, lanes, max_refs);
}

LeafBlocks plan_leaf_blocks(const WideBvh& bvh, std::uint32_t sphere_count, int lanes) {
    return plan_leaf_blocks(bvh.leaf_objects, leaf_ranges(bvh), sphere_count, lanes, bvh.leaf_objects.size());
}

std::vector<WideBvhNode> pack_bvh_nodes(const WideBvh& bvh, const LeafBlocks& plan,
                                        std::vector<LeafBlocks::Leaf>& records) {
    std::vector<WideBvhNode> nodes = bvh.nodes;
    std::size_t next = 0;  // leaf_ranges lists the leaves in slot order, as plan.leaves holds them
    for (WideBvhNode& node : nodes)
        for (int i = 0; i < WideBvhNode::kWidth; ++i) {
            if (!node.is_leaf(i) || node.is_empty(i)) continue;
            const LeafBlocks::Leaf& leaf = plan.leaves.at(next++);
            if (leaf.sphere_count == 0) {
                node.child[i] = leaf.first_block;
                node.count[i] = KDRT_BVH_LEAF_FLAG | leaf.block_count;
            } else {
                node.child[i] = static_cast<std::uint32_t>(records.size());
                node.count[i] = KDRT_BVH_LEAF_FLAG | KDRT_BVH_LEAF_RECORD;
                records.push_back(leaf);
            }
        }
    return nodes;
}

}  // namespace kdrt::detail
