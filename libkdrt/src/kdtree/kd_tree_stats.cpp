// Tree statistics, as the builders' report and the tests' assertions use them.
// The SAH cost is the cost model of sah_kd_builder.cpp applied to the finished
// tree, without the empty-space bonus (a builder's heuristic, not a cost):
//   cost = sum over inner nodes n of traversal_cost * SA(n) / SA(root)
//        + sum over leaves l of intersection_cost * N(l) * SA(l) / SA(root),
// the expected cost of a ray that hits the root cell. Expects a tree that
// passes check_kd_tree.
#include <kdrt/kd_tree.h>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace kdrt {

KdTreeStats kd_tree_stats(const KdTree& tree, const KdBuildConfig& given) {
    const KdBuildConfig config = given.with_triangle_cost(KdBuildConfig::kGenericTriangleCost);
    KdTreeStats s;
    s.nodes = tree.nodes.size();
    s.objects = tree.object_count;
    s.node_bytes = tree.nodes.size() * sizeof(KdNode);
    s.leaf_bytes = 0;  // a leaf node holds its list's range: no leaf records
    s.leaf_object_bytes = tree.leaf_objects.size() * sizeof(std::uint32_t);
    s.rope_bytes = tree.ropes.size() * sizeof(KdLeafRopes);
    if (tree.nodes.empty()) return s;

    const double root_area = tree.bounds.surface_area();
    // A flat or empty root has no area to weight by: count every node as hit.
    auto probability = [&](const Aabb& cell) { return root_area > 0.0 ? cell.surface_area() / root_area : 1.0; };

    // Depth first, below child first (the order of the sums, so the same
    // figures every time), recursing on the depth-first layout: no work list
    // of boxes to grow and copy (this walk is part of every commit).
    std::size_t non_empty = 0, references = 0;
    double depth_sum = 0.0;
    auto walk = [&](auto& self, std::uint32_t node, int depth, const Aabb& cell) -> void {
        const KdNode& n = tree.nodes[node];
        if (kd_is_leaf(n)) {
            const std::uint32_t count = kd_leaf_count(n);
            ++s.leaves;
            if (count == 0) ++s.empty_leaves;
            else ++non_empty;
            references += count;
            depth_sum += depth;
            s.max_leaf_depth = std::max(s.max_leaf_depth, depth);
            s.sah_cost += config.intersection_cost * count * probability(cell);
            return;
        }
        ++s.inner_nodes;
        s.sah_cost += config.traversal_cost * probability(cell);
        const int axis = kd_axis(n);
        Aabb child = cell;
        child.hi[axis] = kd_split(n);
        self(self, node + 1, depth + 1, child);
        child.hi[axis] = cell.hi[axis];
        child.lo[axis] = kd_split(n);
        self(self, kd_above_child(n), depth + 1, child);
    };
    walk(walk, 0, 0, tree.bounds);
    s.mean_leaf_depth = s.leaves ? depth_sum / static_cast<double>(s.leaves) : 0.0;
    s.mean_objects_per_leaf = non_empty ? static_cast<double>(references) / static_cast<double>(non_empty) : 0.0;

    // Duplication counts distinct objects referenced, so objects a builder
    // skipped (empty bounds) do not make it look better than it is.
    std::vector<std::uint8_t> seen(tree.object_count, 0);  // bytes: no read-modify-write of packed bits
    std::size_t distinct = 0;
    for (std::uint32_t id : tree.leaf_objects) {
        if (id >= seen.size() || seen[id]) continue;
        seen[id] = 1;
        ++distinct;
    }
    s.duplication = distinct ? static_cast<double>(references) / static_cast<double>(distinct) : 0.0;
    return s;
}

}  // namespace kdrt
