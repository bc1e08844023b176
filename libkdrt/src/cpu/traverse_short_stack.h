// Traversal "short-stack": the stack traversal with a stack of only a few
// entries, kd-restart when it runs dry, and push-down (Horn, Sugerman, Houston
// and Hanrahan 2007, "Interactive k-D tree GPU raytracing").
//
// The stack is a ring buffer: pushing onto a full one drops the oldest entry,
// which is the farthest part of the ray. When the stack is empty before the
// ray has reached the end of its segment in the tree's box, some far children
// were dropped: start again with tmin = the current leaf's exit, as kd-restart
// does, from the deepest node whose cell holds all of the ray's remaining
// segment (push-down: the last node reached from the restart node without
// pushing, i.e. without splitting the segment). Leaves are then met in the
// same order as with a full stack, never twice, so mailboxing and the
// termination test (a hit counts once it lies before the current leaf's exit)
// stay exactly those of the stack traversal.
//
// StackSize is a template parameter so that tests can force restarts with 1 or
// 2 entries; the renderers use KDRT_SHORT_STACK_SIZE, like the OpenCL twin.
#pragma once

#include "cpu/traversal_common.h"
#include "device/kernel_records.h"

namespace kdrt::detail::inline KDRT_CPU_ISA {

template <int StackSize = KDRT_SHORT_STACK_SIZE, class Real, class Visit>
void traverse_short_stack(const KdTree& tree, const Ray<Real>& ray, Real t_max, Visit&& visit) {
    static_assert(StackSize >= 1, "a short stack needs at least one entry");
    Real t0, t1;
    if (!clip_to_tree(tree, ray, t_max, t0, t1)) return;
    StackEntry<Real> stack[StackSize] = {};  // a few entries: zeroing is free and spares GCC a maybe-uninitialized false alarm
    int top = 0, count = 0;  // next free slot (modulo StackSize), entries held
    std::uint32_t node = 0, restart_node = 0;
    bool push_down = true;  // no push since the last (re)start: node's cell holds all of [tmin, t1]
    Real tmin = t0, tmax = t1;
    for (;;) {
        const KdNode& n = tree.nodes[node];
        if (!kd_is_leaf(n)) {
            Real t_split;
            const SplitStep step = split_step(tree, node, ray, t_split);
            const Crossing c = crossing(t_split, tmin, tmax);
            node = c == Crossing::FarOnly ? step.far_child : step.near_child;
            if (c == Crossing::Both) {
                stack[top] = {step.far_child, t_split, tmax};
                top = top + 1 == StackSize ? 0 : top + 1;
                count = count < StackSize ? count + 1 : StackSize;
                tmax = t_split;
                push_down = false;
            }
            if (push_down) restart_node = node;
            continue;
        }
        if (leaf_finishes(ray, visit_leaf(tree, n, visit), tmax)) return;
        if (count == 0) {
            if (tmax >= t1) return;
            node = restart_node;  // entries were dropped: kd-restart behind this leaf
            tmin = tmax;
            tmax = t1;
            push_down = true;
            continue;
        }
        top = top == 0 ? StackSize - 1 : top - 1;
        --count;
        node = stack[top].node;
        tmin = stack[top].tmin;
        tmax = stack[top].tmax;
    }
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
