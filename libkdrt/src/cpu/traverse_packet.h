// Packet traversal: N rays whose direction components all have the same,
// nonzero signs walk the kd-tree together with one shared stack (Wald 2004,
// "Realtime Ray Tracing and Interactive Global Illumination", ch. 7; Reshetov
// et al. 2005, "Multi-level ray tracing"). Coherent rays (a camera row) share
// the node loads and the branch decisions; the per-lane segment arithmetic is
// on GCC vector extensions (SSE on portable x86-64). Its twin,
// cl/traverse_packet.cl, runs only on CPU devices (PoCL): a GPU runs its
// work-items side by side, one ray each.
//
// Each lane sees exactly what traverse_stack gives its ray alone: the same
// leaves in the same order with the same [tmin, tmax] (the near child is the
// same for every lane because the signs agree), and it stops at the same leaf
// (leaf_finishes). A node is visited when some lane's segment meets it; the
// packet stops when every lane has finished. Rays that are not
// packet_compatible must go through traverse_stack.
#pragma once

#include "cpu/traversal_common.h"

#include <cmath>
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if KDRT_CPU_VECTOR_BYTES >= 32
#include <immintrin.h>  // included by avx2_prelude.h before the AVX2 target: no new definitions here
#endif

namespace kdrt::detail::inline KDRT_CPU_ISA {

// Same direction signs on every axis, no zero components and finite
// reciprocals (a zero component's near child depends on the origin, not the
// sign; an infinite reciprocal can make t_split NaN): then one near/far order
// holds for the whole packet.
template <int N, class Real>
inline bool packet_compatible(const Ray<Real>* const (&rays)[N]) {
    for (int a = 0; a < 3; ++a) {
        const bool positive = axis_of(rays[0]->dir, a) > Real(0);
        for (int i = 0; i < N; ++i) {
            const Real d = axis_of(rays[i]->dir, a), inv = axis_of(rays[i]->inv_dir, a);
            if (d == Real(0) || (d > Real(0)) != positive || !std::isfinite(inv)) return false;
        }
    }
    return true;
}

// Lanes of a packet as one GCC vector: the node step's arithmetic and
// comparisons are then single SSE operations on portable x86-64 (no -march).
template <class Real, int N>
struct PacketLanes {
    typedef Real Vec __attribute__((vector_size(sizeof(Real) * N)));
};

// One bit per lane from a comparison's all-ones/zero lanes.
template <int N, class Mask>
KDRT_HOT_INLINE std::uint32_t lane_bits(const Mask& m) {  // by reference: no AVX-sized arguments (-Wpsabi)
#if defined(__SSE2__)
    if constexpr (sizeof(Mask) == 16 && N == 4) return static_cast<std::uint32_t>(_mm_movemask_ps(__m128(m)));
    if constexpr (sizeof(Mask) == 16 && N == 2) return static_cast<std::uint32_t>(_mm_movemask_pd(__m128d(m)));
#if KDRT_CPU_VECTOR_BYTES >= 32
    if constexpr (sizeof(Mask) == 32 && N == 8) return static_cast<std::uint32_t>(_mm256_movemask_ps(__m256(m)));
    if constexpr (sizeof(Mask) == 32 && N == 4) return static_cast<std::uint32_t>(_mm256_movemask_pd(__m256d(m)));
#else
    if constexpr (sizeof(Mask) == 32 && N == 4) {  // 4 doubles: two SSE halves
        __m128d half[2];
        __builtin_memcpy(half, &m, sizeof(half));
        return static_cast<std::uint32_t>(_mm_movemask_pd(half[0]) | (_mm_movemask_pd(half[1]) << 2));
    }
    if constexpr (sizeof(Mask) == 32 && N == 8) {  // 8 floats: two SSE halves
        __m128 half[2];
        __builtin_memcpy(half, &m, sizeof(half));
        return static_cast<std::uint32_t>(_mm_movemask_ps(half[0]) | (_mm_movemask_ps(half[1]) << 4));
    }
#endif
#endif
    std::uint32_t bits = 0;
    for (int i = 0; i < N; ++i) bits |= static_cast<std::uint32_t>(m[i] != 0) << i;
    return bits;
}

// r = the square roots of x's four doubles (correctly rounded, as std::sqrt).
template <class V>
KDRT_HOT_INLINE void sqrt_lanes(const V& x, V& r) {  // by reference, as lane_bits
    static_assert(sizeof(V) == 4 * sizeof(double));
#if KDRT_CPU_VECTOR_BYTES >= 32
    r = V(_mm256_sqrt_pd(__m256d(x)));
#elif defined(__SSE2__)
    __m128d half[2];
    __builtin_memcpy(half, &x, sizeof(half));
    half[0] = _mm_sqrt_pd(half[0]);
    half[1] = _mm_sqrt_pd(half[1]);
    __builtin_memcpy(&r, half, sizeof(half));
#else
    for (int i = 0; i < 4; ++i) r[i] = std::sqrt(x[i]);
#endif
}

// visit(lanes, ids, count, done_at) tests a leaf's objects for the lanes in
// the bit mask `lanes` and sets done_at[i] of each such lane to its done-at
// distance, as the single-ray visit returns it (test_leaf_packet,
// intersect_packet.h, tests one object against all those lanes at once).
template <int N, class Real, class Visit>
void traverse_stack_packet(const KdTree& tree, const Ray<Real>* const (&rays)[N], const Real (&t_max)[N],
                           Visit&& visit) {
    static_assert(N <= 32, "lane masks are 32 bits");
    using V = typename PacketLanes<Real, N>::Vec;
    if (tree.nodes.empty()) return;
    // Origins and reciprocals by axis: the split arithmetic is one vector op.
    V org[3], inv[3], tmin = {}, tmax = {};
    for (int a = 0; a < 3; ++a)
        for (int i = 0; i < N; ++i) {
            org[a][i] = axis_of(rays[i]->org, a);
            inv[a][i] = axis_of(rays[i]->inv_dir, a);
        }
    std::uint32_t active = 0;
    for (int i = 0; i < N; ++i) {
        Real t0, t1;
        if (clip_to_box(*rays[i], tree.bounds, t_max[i], t0, t1)) active |= 1u << i;
        tmin[i] = t0;
        tmax[i] = t1;
    }
    std::uint32_t live = active;  // lanes that have not finished
    // Bit a: the packet's direction is positive on axis a (the same for every lane).
    std::uint32_t positive = 0;
    for (int a = 0; a < 3; ++a) positive |= static_cast<std::uint32_t>(axis_of(rays[0]->dir, a) > Real(0)) << a;
    struct Entry {
        V tmin, tmax;
        std::uint32_t node, active;
    };
    Entry stack[KDRT_MAX_TREE_DEPTH + 2];
    int top = 0;
    std::uint32_t node = 0;
    for (;;) {
        const KdNode& n = tree.nodes[node];
        if (active != 0 && !kd_is_leaf(n)) {
            const int axis = kd_axis(n);
            const Real split = static_cast<Real>(kd_split(n));
            const std::uint32_t below = node + 1, above = kd_above_child(n);
            KDRT_PREFETCH(&tree.nodes[above]);
            const bool below_first = positive >> axis & 1u;
            const std::uint32_t near_child = below_first ? below : above, far_child = below_first ? above : below;
            // Per lane as in traverse_stack: t_split <= tmin: far only; t_split >= tmax: near only; else both
            // (t_split == tmin == tmax is far only, as there).
            const V ts = (split - org[axis]) * inv[axis];
            const std::uint32_t wants_near = lane_bits<N>(ts > tmin) & active;
            const std::uint32_t wants_far = lane_bits<N>((ts <= tmin) | (ts < tmax)) & active;
            if (wants_near == 0) {
                node = far_child;
            } else if (wants_far == 0) {
                node = near_child;
            } else {
                Entry& e = stack[top++];
                e.node = far_child;
                e.active = wants_far;
                e.tmin = ts > tmin ? ts : tmin;
                e.tmax = tmax;
                tmax = ts < tmax ? ts : tmax;
                node = near_child;
                active = wants_near;
            }
            continue;
        }
        if (active != 0) {
            Real done_at[N];
            visit(active, tree.leaf_objects.data() + kd_leaf_first(n), kd_leaf_count(n), done_at);
            for (std::uint32_t lanes = active; lanes != 0; lanes &= lanes - 1) {
                const int i = __builtin_ctz(lanes);
                if (leaf_finishes(*rays[i], done_at[i], tmax[i])) live &= ~(1u << i);
            }
        }
        if (live == 0) return;
        if (top == 0) return;
        const Entry& e = stack[--top];
        node = e.node;
        active = e.active & live;
        tmin = e.tmin;
        tmax = e.tmax;
    }
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
