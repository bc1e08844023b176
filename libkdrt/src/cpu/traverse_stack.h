// Traversal "stack": classic front-to-back kd-tree traversal with a small
// stack of far children (Jansen 1986; pbrt's KdTreeAccel::Intersect). The
// reference point for speed. The stack is bounded by the tree depth (KDRT_MAX_TREE_DEPTH).
#pragma once

#include "cpu/traversal_common.h"

#include <bit>
#include <type_traits>

namespace kdrt::detail::inline KDRT_CPU_ISA {

// mask ? a : b for an all-ones or zero mask, in bit operations: GCC turns a
// plain ?: here back into the branch the node step avoids.
template <class Real>
KDRT_HOT_INLINE Real select_by_mask(std::uint32_t mask, Real a, Real b) {
    using Bits = std::conditional_t<sizeof(Real) == sizeof(std::uint32_t), std::uint32_t, std::uint64_t>;
    const Bits m = static_cast<Bits>(0) - static_cast<Bits>(mask & 1u);
    return std::bit_cast<Real>((std::bit_cast<Bits>(a) & m) | (std::bit_cast<Bits>(b) & ~m));
}

template <class Real, class Visit>
void traverse_stack(const KdTree& tree, const Ray<Real>& ray, Real t_max, Visit&& visit) {
    Real t0, t1;
    if (!clip_to_tree(tree, ray, t_max, t0, t1)) return;
    StackEntry<Real> stack[KDRT_MAX_TREE_DEPTH + 2];
    int top = 0;
    std::uint32_t node = 0;
    Real tmin = t0, tmax = t1;
    for (;;) {
        const KdNode& n = tree.nodes[node];
        if (!kd_is_leaf(n)) {
            Real t_split;
            SplitStep step = split_step(tree, node, ray, t_split);
            // Far only, near only or both: for incoherent rays a branch on that
            // is hard to predict, so the step computes masks instead. The far entry is always
            // written and kept only when both children are; the depth check of
            // every tree keeps that write inside the stack.
            const std::uint32_t far_only = 0u - static_cast<std::uint32_t>(t_split <= tmin);
            // !(>=): a NaN t_split takes both, as the branches did.
            const std::uint32_t both = ~far_only & (0u - static_cast<std::uint32_t>(!(t_split >= tmax)));
            KDRT_ASSERT(top < KDRT_MAX_TREE_DEPTH + 2);
            stack[top] = {step.far_child, t_split, tmax};
            top += static_cast<int>(both & 1u);
            node = (step.far_child & far_only) | (step.near_child & ~far_only);
            tmax = select_by_mask(both, t_split, tmax);
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
