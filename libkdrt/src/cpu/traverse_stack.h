// Traversal "stack": classic front-to-back kd-tree traversal with a small
// stack of far children (Jansen 1986; pbrt's KdTreeAccel::Intersect). The
// reference point for speed. The stack is bounded by the tree depth (KDRT_MAX_TREE_DEPTH).
#pragma once

#include "cpu/traversal_common.h"

namespace kdrt::detail::inline KDRT_CPU_ISA {

template <class Real, class Visit>
void traverse_stack(const KdTree& tree, const Ray<Real>& ray, Real t_max, Visit&& visit) {
    Real t0, t1;
    if (tree.nodes.empty() || !clip_to_box(ray, tree.bounds, t_max, t0, t1)) return;
    struct Entry {
        std::uint32_t node;
        Real tmin, tmax;
    };
    Entry stack[KDRT_MAX_TREE_DEPTH + 2];
    int top = 0;
    std::uint32_t node = 0;
    Real tmin = t0, tmax = t1;
    for (;;) {
        const KdNode& n = tree.nodes[node];
        if (!kd_is_leaf(n)) {
            Real t_split;
            SplitStep step = split_step(tree, node, ray, t_split);
            if (t_split <= tmin) {
                node = step.far_child;
            } else if (t_split >= tmax) {
                node = step.near_child;
            } else {
                stack[top++] = {step.far_child, t_split, tmax};
                node = step.near_child;
                tmax = t_split;
            }
            continue;
        }
        if (leaf_finishes(ray, visit_leaf(tree, n, visit), tmax)) return;
        if (top == 0) return;
        --top;
        node = stack[top].node;
        tmin = stack[top].tmin;
        tmax = stack[top].tmax;
    }
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
