// A structure's leaves (kd-tree or BVH) repacked for one ray's leaf test:
// each leaf's triangles in blocks of N, their vertices stored by component
// with a lane per triangle (Embree's Triangle4/Triangle8 layout), and its
// spheres in a list of their own. A block is then nine vector loads instead
// of 9 N scalar loads gathered into lanes, and the leaf's ids need no walk to
// sort spheres from triangles.
//
// A commit builds it once: for a BVH always (each triangle is in one leaf,
// so the copy costs about its vertices once more), for a kd-tree only with
// few enough leaf references (kMaxPackedRefs: a kd-tree repeats triangles in
// leaves); bigger kd-trees keep test_leaf_ray. A BVH gets a copy of its
// nodes whose leaf slots refer to their blocks, as Embree's leaf pointers
// do: a ray goes from a node to the triangles with no record in between.
// Duplicated triangles are not mailboxed here: testing one again gives the
// same hit, which the callers' closest-hit and any-hit rules ignore, so the
// result is the same either way. The OpenCL kernels on CPU devices read the
// same layout in blocks of four (visit_packed_leaf in cl/visit_objects.cl).
#pragma once

#include "common/debug_assert.h"
#include "cpu/intersect_packet.h"
#include "device/kernel_records.h"
#include "kdtree/leaf_blocks.h"

#include <kdrt/kd_tree.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace kdrt::detail::inline KDRT_CPU_ISA {

template <class Real, int N>
class PackedLeaves {
public:
    using V = typename PacketShear<Real, N>::V;
    typedef std::int32_t Ids __attribute__((vector_size(sizeof(std::int32_t) * N)));

    // Leaf references (tree.leaf_objects) up to which packing pays per frame.
    static constexpr std::size_t kMaxPackedRefs = kPackedLeafRefsMax;

    // Aligned by hand: GCC gives 32-byte vector types 16-byte alignment in
    // code built without AVX, such as std::allocator's, while the AVX2 copy's
    // loads assume 32. Blocks of 32-byte vectors (the AVX2 copy's, and the
    // baseline copy's in double: 320 bytes) are aligned to cache lines, five
    // whole lines each, which prefetch_object fetches without counting.
    struct alignas(sizeof(V) >= 32 ? 64 : 16) Block {
        V v[3][3];  // v[vertex][axis], a triangle per lane; unused lanes repeat lane 0's triangle
        Ids id;     // the lanes' object ids; -1 in unused lanes
    };

    PackedLeaves() = default;  // nothing packed

    // Packs `leaves` (ranges of leaf_objects) when there are few enough
    // references and each non-empty leaf has a range of its own (how the
    // builders write them); otherwise packed() is false and nothing is kept.
    // The layout is plan_leaf_blocks'.
    PackedLeaves(std::span<const std::uint32_t> leaf_objects, std::span<const LeafRange> leaves,
                 const SceneGeometry<Real>& g) {
        LeafBlocks plan = plan_leaf_blocks(leaf_objects, leaves, sphere_count(g), N, kMaxPackedRefs);
        if (plan.empty()) return;
        fill_blocks(plan, g);
        leaves_ = std::move(plan.leaves);
        leaf_at_ = std::move(plan.leaf_at);
    }

    // Packs a BVH's leaves, whatever their number, and copies its nodes with
    // each leaf slot referring to its blocks (nodes()).
    PackedLeaves(const WideBvh& bvh, const SceneGeometry<Real>& g) {
        LeafBlocks plan = plan_leaf_blocks(bvh, sphere_count(g), N);
        if (plan.empty()) return;
        fill_blocks(plan, g);
        nodes_ = pack_bvh_nodes(bvh, plan, sphere_leaves_);
    }

