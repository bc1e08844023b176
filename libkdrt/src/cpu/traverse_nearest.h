// Nearest-first search of a kd-tree for the objects closest to a point:
// depth first, the child whose cell holds the point before the other, and a
// cell skipped when it lies farther than the best distance so far (its
// lower bound: the point's distance to the cell). Correct for trees with
// perfect splits: an object is in every leaf whose cell it overlaps, so the
// leaf holding the closest surface point is never skipped. Ties aside, the
// same objects as testing every one.
#pragma once

#include "cpu/ray.h"

#include <kdrt/kd_tree.h>

#include <glm/vec3.hpp>

#include <algorithm>
#include <cstdint>

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

}  // namespace kdrt::detail::KDRT_CPU_ISA
