// Tree statistics, as the builders' report and the tests' assertions use them.
// The SAH cost is the cost model of sah_kd_builder.cpp applied to the finished
// tree, without the empty-space bonus (a builder's heuristic, not a cost):
//   cost = sum over inner nodes n of traversal_cost * SA(n) / SA(root)
//        + sum over leaves l of intersection_cost * N(l) * SA(l) / SA(root),
// the expected cost of a ray that hits the root cell. Expects a tree that
// passes check_kd_tree.
#include "common/parallel_chunks.h"

#include <kdrt/kd_tree.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <vector>

namespace kdrt {

KdTreeStats kd_tree_stats(const KdTree& tree, const KdBuildConfig& given) {
    const KdBuildConfig config = given.with_triangle_cost(KdBuildConfig::kGenericTriangleCost);
    KdTreeStats s;
    s.nodes = tree.nodes.size();
    s.objects = tree.object_count;
    s.node_bytes = tree.nodes.size() * sizeof(KdNode);
    s.leaf_object_bytes = tree.leaf_objects.size() * sizeof(std::uint32_t);
    s.rope_bytes = tree.ropes.size() * sizeof(KdLeafRopes);
    if (tree.nodes.empty()) return s;

    const double root_area = tree.bounds.surface_area();
    // A flat or empty root has no area to weight by: count every node as hit.
    auto probability = [&](const Aabb& cell) { return root_area > 0.0 ? cell.surface_area() / root_area : 1.0; };

    // Depth first, below child first, recursing on the depth-first layout (no
    // work list of boxes to grow and copy: this walk is part of every commit).
    // The nodes above kSubtreeDepth are summed first, then the subtrees below
    // it in parallel, each into its own sums, added up in depth-first order:
    // the same figures every time, for any number of threads (the SAH cost
    // differs from one running sum's in its last bits).
    constexpr int kSubtreeDepth = 6;
    struct Sums {
        std::size_t leaves = 0, empty_leaves = 0, inner_nodes = 0, non_empty = 0, references = 0;
        double depth_sum = 0.0, sah_cost = 0.0;
        int max_leaf_depth = 0;
        void add(const Sums& o) {
            leaves += o.leaves;
            empty_leaves += o.empty_leaves;
            inner_nodes += o.inner_nodes;
            non_empty += o.non_empty;
            references += o.references;
            depth_sum += o.depth_sum;
            sah_cost += o.sah_cost;
            max_leaf_depth = std::max(max_leaf_depth, o.max_leaf_depth);
        }
    };
    struct Subtree {
        std::uint32_t node;
        int depth;
        Aabb cell;
        Sums sums;
    };
    std::vector<Subtree> subtrees;
    auto walk = [&](auto& self, Sums& sums, std::uint32_t node, int depth, const Aabb& cell, bool top) -> void {
        const KdNode& n = tree.nodes[node];
        if (kd_is_leaf(n)) {
            const std::uint32_t count = kd_leaf_count(n);
            ++sums.leaves;
            if (count == 0) ++sums.empty_leaves;
            else ++sums.non_empty;
            sums.references += count;
            sums.depth_sum += depth;
            sums.max_leaf_depth = std::max(sums.max_leaf_depth, depth);
            sums.sah_cost += config.intersection_cost * count * probability(cell);
            return;
        }
        if (top && depth == kSubtreeDepth) {
            subtrees.push_back({node, depth, cell, {}});
            return;
        }
        ++sums.inner_nodes;
        sums.sah_cost += config.traversal_cost * probability(cell);
        const int axis = kd_axis(n);
        Aabb child = cell;
        child.hi[axis] = kd_split(n);
        self(self, sums, node + 1, depth + 1, child, top);
        child.hi[axis] = cell.hi[axis];
        child.lo[axis] = kd_split(n);
        self(self, sums, kd_above_child(n), depth + 1, child, top);
    };
    Sums total;
    walk(walk, total, 0, 0, tree.bounds, true);
    detail::for_each_chunk(
        subtrees.size(),
        [&](std::size_t, std::size_t begin, std::size_t end) {
            for (std::size_t i = begin; i < end; ++i) {
                Subtree& t = subtrees[i];
                walk(walk, t.sums, t.node, t.depth, t.cell, false);
            }
        },
        1);
    for (const Subtree& t : subtrees) total.add(t.sums);
    s.leaves = total.leaves;
    s.empty_leaves = total.empty_leaves;
    s.inner_nodes = total.inner_nodes;
    s.max_leaf_depth = total.max_leaf_depth;
    s.sah_cost = total.sah_cost;
    s.mean_leaf_depth = s.leaves ? total.depth_sum / static_cast<double>(s.leaves) : 0.0;
    s.mean_objects_per_leaf =
        total.non_empty ? static_cast<double>(total.references) / static_cast<double>(total.non_empty) : 0.0;

    // Duplication counts distinct objects referenced, so objects a builder
    // skipped (empty bounds) do not make it look better than it is. Marked
    // and counted in parallel: a byte per object, set (never cleared) by
    // relaxed atomic stores, so the count is exact for any interleaving.
    std::vector<std::uint8_t> seen(tree.object_count, 0);
    detail::for_each_chunk(tree.leaf_objects.size(), [&](std::size_t, std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            const std::uint32_t id = tree.leaf_objects[i];
            if (id >= seen.size()) continue;
            std::atomic_ref<std::uint8_t> mark(seen[id]);
            if (!mark.load(std::memory_order_relaxed)) mark.store(1, std::memory_order_relaxed);
        }
    });
    std::vector<std::size_t> distinct_in(detail::chunk_count(seen.size()), 0);
    detail::for_each_chunk(seen.size(), [&](std::size_t c, std::size_t begin, std::size_t end) {
        std::size_t count = 0;
        for (std::size_t i = begin; i < end; ++i) count += seen[i];
        distinct_in[c] = count;
    });
    std::size_t distinct = 0;
    for (std::size_t d : distinct_in) distinct += d;
    s.duplication = distinct ? static_cast<double>(total.references) / static_cast<double>(distinct) : 0.0;
    return s;
}

}  // namespace kdrt