    // The BVH packed by the constructor above, whose objects moved (a refit:
    // the same leaves, new boxes): its boxes and the blocks' vertices copied
    // again, in place.
    void refill(const WideBvh& bvh, const SceneGeometry<Real>& g) {
        KDRT_ASSERT(bvh.nodes.size() == nodes_.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nodes_.size(), 1024), [&](const auto& range) {
            for (std::size_t n = range.begin(); n != range.end(); ++n)
                __builtin_memcpy(nodes_[n].box, bvh.nodes[n].box, sizeof nodes_[n].box);
        });
        const std::uint32_t spheres = sphere_count(g);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks_.size(), 4096), [&](const auto& range) {
            for (std::size_t b = range.begin(); b != range.end(); ++b) {
                Block& block = blocks_[b];
                for (int lane = 0; lane < N; ++lane) {
                    const std::int32_t id = block.id[lane] >= 0 ? block.id[lane] : block.id[0];
                    set_lane(block, lane, g.triangles[static_cast<std::uint32_t>(id) - spheres]);
                }
            }
        });
    }

    bool packed() const { return !leaves_.empty() || !nodes_.empty(); }

    // The memory of the packed copy: blocks, leaf records and a BVH's nodes.
    std::size_t bytes() const {
        return blocks_.size() * sizeof(Block) + (leaves_.size() + sphere_leaves_.size()) * sizeof(Leaf) +
               (spheres_.size() + leaf_at_.size()) * sizeof(std::uint32_t) + nodes_.size() * sizeof(WideBvhNode);
    }

    // The leaf whose objects start at leaf_objects[first] (a kd-tree's): its spheres and triangle blocks.
    using Leaf = LeafBlocks::Leaf;
    const Leaf& leaf(std::uint32_t first) const { return leaves_[leaf_at_[first]]; }

    // A packed BVH's nodes (pack_bvh_nodes), whose leaf slots node_leaf()
    // reads; empty otherwise.
    std::span<const WideBvhNode> nodes() const { return nodes_; }
    Leaf node_leaf(std::uint32_t child, std::uint32_t count) const {
        if (count & KDRT_BVH_LEAF_RECORD) return sphere_leaves_[child];
        return Leaf{child, count, 0, 0};
    }
    const Block* blocks() const { return blocks_.data(); }
    const std::uint32_t* spheres() const { return spheres_.data(); }

private:
    static std::uint32_t sphere_count(const SceneGeometry<Real>& g) {
        return static_cast<std::uint32_t>(g.spheres.size());
    }

    template <class Triangle>
    static void set_lane(Block& block, int lane, const Triangle& tri) {
        const glm::vec<3, Real>* vertex[3] = {&tri.v0, &tri.v1, &tri.v2};
        for (int v = 0; v < 3; ++v)
            for (int a = 0; a < 3; ++a) block.v[v][a][lane] = axis_of(*vertex[v], a);
    }

    void fill_blocks(const LeafBlocks& plan, const SceneGeometry<Real>& g) {
        const std::uint32_t spheres = sphere_count(g);
        blocks_.resize(plan.block_count());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks_.size(), 4096), [&](const auto& range) {
            for (std::size_t b = range.begin(); b != range.end(); ++b) {
                Block& block = blocks_[b];
                for (int lane = 0; lane < N; ++lane) {
                    const std::uint32_t id = plan.block_ids[b * N + static_cast<std::size_t>(lane)];
                    set_lane(block, lane, g.triangles[id - spheres]);
                    const bool used = (plan.block_lanes[b] >> lane) & 1u;
                    block.id[lane] = used ? static_cast<std::int32_t>(id) : -1;
                }
            }
        });
        spheres_ = plan.spheres;
    }

    std::vector<Leaf> leaves_;
    std::vector<Block> blocks_;
    std::vector<std::uint32_t> spheres_;
    std::vector<std::uint32_t> leaf_at_;  // a kd-tree's: by first index into leaf_objects
    std::vector<WideBvhNode> nodes_;      // a BVH's, leaf slots referring to blocks (nodes())
    std::vector<Leaf> sphere_leaves_;     // a BVH's leaves with spheres, by the index in their slots
};

// test_leaf_ray over a packed leaf: the spheres through `single(id)` (with the
// mailbox), each triangle block through the vector test, its rare lanes
// through `single`. `take` and `single` return true when the ray needs no more
// tests; then so does this.
template <class Real, int N, class Box, class Take, class Single>
KDRT_HOT_INLINE bool test_packed_leaf(const PackedLeaves<Real, N>& packed,
                                      const typename PackedLeaves<Real, N>::Leaf& leaf,
                                      const PacketShear<Real, N>& p, Box& tested, Take&& take, Single&& single) {
    using Ids = typename PackedLeaves<Real, N>::Ids;
    const std::uint32_t* spheres = packed.spheres() + leaf.first_sphere;
    for (std::uint32_t k = 0; k < leaf.sphere_count; ++k)
        if (!tested.seen(spheres[k]) && single(spheres[k])) return true;
    const auto* block = packed.blocks() + leaf.first_block;
    const Ids ignore = Ids{} + p.ignore[0];
    for (std::uint32_t b = 0; b < leaf.block_count; ++b, ++block) {
        // A flat triangle is never hit by a ray leaving it.
        const std::uint32_t lanes = lane_bits<N>((block->id >= 0) & (block->id != ignore));
        if (lanes == 0) continue;
        std::uint32_t slow = 0;
        TriangleLanes<Real, N> found;
        const std::uint32_t hits = watertight_lanes(p, lanes, block->v[0], block->v[1], block->v[2], found, slow);
        if (take_lane_hits(hits, slow, found, [&](int i) { return block->id[i]; }, take, single))
            return true;
    }
    return false;
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
