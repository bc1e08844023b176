// Tree statistics, as the builders' report and the tests' assertions use them.
// The SAH cost is the cost model of sah_kd_builder.cpp applied to the finished
// tree, without the empty-space bonus (a builder's heuristic, not a cost):
//   cost = sum over inner nodes n of traversal_cost * SA(n) / SA(root)
//        + sum over leaves l of intersection_cost * N(l) * SA(l) / SA(root),
// the expected cost of a ray that hits the root cell. Expects a tree that
// passes check_kd_tree.
#include <kdrt/kd_tree.h>

#include <algorithm>
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

    struct Item {
        std::uint32_t node;
        int depth;
        Aabb cell;
    };
    std::vector<Item> stack{{0, 0, tree.bounds}};
    std::size_t non_empty = 0, references = 0;
    double depth_sum = 0.0;
    while (!stack.empty()) {
        const Item item = stack.back();
        stack.pop_back();
        const KdNode& n = tree.nodes[item.node];
        if (kd_is_leaf(n)) {
            const std::uint32_t count = kd_leaf_count(n);
            ++s.leaves;
            if (count == 0) ++s.empty_leaves;
            else ++non_empty;
            references += count;
            depth_sum += item.depth;
            s.max_leaf_depth = std::max(s.max_leaf_depth, item.depth);
            s.sah_cost += config.intersection_cost * count * probability(item.cell);
            continue;
        }
        ++s.inner_nodes;
        s.sah_cost += config.traversal_cost * probability(item.cell);
        const int axis = kd_axis(n);
        Item below{item.node + 1, item.depth + 1, item.cell}, above{kd_above_child(n), item.depth + 1, item.cell};
        below.cell.hi[axis] = kd_split(n);
        above.cell.lo[axis] = kd_split(n);
        stack.push_back(above);
        stack.push_back(below);
    }
    s.mean_leaf_depth = s.leaves ? depth_sum / static_cast<double>(s.leaves) : 0.0;
    s.mean_objects_per_leaf = non_empty ? static_cast<double>(references) / static_cast<double>(non_empty) : 0.0;

    // Duplication counts distinct objects referenced, so objects a builder
    // skipped (empty bounds) do not make it look better than it is.
    std::vector<bool> seen(tree.object_count, false);
    std::size_t distinct = 0;
    for (std::uint32_t id : tree.leaf_objects) {
        if (id >= seen.size() || seen[id]) continue;
        seen[id] = true;
        ++distinct;
    }
    s.duplication = distinct ? static_cast<double>(references) / static_cast<double>(distinct) : 0.0;
    return s;
}

}  // namespace kdrt
