#include "bvh/bvh_stats.h"

#include "bvh/bvh_boxes.h"
#include "common/parallel_chunks.h"

#include <algorithm>
#include <utility>
#include <vector>

namespace kdrt {

template <int N>
double bvh_sah_cost(const WideBvhN<N>& bvh) {
    const double root_area = detail::round_out(bvh.bounds.empty() ? Aabb{glm::dvec3(0), glm::dvec3(0)} : bvh.bounds).area();
    const bool flat = !(root_area > 0.0);
    // Summed over fixed chunks of nodes, the chunks' sums in order: the same
    // rounding for any thread count.
    std::vector<double> sums(detail::chunk_count(bvh.nodes.size()), 0.0);
    detail::for_each_chunk(bvh.nodes.size(), [&](std::size_t c, std::size_t b, std::size_t e) {
        double sum = 0.0;
        for (std::size_t n = b; n < e; ++n) {
            const auto& node = bvh.nodes[n];
            for (int i = 0; i < N && !node.is_empty(i); ++i) {
                const double p = flat ? 1.0 : slot_box(node, i).area() / root_area;
                sum += p * (node.is_leaf(i) ? static_cast<double>(node.leaf_count(i)) : 1.0);
            }
        }
        sums[c] = sum;
    });
    double cost = 1.0;
    for (double sum : sums) cost += sum;
    return cost;
}

template <int N>
BvhStats bvh_stats(const WideBvhN<N>& bvh) {
    BvhStats s;
    s.nodes = bvh.nodes.size();
    s.objects = bvh.object_count;
    s.node_bytes = bvh.nodes.size() * sizeof(WideBvhNodeN<N>);
    s.leaf_object_bytes = bvh.leaf_objects.size() * sizeof(std::uint32_t);
    s.sah_cost = bvh_sah_cost(bvh);
    s.build_sah_cost = bvh.build_sah_cost;
    std::size_t listed = 0;
    // Depth: nodes come after their parents, so one pass in index order.
    std::vector<int> level(bvh.nodes.size(), 1);
    for (std::size_t n = 0; n < bvh.nodes.size(); ++n) {
        const auto& node = bvh.nodes[n];
        for (int i = 0; i < N; ++i) {
            if (node.is_empty(i)) {
                ++s.empty_slots;
            } else if (node.is_leaf(i)) {
                ++s.leaves;
                listed += node.leaf_count(i);
                s.depth = std::max(s.depth, level[n]);
            } else if (node.child[i] < level.size()) {
                level[node.child[i]] = level[n] + 1;
            }
        }
    }
    s.mean_leaf_size = s.leaves ? static_cast<double>(listed) / static_cast<double>(s.leaves) : 0.0;
    return s;
}

int bvh2_depth(const Bvh2& bvh) {
    if (bvh.nodes.empty()) return -1;
    int deepest = 0;
    std::vector<std::pair<std::uint32_t, int>> stack{{0, 0}};
    while (!stack.empty()) {
        const auto [i, d] = stack.back();
        stack.pop_back();
        const Bvh2Node& n = bvh.nodes[i];
        if (bvh2_is_leaf(n)) {
            deepest = std::max(deepest, d);
            continue;
        }
        stack.push_back({n.first, d + 1});
        stack.push_back({n.first + 1, d + 1});
    }
    return deepest;
}

template double bvh_sah_cost<4>(const WideBvhN<4>&);
template double bvh_sah_cost<8>(const WideBvhN<8>&);
template BvhStats bvh_stats<4>(const WideBvhN<4>&);
template BvhStats bvh_stats<8>(const WideBvhN<8>&);

}  // namespace kdrt
