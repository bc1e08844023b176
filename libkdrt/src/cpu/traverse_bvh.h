// BVH traversals for one ray, with the kd-tree traversals' contract
// (traversal_common.h): leaves are handed to visit(ids, count), which returns
// the distance beyond which nothing matters (the closest hit so far, or -inf
// once an any-hit query is satisfied); a node or leaf whose entry distance
// lies beyond it (plus the termination slack) is skipped.
//
// traverse_bvh walks a wide BVH (bvh/bvh.h) with a stack, testing all N
// boxes of a node at once (GCC vector extensions: SSE in the baseline copy,
// AVX in the AVX2 copy, cpu_isa.h) and going on to the hit children nearest
// first, as Embree's BVH8 single-ray traversal does; any-hit and every-hit
// queries take them in the node's order instead (ChildOrder), as Embree's
// occlusion rays do.
// traverse_bvh2 walks a binary BVH the same way, a box at a time.
//
// Box tests are conservative, so that a ray never misses a box it touches
// and the result is brute force's: the slab distances are (plane - origin) *
// (1 / direction), each of the three operations rounded once, and the far
// planes' reciprocal is multiplied by 1 + 8u (u the unit roundoff, 2^-24 for
// float), which covers Ize's bound (1 + 2 gamma_3, "Robust BVH Ray
// Traversal", JCGT 2013) and that product's own rounding. A slab's planes are
// chosen by the sign of the reciprocal (for -0 too). A ray with a zero
// direction component (an infinite reciprocal) gets a NaN distance where it
// lies in a slab's plane (0 * inf), which must not make it miss
// (bvh_box_hits; bvh2_box_hit keeps each NaN the first operand). Boxes are
// floats; a double ray tests them in double.
#pragma once

#include "bvh/bvh.h"
#include "common/debug_assert.h"
#include "cpu/traversal_common.h"
#include "cpu/traverse_packet.h"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>

namespace kdrt::detail::inline KDRT_CPU_ISA {

// The far distance's conservative factor: 1 + 8u.
template <class Real>
inline constexpr Real kBoxFarScale = Real(1) + Real(4) * std::numeric_limits<Real>::epsilon();

// Where visiting stops: beyond `done_at` plus the slack for a hit that lies a
// rounding error beyond where its box was entered (termination_slack).
template <class Real>
KDRT_HOT_INLINE Real bvh_limit(const Ray<Real>& ray, Real done_at) {
    return done_at + termination_slack(ray, done_at);
}

// Stack entries of the wide traversal: the deepest node has kBvhMaxDepth
// ancestors, each with at most N - 1 pending siblings, and pushes at most N.
template <int N>
inline constexpr int kBvhStackSize = kBvhMaxDepth * (N - 1) + N;

// The node's boxes are tested a native vector at a time: W lanes (4 floats
// in the baseline copy, 8 in the AVX2 one), N / W steps per node. Wider GCC
// vectors than the registers are emulated through memory, each broadcast a
// store and a stalled load.
template <class Real, int N>
inline constexpr int kBvhLanes = std::min<int>(N, KDRT_CPU_VECTOR_BYTES / static_cast<int>(sizeof(Real)));

// The ray as the box tests use it, in W lanes: the far planes' distances
// are taken with the reciprocal times the conservative factor (one rounding
// more, which 1 + 8u covers as well).
template <class Real, int W>
struct BvhRayLanes {
    using V = typename PacketLanes<Real, W>::Vec;
    int near[3];  // 1 where the direction is negative: the slab's near plane is its upper one
    V org[3], inv_near[3], inv_far[3];

    BvhRayLanes() = default;
    explicit BvhRayLanes(const Ray<Real>& ray) {
        for (int a = 0; a < 3; ++a) {
            const Real inv = axis_of(ray.inv_dir, a);
            near[a] = inv < Real(0) ? 1 : 0;
            org[a] = V{} + axis_of(ray.org, a);
            inv_near[a] = V{} + inv;
            inv_far[a] = V{} + inv * kBoxFarScale<Real>;
        }
    }
};

// The planes of W of a node's slots from slot c on, as a ray whose near
// planes are `near` (BvhRayLanes::near) meets them: the near ones and the far.
template <class Real, int W>
struct BvhNodePlanes {
    using V = typename PacketLanes<Real, W>::Vec;
    V near_plane[3], far_plane[3];

