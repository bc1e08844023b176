// Collapse of a binary BVH into one of N children per node. A wide node's
// slots are a cut through the binary subtree below it, of at most N binary
// nodes; the cut is chosen by dynamic programming over the whole tree (as
// Ylitie, Karras and Laine 2017 collapse to their 8-wide BVH) so that the
// sum of the wide nodes' surface areas, the SAH's expected node visits per
// ray, is least. Leaves stay the binary BVH's: their cost is the same for
// any cut. A greedy collapse (open the largest child until N) fills the top
// of the tree and leaves the bottom nodes with two to four leaves; the
// optimal cut fills the nodes where rays go. A node's inner children take
// consecutive indices after the nodes made before them, so the children of
// one node lie together.
#include "bvh/bvh_boxes.h"
#include "bvh/bvh_build.h"
#include "bvh/bvh_stats.h"
#include "common/debug_assert.h"
#include "common/tsan_fork_join.h"

#include <kdrt/error.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <utility>
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
    explicit Collapse(const Bvh2& bvh) : b2_(bvh), cost_(bvh.nodes.size()) {
        // Areas relative to the root's, so that float sums stay finite for any box that floats hold.
        const double root = node_area(bvh.nodes[0]);
        unit_ = root > 0.0 ? 1.0 / root : 1.0;
        costs(0, 0);
    }

    // Fills out[at] from binary node `inner` and appends its subtree to out.
    void emit(std::uint32_t inner, std::vector<Node>& out, std::size_t at) const {
        std::uint32_t slots[N];
        int k = 0;
        const std::uint32_t first = b2_.nodes[inner].first;
        const int j = spread(first, N).second;
        cut(first, j, slots, k);
        cut(first + 1, N - j, slots, k);
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
        for (int c = 0; c < inners; ++c) emit(inner_children[c], out, base + c);
    }

private:
    // cost_[n][i - 1]: the least summed area of the wide nodes for binary
    // subtree n when it takes at most i slots of its parent; [0] is n as one
    // slot (a wide node of its own). Leaves stay 0 at any i.
    using Costs = std::array<float, N>;
    // Added to each wide node's area: far below any area that counts, it makes
    // fewer nodes cheaper where areas vanish (objects at one point).
    static constexpr float kNodeFloor = 1e-30f;

    // The cost of spreading the two children first, first + 1 over at most
    // i >= 2 slots, and the slots the first child takes.
    std::pair<float, int> spread(std::uint32_t first, int i) const {
        float best = std::numeric_limits<float>::infinity();
        int best_j = 1;
        for (int j = 1; j < i; ++j) {
            const float c = cost_at(first, j) + cost_at(first + 1, i - j);
            if (c < best) {
                best = c;
                best_j = j;
            }
        }
        return {best, best_j};
    }
    float cost_at(std::uint32_t n, int i) const { return cost_[n][i - 1]; }

    void costs(std::uint32_t n, int depth) {
        const Bvh2Node& node = b2_.nodes[n];
        if (bvh2_is_leaf(node)) return;
        KDRT_ASSERT(depth <= kBvhMaxDepth);  // as build_bvh2 makes them
        costs(node.first, depth + 1);
        costs(node.first + 1, depth + 1);
        Costs& c = cost_[n];
        const float spread_all = spread(node.first, N).first;
        c[0] = (static_cast<float>(node_area(node) * unit_) + kNodeFloor) + spread_all;
        for (int i = 2; i < N; ++i) c[i - 1] = std::min(c[0], spread(node.first, i).first);
        c[N - 1] = std::min(c[0], spread_all);
    }

    // Appends the slots of binary subtree n given at most i of them; on a
    // tie, its children's.
    void cut(std::uint32_t n, int i, std::uint32_t (&slots)[N], int& k) const {
        const Bvh2Node& node = b2_.nodes[n];
        if (i > 1 && !bvh2_is_leaf(node)) {
            const auto [spread_cost, j] = spread(node.first, i);
            if (!(cost_[n][0] < spread_cost)) {
                cut(node.first, j, slots, k);
                cut(node.first + 1, i - j, slots, k);
                return;
            }
        }
        slots[k++] = n;
    }

    const Bvh2& b2_;
    std::vector<Costs> cost_;
    double unit_ = 1.0;  // 1 / the root's area
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
