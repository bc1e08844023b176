// Traversal "restart": kd-restart (Foley and Sugerman 2005), the study's
// "basic" traversal. No stack: descend from the root to the leaf holding the
// ray at t = tmin, test it, move tmin to the leaf's exit, repeat.
#pragma once

#include "cpu/traversal_common.h"

namespace kdrt::detail::inline KDRT_CPU_ISA {

template <class Real, class Visit>
void traverse_restart(const KdTree& tree, const Ray<Real>& ray, Real t_max, Visit&& visit) {
    Real t0, t1;
    if (!clip_to_tree(tree, ray, t_max, t0, t1)) return;
    Real t_start = t0;
    for (;;) {
        std::uint32_t node = 0;
        Real tmin = t_start, tmax = t1;
        while (!kd_is_leaf(tree.nodes[node])) {
            Real t_split;
            const SplitStep step = split_step(tree, node, ray, t_split);
            const Crossing c = crossing(t_split, tmin, tmax);
            node = c == Crossing::FarOnly ? step.far_child : step.near_child;
            if (c == Crossing::Both) tmax = t_split;
        }
        if (leaf_finishes(ray, visit_leaf(tree, tree.nodes[node], visit), tmax)) return;
        if (tmax >= t1) return;
        t_start = tmax;
    }
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
