// Collapse of a binary BVH into one of N children per node, SAH-greedy as
// Embree's builders open a node (BVHBuilderBinnedSAH's branching factor): a
// wide node starts with a binary node's two children, and the inner child of
// largest surface area (the one a ray most likely enters) is replaced by its
// two children until N slots are filled or all are leaves. Leaves keep their
// object ranges. A node's inner children take consecutive indices right
// after the nodes made before them, so the children of one node lie together.
#include "bvh/bvh_boxes.h"
#include "bvh/bvh_build.h"
#include "bvh/bvh_stats.h"
#include "common/tsan_fork_join.h"

#include <kdrt/error.h>

#include <tbb/task_arena.h>

#include <cstdint>
#include <vector>

namespace kdrt {

namespace {

double node_area(const Bvh2Node& n) {
    detail::FloatBox b;
    for (int a = 0; a < 3; ++a) {
        b.lo[a] = n.lo[a];
        b.hi[a] = n.hi[a];
    }
    return b.area();
}

template <int N>
class Collapse {
public:
    using Node = WideBvhNodeN<N>;
    explicit Collapse(const Bvh2& bvh) : b2_(bvh) {}

    // The binary nodes that become the slots of the wide node for binary node `inner`.
    int open(std::uint32_t inner, std::uint32_t (&slots)[N]) const {
        const std::uint32_t first = b2_.nodes[inner].first;
        slots[0] = first;
        slots[1] = first + 1;
        int k = 2;
        while (k < N) {
            int best = -1;
            double best_area = -1.0;
            for (int i = 0; i < k; ++i) {
                const Bvh2Node& n = b2_.nodes[slots[i]];
                if (bvh2_is_leaf(n)) continue;
                const double area = node_area(n);
                if (area > best_area) {
                    best = i;
                    best_area = area;
                }
            }
            if (best < 0) break;
            const std::uint32_t opened = b2_.nodes[slots[best]].first;
            slots[best] = opened;
            slots[k++] = opened + 1;
        }
        return k;
    }

    // Fills out[at] from binary node `inner` and appends its subtree to out.
    void emit(std::uint32_t inner, std::vector<Node>& out, std::size_t at) const {
        std::uint32_t slots[N];
        const int k = open(inner, slots);
        Node node = Node::empty_node();
        std::uint32_t inner_children[N];
        int inners = 0;
        const std::size_t base = out.size();
        if (base + N > 0xFFFFFFFFull) throw Error(ErrorCode::Unsupported, "wide BVH too large: more than 2^32 nodes");
        for (int i = 0; i < k; ++i) {
            const Bvh2Node& n = b2_.nodes[slots[i]];
            node.set_box(i, n.lo, n.hi);
            if (bvh2_is_leaf(n)) {
                node.set_leaf(i, n.first, n.count);
            } else {
                node.set_inner(i, static_cast<std::uint32_t>(base + inners));
                inner_children[inners++] = slots[i];
            }
        }
        out[at] = node;
        out.resize(base + inners);
        for (int j = 0; j < inners; ++j) emit(inner_children[j], out, base + j);
    }

private:
    const Bvh2& b2_;
};

}  // namespace

template <int N>
WideBvhN<N> collapse_bvh(const Bvh2& bvh, int threads) {
    WideBvhN<N> wide;
    wide.object_count = bvh.object_count;
    wide.leaf_objects = bvh.leaf_objects;
    wide.nodes.push_back(WideBvhNodeN<N>::empty_node());
    if (!bvh.nodes.empty()) {
        const Bvh2Node& root = bvh.nodes[0];
        if (bvh2_is_leaf(root)) {
            wide.nodes[0].set_box(0, root.lo, root.hi);
            wide.nodes[0].set_leaf(0, root.first, root.count);
        } else {
            wide.nodes.reserve(bvh.nodes.size() / (N - 1) + 1);
            Collapse<N>(bvh).emit(0, wide.nodes, 0);
        }
        detail::FloatBox b;
        for (int a = 0; a < 3; ++a) {
            b.lo[a] = root.lo[a];
            b.hi[a] = root.hi[a];
        }
        wide.bounds = b.to_aabb();
    }
    // The SAH cost's sum is the one parallel part, on `threads` as the build was.
    tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
    {
        detail::TsanForkJoin tsan;
        auto sum = [&] { wide.build_sah_cost = bvh_sah_cost(wide); };
        arena.execute(tsan.task(sum));
    }
    return wide;
}

template WideBvhN<4> collapse_bvh<4>(const Bvh2&, int);
template WideBvhN<8> collapse_bvh<8>(const Bvh2&, int);

}  // namespace kdrt
