// Traversal "ropes": stackless traversal over neighbour links (Havran et al.
// 1998; Popov et al. 2007), the study's "neighbour" traversal. After a leaf,
// follow the rope of the face through which the ray leaves and descend from
// the rope's node, never from the root.
#pragma once

#include "cpu/traversal_common.h"

namespace kdrt::detail::inline KDRT_CPU_ISA {

// The face (rope index) through which the ray leaves a leaf's box: the
// nearest far-side plane, at t_exit; -1 for a zero direction.
template <class Real>
KDRT_HOT_INLINE int exit_face(const KdLeafRopes& leaf, const Ray<Real>& ray, Real& t_exit) {
    t_exit = std::numeric_limits<Real>::infinity();
    int face = -1;
    for (int a = 0; a < 3; ++a) {
        const Real d = ray.dir[a];
        if (d == Real(0)) continue;
        const Real plane = static_cast<Real>(d > Real(0) ? leaf.box_max[a] : leaf.box_min[a]);
        const Real t = (plane - ray.org[a]) * ray.inv_dir[a];
        if (t < t_exit) {
            t_exit = t;
            face = 2 * a + (d > Real(0) ? 1 : 0);
        }
    }
    return face;
}

template <class Real, class Visit>
void traverse_ropes(const KdTree& tree, const Ray<Real>& ray, Real t_max, Visit&& visit) {
    Real t0, t1;
    if (!clip_to_tree(tree, ray, t_max, t0, t1)) return;
    std::uint32_t node = 0;
    Real t_entry = t0;
    // Each step moves to a cell further along the ray; the cap only guards
    // against a corrupt tree.
    std::size_t steps_left = 4 * tree.leaf_count() + 64;
    while (steps_left-- > 0) {
        while (!kd_is_leaf(tree.nodes[node])) {
            Real t_split;
            SplitStep step = split_step(tree, node, ray, t_split);
            node = (t_split <= t_entry) ? step.far_child : step.near_child;
        }
        const KdLeafRopes& r = tree.ropes[node];
        Real t_exit;
        const int face = exit_face(r, ray, t_exit);
        if (leaf_finishes(ray, visit_leaf(tree, tree.nodes[node], visit), t_exit)) return;
        if (face < 0 || t_exit >= t1) return;
        const std::uint32_t next = r.rope[face];
        if (next == KDRT_ROPE_NONE) return;
        node = next;
        t_entry = std::max(t_entry, t_exit);
    }
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
