// A structure's leaves (a kd-tree's or a BVH's) laid out for the leaf tests
// that take a leaf's triangles N at a time: per leaf, its spheres in a list of their own and its triangles
// in blocks of N lanes (Embree's Triangle4/Triangle8 grouping). Only ids: the
// cpu device (cpu/packed_leaves.h) and the OpenCL kernels on CPU devices
// (opencl/cl_scene_buffers.cpp) each store the blocks' vertices their own way.
#pragma once

#include "bvh/bvh.h"

#include <kdrt/kd_tree.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace kdrt::detail {

// Leaf references up to which the renderers pack a structure's leaves: a
// packed leaf holds a copy of each triangle's vertices, and packing takes
// well under a millisecond up to here.
inline constexpr std::size_t kPackedLeafRefsMax = std::size_t{1} << 16;

struct LeafBlocks {
    static constexpr std::uint32_t kNoLeaf = std::numeric_limits<std::uint32_t>::max();

    struct Leaf {
        std::uint32_t first_block, block_count, first_sphere, sphere_count;
    };
    int lanes = 0;                        // N
    std::vector<Leaf> leaves;             // the non-empty leaves, in node order
    std::vector<std::uint32_t> leaf_at;   // by first index into leaf_objects: index into leaves, or kNoLeaf
    std::vector<std::uint32_t> block_ids; // N per block, in leaf order; a block's unused lanes repeat lane 0
    std::vector<std::uint32_t> block_lanes;  // per block, bit k: lane k holds a triangle
    std::vector<std::uint32_t> spheres;   // the leaves' sphere ids, in leaf order

    bool empty() const { return leaves.empty(); }
    std::size_t block_count() const { return block_lanes.size(); }
};

// A leaf of a structure: objects leaf_objects[first .. first + count).
struct LeafRange {
    std::uint32_t first, count;
};

// The non-empty leaves of a kd-tree in node order, of a BVH in slot order.
std::vector<LeafRange> leaf_ranges(const KdTree& tree);
std::vector<LeafRange> leaf_ranges(const WideBvh& bvh);

// The layout of `leaves` (ranges of `leaf_objects`) in blocks of `lanes` triangles (object ids
// from sphere_count on are triangles). Empty when the tree has no leaf
// references, more than max_refs of them, or two leaves whose lists start at
// the same place (a tree file may share them; the builders never do): a leaf
// is found by where its list starts.
LeafBlocks plan_leaf_blocks(std::span<const std::uint32_t> leaf_objects, std::span<const LeafRange> leaves,
                            std::uint32_t sphere_count, int lanes, std::size_t max_refs);
// The same for a kd-tree's leaves.
LeafBlocks plan_leaf_blocks(const KdTree& tree, std::uint32_t sphere_count, int lanes, std::size_t max_refs);
// The same for a BVH's, whatever their number (each object is in one leaf).
LeafBlocks plan_leaf_blocks(const WideBvh& bvh, std::uint32_t sphere_count, int lanes);

// A BVH's nodes with each leaf slot referring to its packed blocks instead of
// its object ids, so that a traversal goes from a node to the triangles with
// no record in between (Embree's leaf pointers): a leaf of triangles becomes
// (first block, KDRT_BVH_LEAF_FLAG | block count); a leaf with spheres
// (first_record, KDRT_BVH_LEAF_FLAG | KDRT_BVH_LEAF_RECORD) with its record
// appended to `records`. `plan` is plan_leaf_blocks(bvh, ...)'s.
std::vector<WideBvhNode> pack_bvh_nodes(const WideBvh& bvh, const LeafBlocks& plan,
                                        std::vector<LeafBlocks::Leaf>& records);

}  // namespace kdrt::detail
