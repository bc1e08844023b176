// Nearest-first searches of a kd-tree or a wide BVH for the objects closest
// to a point: a cell or box is skipped when it lies farther than the best
// distance so far (its lower bound: the point's distance to it).
// kd-tree: depth first, the child whose cell holds the point first; correct
// because an object is in every leaf whose cell it overlaps. BVH: a node's
// children nearest first; correct because a box encloses its objects.
// Ties aside, both find the objects testing every one finds.
#pragma once

#include "common/debug_assert.h"
#include "cpu/ray.h"

#include "bvh/bvh.h"

#include <kdrt/kd_tree.h>

#include <glm/vec3.hpp>

#include <algorithm>
#include <cstdint>
#include <iterator>

namespace kdrt::detail::inline KDRT_CPU_ISA {

// Squared distance from p to the box [lo, hi] (0 inside).
inline double box_distance2(const glm::dvec3& p, const glm::dvec3& lo, const glm::dvec3& hi) {
    double d2 = 0.0;
    for (int a = 0; a < 3; ++a) {
        const double d = std::max({lo[a] - p[a], 0.0, p[a] - hi[a]});
        d2 += d * d;
    }
    return d2;
}

// visit(ids, count) tests a leaf's objects; best_d2() returns the squared
// distance of the best object so far (it only shrinks).
template <class Visit, class BestD2>
void traverse_nearest(const KdTree& tree, const glm::dvec3& p, Visit&& visit, BestD2&& best_d2) {
    if (tree.nodes.empty()) return;
    struct Entry {
        std::uint32_t node;
        glm::dvec3 lo, hi;
        double d2;
    };
    Entry stack[KDRT_MAX_TREE_DEPTH + 2];
    int top = 0;
    stack[top++] = {0, tree.bounds.lo, tree.bounds.hi, box_distance2(p, tree.bounds.lo, tree.bounds.hi)};
    while (top > 0) {
        Entry e = stack[--top];
        if (e.d2 > best_d2()) continue;
        for (;;) {
            const KdNode& n = tree.nodes[e.node];
            if (kd_is_leaf(n)) {
                visit(tree.leaf_objects.data() + kd_leaf_first(n), kd_leaf_count(n));
                break;
            }
            const int axis = kd_axis(n);
            const double split = static_cast<double>(kd_split(n));
            Entry below{e.node + 1, e.lo, e.hi, e.d2}, above{kd_above_child(n), e.lo, e.hi, e.d2};
            below.hi[axis] = split;
            above.lo[axis] = split;
            const bool point_below = p[axis] <= split;
            Entry& near = point_below ? below : above;
            Entry& far = point_below ? above : below;
            far.d2 = box_distance2(p, far.lo, far.hi);
            if (far.d2 <= best_d2()) stack[top++] = far;
            e = near;
        }
    }
}

// The same over a wide BVH: a node's used slots by their box distance, the
// nearest on top of the stack; leaves are visited as they come off it.
template <class Visit, class BestD2>
void traverse_nearest(const WideBvh& bvh, const glm::dvec3& p, Visit&& visit, BestD2&& best_d2) {
    constexpr int N = WideBvh::kWidth;
    struct Entry {
        double d2;
        std::uint32_t child, count;  // a slot's reference, as in the node
    };
    Entry stack[kBvhMaxDepth * (N - 1) + N];
    int top = 0;
    stack[top++] = {0.0, 0u, 0u};  // the root, an inner reference
    while (top > 0) {
        const Entry e = stack[--top];
        if (e.d2 > best_d2()) continue;
        if (e.count != 0) {
            visit(bvh.leaf_objects.data() + e.child, e.count & kBvhMaxLeafCount);
            continue;
        }
        const WideBvhNode& n = bvh.nodes[e.child];
        Entry kids[N];
        int k = 0;
        for (int s = 0; s < N && !n.is_empty(s); ++s) {
            const glm::dvec3 lo(n.box[0][0][s], n.box[0][1][s], n.box[0][2][s]);
            const glm::dvec3 hi(n.box[1][0][s], n.box[1][1][s], n.box[1][2][s]);
            const double d2 = box_distance2(p, lo, hi);
            if (d2 <= best_d2()) kids[k++] = {d2, n.child[s], n.count[s]};
        }
        // Farthest pushed first, so the nearest comes off next: an insertion
        // sort of at most N (std::sort's of a fixed array trips GCC 12's -Warray-bounds).
        KDRT_ASSERT(top + k <= static_cast<int>(std::size(stack)));
        for (int i = 0; i < k; ++i) {
            int at = top++;
            while (at > top - 1 - i && stack[at - 1].d2 < kids[i].d2) {
                stack[at] = stack[at - 1];
                --at;
            }
            stack[at] = kids[i];
        }
    }
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