    template <int N>
    KDRT_HOT_INLINE BvhNodePlanes(const WideBvhNodeN<N>& node, const int (&near)[3], int c) {
        using FV = typename PacketLanes<float, W>::Vec;
        for (int a = 0; a < 3; ++a) {
            FV np, fp;
            __builtin_memcpy(&np, node.box[near[a]][a] + c, sizeof np);
            __builtin_memcpy(&fp, node.box[1 - near[a]][a] + c, sizeof fp);
            near_plane[a] = __builtin_convertvector(np, V);
            far_plane[a] = __builtin_convertvector(fp, V);
        }
    }
};

// Which of the W boxes of `p` the ray enters within [0, limit] (bit i: the
// i-th), and where (t_enter). The entry is the largest of the three near
// distances and 0, the exit the smallest of the far ones and the limit, each
// taken as two pairs, for a short dependency chain. A NaN distance (a ray
// lying in a slab's plane) must not narrow the interval: as the first
// operand of a select it loses, and as the second it wins its pair but then
// loses the second select, taking its pair's other operand with it: the
// interval only widens, so a ray never misses a box it touches.
template <class Real, int W>
KDRT_HOT_INLINE std::uint32_t bvh_box_hits(const BvhNodePlanes<Real, W>& p, const BvhRayLanes<Real, W>& r, Real limit,
                                           Real* t_enter) {
    using V = typename BvhRayLanes<Real, W>::V;
    const V zero{}, lim = zero + limit;
    V t_near[3], t_far[3];
    for (int a = 0; a < 3; ++a) {
        t_near[a] = (p.near_plane[a] - r.org[a]) * r.inv_near[a];
        t_far[a] = (p.far_plane[a] - r.org[a]) * r.inv_far[a];
    }
    const V n01 = t_near[0] > t_near[1] ? t_near[0] : t_near[1];
    const V n2 = t_near[2] > zero ? t_near[2] : zero;
    const V f01 = t_far[0] < t_far[1] ? t_far[0] : t_far[1];
    const V f2 = t_far[2] < lim ? t_far[2] : lim;
    const V tn = n01 > n2 ? n01 : n2;
    const V tf = f01 < f2 ? f01 : f2;
    __builtin_memcpy(t_enter, &tn, sizeof tn);
    return lane_bits<W>(tn <= tf);
}

// Which of a node's N boxes the ray enters within [0, limit] (bit i: slot
// i), and where (t_enter): bvh_box_hits, W slots at a time.
template <class Real, int N, int W>
KDRT_HOT_INLINE std::uint32_t bvh_node_hits(const WideBvhNodeN<N>& node, const BvhRayLanes<Real, W>& r, Real limit,
                                            Real (&t_enter)[N]) {
    std::uint32_t hits = 0;
    for (int c = 0; c < N; c += W)
        hits |= bvh_box_hits(BvhNodePlanes<Real, W>(node, r.near, c), r, limit, t_enter + c) << c;
    return hits;
}

// bvh_node_hits for the `active` lanes of a packet (hits[k], t_enter[k] for
// lane k; the others hit nothing), whose rays share their direction signs
// (packet_compatible): the node's planes are loaded once for all of them.
// Returns the slots some lane reached.
template <class Real, int N, int W, int K, class TV>
KDRT_HOT_INLINE std::uint32_t bvh_packet_node_hits(const WideBvhNodeN<N>& node, const BvhRayLanes<Real, W> (&r)[K],
                                                   std::uint32_t active, const TV& limit, Real (&t_enter)[K][N],
                                                   std::uint32_t (&hits)[K]) {
    for (int k = 0; k < K; ++k) hits[k] = 0;
    for (int c = 0; c < N; c += W) {
        const BvhNodePlanes<Real, W> planes(node, r[0].near, c);
        for (int k = 0; k < K; ++k)
            if ((active >> k) & 1u) hits[k] |= bvh_box_hits(planes, r[k], limit[k], t_enter[k] + c) << c;
    }
    std::uint32_t reached = 0;
    for (int k = 0; k < K; ++k) reached |= hits[k];
    return reached;
}

// No prefetch of a hit leaf's data (the default of the traversals).
struct NoLeafPrefetch {
    void operator()(std::uint32_t, std::uint32_t) const {}
};

// Starts the loads of the data of a node's `hits` children: prefetch(child,
// count) for leaf slots, the nodes themselves for inner ones. The first is
// visited now, the others later, and their data is on its way meanwhile.
template <int N, class Prefetch>
KDRT_HOT_INLINE void prefetch_children(const WideBvhNodeN<N>* nodes, const WideBvhNodeN<N>& node, std::uint32_t hits,
                                       Prefetch& prefetch) {
    for (; hits != 0; hits &= hits - 1) {
        const int i = __builtin_ctz(hits);
        if (node.is_leaf(i)) {
            prefetch(node.child[i], node.leaf_count(i));
        } else {
            prefetch_object(nodes + node.child[i]);
        }
    }
}

// The order in which a node's hit children are visited: nearest first, for
// closest hits (their limit shrinks as hits are found), or as the node holds
// them, for queries whose limit does not shrink (any hit, every hit). The
// order changes none of their answers, and an any-hit query rarely finds its
// blocker sooner nearest first by more than the sort costs.
enum class ChildOrder { NearestFirst, AsStored };

// A node's hit children (`hits`, not none) taken by a stack walk: the one to
// visit now into `cur`, the others onto the stack, as `Order` says (nearest
// first: the nearest now, the next nearest on top). entry(i) is slot i's
// stack entry, whose `t` is where the ray enters the slot's box.
template <ChildOrder Order, class Entry, class EntryOf>
KDRT_HOT_INLINE void take_children(std::uint32_t hits, EntryOf& entry, Entry* stack, int& top, Entry& cur) {
    const int i = __builtin_ctz(hits);
    hits &= hits - 1;
    if (Order == ChildOrder::AsStored || hits == 0) {  // the first now, the others (if any) in turn
        cur = entry(i);
        for (; hits != 0; hits &= hits - 1) stack[top++] = entry(__builtin_ctz(hits));
        return;
    }
    const int j = __builtin_ctz(hits);
    hits &= hits - 1;
    Entry a = entry(i), b = entry(j);
    if (a.t < b.t) std::swap(a, b);
    if (hits == 0) {  // two: the farther waits
        stack[top++] = a;
        cur = b;
        return;
    }
    // More: all on the stack, sorted so that the nearest is on top.
    const int first = top;
    stack[top++] = a;
    stack[top++] = b;
    for (; hits != 0; hits &= hits - 1) {
        const Entry e = entry(__builtin_ctz(hits));
        int k = top++;
        while (k > first && stack[k - 1].t < e.t) {
            stack[k] = stack[k - 1];
            --k;
        }
        stack[k] = e;
    }
    cur = stack[--top];
}

// The wide traversal over `nodes` (root at 0), whatever a leaf slot refers
// to: leaf(child, count) gets the slot's reference (bvh.h), count without the
// leaf flag, and returns what a visit returns. traverse_bvh below hands it a
// BVH's object ids; the cpu device's copy of the nodes refers to its packed
// triangle blocks instead (packed_leaves.h). prefetch as in prefetch_children.
template <ChildOrder Order = ChildOrder::NearestFirst, class Real, int N, class Leaf, class Prefetch = NoLeafPrefetch>
void traverse_bvh_nodes(const WideBvhNodeN<N>* nodes, [[maybe_unused]] std::size_t node_count, const Ray<Real>& ray,
                        Real t_max, Leaf&& leaf, Prefetch&& prefetch = {}) {
    if (node_count == 0) return;
    const BvhRayLanes<Real, kBvhLanes<Real, N>> lanes(ray);
    Real limit = bvh_limit(ray, t_max);
    struct Entry {
        std::uint32_t child, count;  // a slot's reference (bvh.h)
        Real t;                      // where the ray enters its box
    };
    Entry stack[kBvhStackSize<N>];
    int top = 0;
    Entry cur{0, 0, Real(0)};
    for (;;) {
        if ((cur.count & kBvhLeafFlag) == 0) {
            KDRT_ASSERT(cur.child < node_count);
            const WideBvhNodeN<N>& node = nodes[cur.child];
            alignas(64) Real t_enter[N];
            std::uint32_t hits = bvh_node_hits(node, lanes, limit, t_enter);
            auto entry = [&](int i) KDRT_HOT_INLINE_LAMBDA { return Entry{node.child[i], node.count[i], t_enter[i]}; };
            prefetch_children(nodes, node, hits, prefetch);
            if (hits != 0) {
                KDRT_ASSERT(top + std::popcount(hits) <= kBvhStackSize<N>);
                take_children<Order>(hits, entry, stack, top, cur);
                continue;
            }
        } else if (cur.count != kBvhLeafFlag) {
            const Real done_at = leaf(cur.child, cur.count & kBvhMaxLeafCount);
            if (!(done_at >= Real(0))) return;  // -inf: an any-hit query is satisfied
            const Real l = bvh_limit(ray, done_at);
            limit = l < limit ? l : limit;
        }
        // The nearest pending entry that still matters.
        for (;;) {
            if (top == 0) return;
            cur = stack[--top];
            if (cur.t <= limit) break;
        }
    }
}

// K rays through the wide BVH together (K a packet of coherent rays, such as
// a camera row's, which must pass packet_compatible: the lanes share their
// direction signs, and so a node's near and far planes). Each lane tests a
// node's boxes as traverse_bvh_nodes does for its ray alone, with its own
// limit, on planes loaded once for all lanes (bvh_packet_node_hits), and
// visits only the nodes its own tests reached within its own limit, in the
// packet's order (children nearest first by the lanes' least entry; with
// ChildOrder::AsStored, for any-hit packets, pushed in slot order, unsorted,
// so the highest slot first), so its limit shrinks at other moments than
// alone but never culls the leaf of its closest hit.
// What the lanes share is the stack, the ordering and the planes' loads, and
// their tests of one node overlap. leaf(child, count, k) visits a leaf
// slot's reference for lane k and returns what a visit returns for that
// ray; closest hits do not depend on the order (Hit::closer_than breaks ties).
// prefetch as in prefetch_children.
template <ChildOrder Order = ChildOrder::NearestFirst, class Real, int N, int K, class Leaf,
          class Prefetch = NoLeafPrefetch>
void traverse_bvh_packet(const WideBvhNodeN<N>* nodes, [[maybe_unused]] std::size_t node_count,
                         const Ray<Real>* const (&rays)[K], const Real (&t_max)[K], Leaf&& leaf,
                         Prefetch&& prefetch = {}) {
    static_assert(K <= 32, "a lane mask is 32 bits");
    using Lanes = BvhRayLanes<Real, kBvhLanes<Real, N>>;
    using TV = typename PacketLanes<Real, K>::Vec;  // a value per lane
    if (node_count == 0) return;
    Lanes lanes[K];
    TV limit;
    for (int k = 0; k < K; ++k) {
        lanes[k] = Lanes(*rays[k]);
        for (int a = 0; a < 3; ++a) KDRT_ASSERT(lanes[k].near[a] == lanes[0].near[a]);
        limit[k] = bvh_limit(*rays[k], t_max[k]);
    }
    struct Entry {
        TV t;                        // where each lane enters its box; +inf in lanes it did not reach (the root: unused)
        std::uint32_t child, count;  // a slot's reference (bvh.h)
        std::uint32_t lanes;         // the lanes whose tests reached it
        Real nearest;                // the least of their entries: the order
    };
    Entry stack[kBvhStackSize<N>];
    int top = 0;
    Entry cur{TV{}, 0, 0, (K == 32 ? 0u : 1u << K) - 1u, Real(0)};
    std::uint32_t live = cur.lanes;  // the lanes whose any-hit query is not yet satisfied
    for (;;) {
        if ((cur.count & kBvhLeafFlag) == 0) {
            KDRT_ASSERT(cur.child < node_count);
            const WideBvhNodeN<N>& node = nodes[cur.child];
            alignas(64) Real t_enter[K][N];
            std::uint32_t hits[K];
            std::uint32_t reached = bvh_packet_node_hits(node, lanes, cur.lanes, limit, t_enter, hits);
            prefetch_children(nodes, node, reached, prefetch);
            // The children some lane reached, on the stack with the nearest (AsStored:
            // the highest slot) on top.
            const int first = top;
            KDRT_ASSERT(top + std::popcount(reached) <= kBvhStackSize<N>);
            for (; reached != 0; reached &= reached - 1) {
                const int c = __builtin_ctz(reached);
                Entry e{TV{}, node.child[c], node.count[c], 0u, std::numeric_limits<Real>::infinity()};
                for (int k = 0; k < K; ++k) {
                    const bool in = (hits[k] >> c) & 1u;
                    e.t[k] = in ? t_enter[k][c] : std::numeric_limits<Real>::infinity();
                    e.lanes |= static_cast<std::uint32_t>(in) << k;
                    e.nearest = e.t[k] < e.nearest ? e.t[k] : e.nearest;
                }
                int j = top++;
                while (Order == ChildOrder::NearestFirst && j > first && stack[j - 1].nearest < e.nearest) {
                    stack[j] = stack[j - 1];
                    --j;
                }
                stack[j] = e;
            }
        } else if (cur.count != kBvhLeafFlag) {
            for (std::uint32_t m = cur.lanes; m != 0; m &= m - 1) {
                const int k = __builtin_ctz(m);
                const Real done_at = leaf(cur.child, cur.count & kBvhMaxLeafCount, k);
                // -inf: an any-hit query is satisfied, and the lane enters no box again.
                constexpr Real kDone = -std::numeric_limits<Real>::infinity();
                const bool satisfied = !(done_at >= Real(0));
                const Real l = satisfied ? kDone : bvh_limit(*rays[k], done_at);
                limit[k] = l < limit[k] ? l : limit[k];
                if (satisfied) live &= ~(1u << k);
            }
            if (live == 0) return;  // every lane satisfied: nothing on the stack matters
        }
        // The next pending entry (the nearest, unless AsStored) that still matters to some lane.
        for (;;) {
            if (top == 0) return;
            cur = stack[--top];
            cur.lanes &= lane_bits<K>(cur.t <= limit);
            if (cur.lanes != 0) break;
        }
    }
}

// A BVH's leaves as visit(ids, count): their object ids.
template <ChildOrder Order = ChildOrder::NearestFirst, class Real, int N, class Visit>
void traverse_bvh(const WideBvhN<N>& bvh, const Ray<Real>& ray, Real t_max, Visit&& visit) {
    auto leaf = [&](std::uint32_t first, std::uint32_t count) KDRT_HOT_INLINE_LAMBDA {
        KDRT_ASSERT(std::size_t{first} + count <= bvh.leaf_objects.size());
        return visit(bvh.leaf_objects.data() + first, count);
    };
    traverse_bvh_nodes<Order>(bvh.nodes.data(), bvh.nodes.size(), ray, t_max, leaf);
}

// Slab test of one float box: whether the ray meets it within [0, limit], and where it enters.
template <class Real>
KDRT_HOT_INLINE bool bvh2_box_hit(const Bvh2Node& n, const Ray<Real>& ray, Real limit, Real& t_enter) {
    Real tn = Real(0), tf = std::numeric_limits<Real>::infinity();
    for (int a = 0; a < 3; ++a) {
        const bool negative = axis_of(ray.inv_dir, a) < Real(0);
        const Real lo = static_cast<Real>(negative ? n.hi[a] : n.lo[a]);
        const Real hi = static_cast<Real>(negative ? n.lo[a] : n.hi[a]);
        const Real t_near = (lo - axis_of(ray.org, a)) * axis_of(ray.inv_dir, a);
        const Real t_far = (hi - axis_of(ray.org, a)) * (axis_of(ray.inv_dir, a) * kBoxFarScale<Real>);
        tn = t_near > tn ? t_near : tn;
        tf = t_far < tf ? t_far : tf;
    }
    tf = tf < limit ? tf : limit;
    t_enter = tn;
    return tn <= tf;
}

template <class Real, class Visit>
void traverse_bvh2(const Bvh2& bvh, const Ray<Real>& ray, Real t_max, Visit&& visit) {
    if (bvh.nodes.empty()) return;
    Real limit = bvh_limit(ray, t_max);
    struct Entry {
        std::uint32_t node;
        Real t;
    };
    Entry stack[kBvhMaxDepth + 2];
    int top = 0;
    Real t_root;
    if (!bvh2_box_hit(bvh.nodes[0], ray, limit, t_root)) return;
    std::uint32_t cur = 0;
    for (;;) {
        const Bvh2Node& n = bvh.nodes[cur];
        if (!bvh2_is_leaf(n)) {
            Real ta, tb;
            const bool a = bvh2_box_hit(bvh.nodes[n.first], ray, limit, ta);
            const bool b = bvh2_box_hit(bvh.nodes[n.first + 1], ray, limit, tb);
            if (a && b) {
                const bool second_first = tb < ta;
                KDRT_ASSERT(top < kBvhMaxDepth + 2);
                stack[top++] = second_first ? Entry{n.first, ta} : Entry{n.first + 1, tb};
                cur = second_first ? n.first + 1 : n.first;
                continue;
            }
            if (a || b) {
                cur = a ? n.first : n.first + 1;
                continue;
            }
        } else {
            KDRT_ASSERT(std::size_t{n.first} + n.count <= bvh.leaf_objects.size());
            const Real done_at = visit(bvh.leaf_objects.data() + n.first, n.count);
            if (!(done_at >= Real(0))) return;
            const Real l = bvh_limit(ray, done_at);
            limit = l < limit ? l : limit;
        }
        for (;;) {
            if (top == 0) return;
            --top;
            if (stack[top].t <= limit) break;
        }
        cur = stack[top].node;
    }
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
