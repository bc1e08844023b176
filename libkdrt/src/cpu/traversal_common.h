// What the C++ traversals share: clipping a ray to the tree's box, the
// near/far decision at a split plane, and the termination slack.
//
// Every traversal visits leaves front to back (a BVH's any-hit and every-hit
// walks: in its nodes' order, traverse_bvh.h) and hands each leaf's objects to
// a callback, so node code knows nothing about primitives. The callback returns
// the distance beyond which nothing matters any more (the closest hit so far,
// or -inf once a shadow ray is blocked); the traversal stops when that is
// before the current leaf's exit. The OpenCL twins live in cl/traverse_*.cl.
#pragma once

#include "common/debug_assert.h"
#include "cpu/ray.h"

#include <kdrt/kd_tree.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace kdrt::detail::inline KDRT_CPU_ISA {

// A hit found in one leaf may lie a rounding error beyond that leaf's exit
// while another object, stored only in the next leaf, is hit a rounding error
// nearer. Stopping only when the best hit is clearly inside the leaf keeps the
// result identical to brute force; the price is an occasional extra leaf.
template <class Real>
KDRT_HOT_INLINE Real termination_slack(const Ray<Real>& ray, Real t) {
    constexpr Real eps = sizeof(Real) == sizeof(double) ? Real(1e-13) : Real(1e-5);
    return eps * std::max(ray.org_max, std::abs(t));
}

template <class Real>
KDRT_HOT_INLINE bool leaf_finishes(const Ray<Real>& ray, Real done_at, Real t_exit) {
    return done_at < t_exit - termination_slack(ray, t_exit);
}

// Slab test against the tree's box; [t0, t1] is the part with t in [0, t_max].
// Zero direction components never divide: the origin is inside the slab or not.
template <class Real>
KDRT_HOT_INLINE bool clip_to_box(const Ray<Real>& ray, const Aabb& box, Real t_max, Real& t0, Real& t1) {
    t0 = Real(0);
    t1 = t_max;
    for (int a = 0; a < 3; ++a) {
        const Real lo = static_cast<Real>(box.lo[a]), hi = static_cast<Real>(box.hi[a]);
        if (ray.dir[a] == Real(0)) {
            if (ray.org[a] < lo || ray.org[a] > hi) return false;
            continue;
        }
        Real tn = (lo - ray.org[a]) * ray.inv_dir[a];
        Real tf = (hi - ray.org[a]) * ray.inv_dir[a];
        if (tn > tf) std::swap(tn, tf);
        t0 = std::max(t0, tn);
        t1 = std::min(t1, tf);
    }
    return t0 <= t1;
}

// clip_to_box on the tree's root cell; false for an empty tree too.
template <class Real>
KDRT_HOT_INLINE bool clip_to_tree(const KdTree& tree, const Ray<Real>& ray, Real t_max, Real& t0, Real& t1) {
    return !tree.nodes.empty() && clip_to_box(ray, tree.bounds, t_max, t0, t1);
}

// A far child waiting on a traversal's stack, with the ray's segment in its cell.
template <class Real>
struct StackEntry {
    std::uint32_t node;
    Real tmin, tmax;
};

// At an inner node: which child the ray meets first, and where it crosses the
// split plane (+inf when it runs parallel to it; then the origin's side is near,
// and a ray lying in the plane takes the lower side: builders give objects
// touching a split plane to both sides, so either side holds all it can hit).
struct SplitStep {
    std::uint32_t near_child, far_child;
};

template <class Real>
KDRT_HOT_INLINE SplitStep split_step(const KdTree& tree, std::uint32_t node, const Ray<Real>& ray, Real& t_split) {
    const KdNode& n = tree.nodes[node];
    const int axis = kd_axis(n);
    const Real split = static_cast<Real>(kd_split(n));
    const Real o = axis_of(ray.org, axis), d = axis_of(ray.dir, axis);
    const std::uint32_t below = node + 1, above = kd_above_child(n);
    // The below child is the next node, most likely in the same cache line; fetch the other early.
    KDRT_PREFETCH(&tree.nodes[above]);
    const bool below_first = d > Real(0) || (d == Real(0) && o <= split);
    t_split = d == Real(0) ? std::numeric_limits<Real>::infinity() : (split - o) * axis_of(ray.inv_dir, axis);
    return below_first ? SplitStep{below, above} : SplitStep{above, below};
}

// Which children of an inner node a ray's segment [tmin, tmax] meets, from
// where it crosses the split plane: the far one alone when it crosses at or
// before tmin (so a leaf is never entered with zero length), the near one
// alone when at or after tmax, else both.
enum class Crossing { FarOnly, NearOnly, Both };

template <class Real>
KDRT_HOT_INLINE Crossing crossing(Real t_split, Real tmin, Real tmax) {
    if (t_split <= tmin) return Crossing::FarOnly;
    if (t_split >= tmax) return Crossing::NearOnly;
    return Crossing::Both;
}

// The leaf node holds its list's range (first, count): no leaf record to load,
// and no cache miss for one on big trees.
template <class Visit>
KDRT_HOT_INLINE auto visit_leaf(const KdTree& tree, const KdNode& n, Visit& visit) {
    KDRT_ASSERT(std::size_t{kd_leaf_first(n)} + kd_leaf_count(n) <= tree.leaf_objects.size());
    return visit(tree.leaf_objects.data() + kd_leaf_first(n), kd_leaf_count(n));
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
