// Traversal "restart": kd-restart (Foley and Sugerman 2005), the study's
// "basic" traversal. No stack: descend from the root to the leaf holding the
// ray at t = tmin, test it, move tmin to the leaf's exit, repeat.
//
// Sending the ray to the far child when the plane is crossed at or before
// tmin guarantees progress: a leaf is never entered with zero length.
#pragma once

#include "cpu/traversal_common.h"

namespace kdrt::detail::inline KDRT_CPU_ISA {

template <class Real, class Visit>
void traverse_restart(const KdTree& tree, const Ray<Real>& ray, Real t_max, Visit&& visit) {
    Real t0, t1;
    if (tree.nodes.empty() || !clip_to_box(ray, tree.bounds, t_max, t0, t1)) return;
    Real t_start = t0;
    for (;;) {
        std::uint32_t node = 0;
        Real tmin = t_start, tmax = t1;
        while (!kd_is_leaf(tree.nodes[node])) {
            Real t_split;
            SplitStep step = split_step(tree, node, ray, t_split);
            if (t_split <= tmin) {
                node = step.far_child;
            } else if (t_split >= tmax) {
                node = step.near_child;
            } else {
                node = step.near_child;
                tmax = t_split;
            }
        }
        if (leaf_finishes(ray, visit_leaf(tree, tree.nodes[node], visit), tmax)) return;
        if (tmax >= t1) return;
        t_start = tmax;
    }
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
