// Tracer: the cpu device's one tracing core. Closest-hit and any-hit queries
// of single rays and packets over a scene's geometry, through an acceleration
// structure's traversal and the leaf tests, with the hit window as a policy
// (hit_window.h). The Whitted renderer (render_frame.h, through the shading
// interface at the end of the class), the ray queries (ray_query_loops.h) and
// the tests all trace through it.
//
// A structure plugs in through traverse(): its traversal hands the leaves a
// ray meets, front to back (a BVH's any-hit and every-hit walks: in its
// nodes' order, ChildOrder), to visit(LeafRef) (the leaf's ids, or its packed
// blocks), and stops where visit's answer (the distance beyond which nothing
// matters) lies before the leaf's exit (traversal_common.h): the kd-tree's
// five traversals and the wide BVH's (traverse_bvh.h), which on packed leaves
// walks the packed copy of the nodes (packed_leaves.h).
#pragma once

#include "common/debug_assert.h"
#include "cpu/closest_point.h"
#include "cpu/function_ref.h"
#include "cpu/hit_window.h"
#include "cpu/intersect.h"
#include "cpu/intersect_packet.h"
#include "cpu/mailbox.h"
#include "cpu/packed_leaves.h"
#include "cpu/traverse_bvh.h"
#include "cpu/traverse_nearest.h"
#include "cpu/traverse_none.h"
#include "cpu/traverse_packet.h"
#include "cpu/traverse_restart.h"
#include "cpu/traverse_ropes.h"
#include "cpu/traverse_short_stack.h"
#include "cpu/traverse_stack.h"
#include "device/accel.h"

#include <kdrt/commit_options.h>
#include <kdrt/error.h>

#include <array>
#include <limits>
#include <numeric>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace kdrt::detail::inline KDRT_CPU_ISA {

// ShortStackSize: entries of the short-stack traversal (tests use 1 and 2 to force restarts).
template <class Real, int ShortStackSize = KDRT_SHORT_STACK_SIZE>
class Tracer {
public:
    // Traces through accel.bvh when it is given, else accel.kd with
    // `traversal` (neither for Traversal::None: every object). `geometry` and
    // the structure must outlive the tracer. pack_leaves: repack a small
    // enough structure's leaves for the batched leaf test (packed_leaves.h);
    // false keeps test_leaf_ray (tests cover both).
    Tracer(const SceneGeometry<Real>& geometry, AccelRef accel, Traversal traversal, IntersectConfig config = {},
           bool pack_leaves = true)
        : g_(geometry), tree_(accel.kd), bvh_(accel.bvh), traversal_(traversal), config_(config) {
        if (traversal_ == Traversal::None) {
            all_ids_.resize(g_.object_count());
            std::iota(all_ids_.begin(), all_ids_.end(), 0u);
            tree_ = nullptr;
            bvh_ = nullptr;
            return;
        }
        if (bvh_) {
            if (traversal_ != Traversal::Stack)
                throw Error(ErrorCode::InvalidArgument, std::string("the BVH has no ") + to_string(traversal_) +
                                                            " traversal: only stack (and none)");
            tree_ = nullptr;
            leaf_objects_ = bvh_->leaf_objects;
        } else {
            if (!tree_) throw Error(ErrorCode::InvalidArgument, "the traversal needs a kd-tree");
            if (traversal_ == Traversal::Ropes && !tree_->has_ropes())
                throw Error(ErrorCode::InvalidArgument, "the ropes traversal needs a kd-tree with ropes");
            mailbox_ = tree_duplicates_objects(tree_);
            leaf_objects_ = tree_->leaf_objects;
        }
        if (pack_leaves && batch_triangles_)
            packed_ = bvh_ ? PackedLeaves<Real, kLeafLanes<Real>>(*bvh_, g_)
                           : PackedLeaves<Real, kLeafLanes<Real>>(leaf_objects_, leaf_ranges(*tree_), g_);
    }

    // The closest hit inside `window`; an invalid Hit when there is none.
    template <class Window>
    Hit<Real> closest(const Ray<Real>& ray, const Window& window) const {
        ClosestQuery<Window> q{*this, ray, window};
        run(q);
        return q.best;
    }

    // Whether some object is hit inside `window`.
    template <class Window>
    bool any(const Ray<Real>& ray, const Window& window) const {
        AnyQuery<Window> q{*this, ray, window};
        run(q);
        return q.hit;
    }

    // N rays at once through the packet traversal (Wald 2004), with the
    // single-ray results bit for bit; false (nothing done) unless packs(rays).
    template <int N, class Window>
    bool closest(const Ray<Real>* const (&rays)[N], const Window (&windows)[N], Hit<Real> (&hits)[N]) const {
        if (!packs(rays)) return false;
        if (bvh_) {
            auto q = queries<ClosestQuery<Window>>(rays, windows);
            bvh_packet(q, rays);
            for (int k = 0; k < N; ++k) hits[k] = q[k].best;
        }
        else if (mailbox_) closest_packet_with<Mailbox>(rays, windows, hits);
        else closest_packet_with<NoMailbox>(rays, windows, hits);
        return true;
    }
    template <int N, class Window>
    bool any(const Ray<Real>* const (&rays)[N], const Window (&windows)[N], bool (&hit)[N]) const {
        if (!packs(rays)) return false;
        if (bvh_) {
            auto q = queries<AnyQuery<Window>>(rays, windows);
            bvh_packet(q, rays);
            for (int k = 0; k < N; ++k) hit[k] = q[k].hit;
        }
        else if (mailbox_) any_packet_with<Mailbox>(rays, windows, hit);
        else any_packet_with<NoMailbox>(rays, windows, hit);
        return true;
    }

    // Every hit inside `window`, to on_hit(hit) in no particular order: each
    // triangle once however many leaves hold it, a sphere once per root
    // inside the window. `seen` is scratch space (the objects hit so far).
    template <class Window, class OnHit>
    void every(const Ray<Real>& ray, const Window& window, std::vector<std::uint32_t>& seen, OnHit&& on_hit) const {
        seen.clear();
        using Sink = FunctionRef<void(const Hit<Real>&)>;
        Sink sink(on_hit);  // one traversal per window and structure, whatever the caller's on_hit
        EveryQuery<Window, Sink> q{*this, ray, window, seen, sink};
        run(q);
    }

    // The point of the scene's surface nearest to `p` (working frame); an
    // invalid NearestPoint for a scene without objects.
    NearestPoint nearest(const glm::dvec3& p) const {
        NearestPoint best;
        auto visit = [&](const std::uint32_t* ids, std::uint32_t count) {
            for (std::uint32_t i = 0; i < count; ++i) test_nearest(g_, p, ids[i], best);
        };
        if (bvh_) traverse_nearest(*bvh_, p, visit, [&] { return best.d2; });
        else if (tree_) traverse_nearest(*tree_, p, visit, [&] { return best.d2; });
        else visit(all_ids_.data(), static_cast<std::uint32_t>(all_ids_.size()));
        return best;
    }

    // Whether these rays take a packet traversal: rays whose directions share
    // their signs, none zero (packet_compatible: coherent enough to share the walk), on
    // the kd-tree's stack traversal or on a BVH's packed nodes.
    template <int N>
    bool packs(const Ray<Real>* const (&rays)[N]) const {
        const bool walks = (tree_ && traversal_ == Traversal::Stack) || (bvh_ && packed_.packed());
        return walks && packet_compatible(rays);
    }

    // The shading interface (whitted_tracer.h): every hit ahead of a ray, and
    // shadow rays blocked before t_max; packets ray by ray where they do not pack.
    Hit<Real> closest(const Ray<Real>& ray) const { return closest(ray, OpenWindow<Real>{}); }
    bool occluded(const Ray<Real>& ray, Real t_max) const { return any(ray, ShadowWindow<Real>{t_max}); }
    template <int N>
    void closest(const Ray<Real>* const (&rays)[N], Hit<Real> (&hits)[N]) const {
        const OpenWindow<Real> open[N] = {};
        if (closest(rays, open, hits)) return;
        for (int i = 0; i < N; ++i) hits[i] = closest(*rays[i]);
    }
    template <int N>
    void occluded(const Ray<Real>* const (&rays)[N], const Real (&t_max)[N], bool (&blocked)[N]) const {
        ShadowWindow<Real> windows[N];
        for (int i = 0; i < N; ++i) windows[i].t_max = t_max[i];
        if (any(rays, windows, blocked)) return;
        for (int i = 0; i < N; ++i) blocked[i] = occluded(*rays[i], t_max[i]);
    }

    // The geometry's objects moved and the BVH was refit to them in place
    // (the same leaves): the packed copy of both follows, in place. A
    // kd-tree is never refit.
    void refit() {
        if (bvh_ && packed_.packed()) packed_.refill(*bvh_, g_);
    }

    const SceneGeometry<Real>& geometry() const { return g_; }
    bool leaves_packed() const { return packed_.packed(); }
    std::size_t packed_bytes() const { return packed_.bytes(); }

private:
    using PackedLeaf = typename PackedLeaves<Real, kLeafLanes<Real>>::Leaf;

    // A triangle hit from a batched leaf test, its vertices prefetched: the caller
    // reads them for the hit's normal, and the traversal goes on meanwhile.
    KDRT_HOT_INLINE const Hit<Real>& fetching(const Hit<Real>& h) const {
        KDRT_PREFETCH(&g_.triangles[static_cast<std::uint32_t>(h.id) - g_.spheres.size()]);
        return h;
    }

    // What a visit gets of a leaf: its objects' ids, or where the leaves are
    // packed, its packed record (a packed BVH's node slots refer to no ids).
    struct LeafRef {
        const std::uint32_t* ids;
        std::uint32_t count;
        bool packed;
        PackedLeaf blocks;  // when packed
    };

    // One ray's query, as the leaf tests report to it: single(id) tests an
    // object, take(h) is a batched leaf test's triangle hit (inside the ray's
    // extent, not yet the window); both return true once the ray needs no
    // more tests, and so does done(). done_at() is what a visit returns
    // (traversal_common.h).
    template <class Window>
    struct ClosestQuery {
        const Tracer& tracer;
        const Ray<Real>& ray;
        const Window& window;
        Hit<Real> best{};
        KDRT_HOT_INLINE bool single(std::uint32_t id) {
            Hit<Real> h;
            if (test_object(tracer.g_, ray, id, window, tracer.config_, h) && h.closer_than(best.t, best.id)) best = h;
            return false;
        }
        KDRT_HOT_INLINE bool take(const Hit<Real>& h) {
            if (window.contains(h.t) && h.closer_than(best.t, best.id)) best = tracer.fetching(h);
            return false;
        }
        bool done() const { return false; }
        Real done_at() const { return best.t; }
        static constexpr ChildOrder kOrder = ChildOrder::NearestFirst;
    };

    template <class Window>
    struct AnyQuery {
        const Tracer& tracer;
        const Ray<Real>& ray;
        const Window& window;
        bool hit = false;
        KDRT_HOT_INLINE bool single(std::uint32_t id) {
            Hit<Real> h;
            return hit = test_object(tracer.g_, ray, id, window, tracer.config_, h);
        }
        KDRT_HOT_INLINE bool take(const Hit<Real>& h) { return hit = window.contains(h.t); }
        bool done() const { return hit; }
        Real done_at() const {
            return hit ? -std::numeric_limits<Real>::infinity() : std::numeric_limits<Real>::infinity();
        }
        static constexpr ChildOrder kOrder = ChildOrder::AsStored;
    };

    // Every hit to on_hit: each triangle once (`seen`, where a mailbox is
    // lossy), a sphere once per root inside the window.
    template <class Window, class OnHit>
    struct EveryQuery {
        const Tracer& tracer;
        const Ray<Real>& ray;
        const Window& window;
        std::vector<std::uint32_t>& seen;
        OnHit& on_hit;
        KDRT_HOT_INLINE bool first_hit_of(std::uint32_t id) {
            if (!tracer.mailbox_) return true;
            for (std::uint32_t s : seen)
                if (s == id) return false;
            seen.push_back(id);
            return true;
        }
        KDRT_HOT_INLINE bool single(std::uint32_t id) {
            const SceneGeometry<Real>& g = tracer.g_;
            if (id < g.spheres.size()) {
                const auto& sphere = g.spheres[id];
                Real t0, t1;
                if (!(tracer.config_.textbook ? sphere_roots_textbook(ray, sphere.center, sphere.radius, t0, t1)
                                              : sphere_roots(ray, sphere.center, sphere.radius, t0, t1)))
                    return false;
                const bool in0 = window.contains(t0), in1 = window.contains(t1);
                if ((in0 || in1) && first_hit_of(id)) {
                    Hit<Real> h;
                    h.id = static_cast<std::int32_t>(id);
                    if (in0) { h.t = t0; on_hit(h); }
                    if (in1) { h.t = t1; on_hit(h); }
                }
                return false;
            }
            Hit<Real> h;
            if (test_object(g, ray, id, window, tracer.config_, h) && first_hit_of(id)) on_hit(h);
            return false;
        }
        KDRT_HOT_INLINE bool take(const Hit<Real>& h) {
            if (window.contains(h.t) && first_hit_of(static_cast<std::uint32_t>(h.id))) on_hit(h);
            return false;
        }
        bool done() const { return false; }
        Real done_at() const { return std::numeric_limits<Real>::infinity(); }
        static constexpr ChildOrder kOrder = ChildOrder::AsStored;
    };

    // A query over the structure, through the batched leaf test where it
    // pays and with the mailbox where the structure repeats objects.
    template <class Query>
    void run(Query& q) const {
        if (batch_triangles_) return mailbox_ ? run_with<Mailbox, true>(q) : run_with<NoMailbox, true>(q);
        return mailbox_ ? run_with<Mailbox, false>(q) : run_with<NoMailbox, false>(q);
    }

    // Out of line: one traversal loop per query, window and mailbox kind, not copies in every caller.
    template <class Box, bool Batched, class Query>
    KDRT_NOINLINE void run_with(Query& q) const {
        Box tested;
        if constexpr (Batched) {
            const PacketShear<Real, kLeafLanes<Real>> lanes(q.ray, config_);
            auto visit = [&](const LeafRef& leaf) KDRT_HOT_INLINE_LAMBDA { return visit_leaf(q, lanes, leaf, tested); };
            traverse<Query::kOrder>(q.ray, q.window.bound(), visit);
        } else {
            auto visit = [&](const LeafRef& leaf) KDRT_HOT_INLINE_LAMBDA {
                for (std::uint32_t i = 0; i < leaf.count && !q.done(); ++i)
                    if (!tested.seen(leaf.ids[i])) q.single(leaf.ids[i]);
                return q.done_at();
            };
            traverse<Query::kOrder>(q.ray, q.window.bound(), visit);
        }
    }

    // A leaf's objects for q's ray (`lanes`: its leaf-test setup), kLeafLanes
    // triangles at a time, from the packed blocks where the leaves are packed;
    // returns what the visit returns.
    template <class Query, class Box>
    KDRT_HOT_INLINE Real visit_leaf(Query& q, const PacketShear<Real, kLeafLanes<Real>>& lanes, const LeafRef& leaf,
                                    Box& tested) const {
        if (q.done()) return q.done_at();
        auto single = [&](std::uint32_t id) KDRT_HOT_INLINE_LAMBDA { return q.single(id); };
        auto take = [&](const Hit<Real>& h) KDRT_HOT_INLINE_LAMBDA { return q.take(h); };
        if (leaf.packed) test_packed_leaf(packed_, leaf.blocks, lanes, tested, take, single);
        else test_leaf_ray(g_, lanes, leaf.ids, leaf.count, tested, take, single);
        return q.done_at();
    }

    // Leaves are tested for all of a packet's lanes at once (test_leaf_packet).
    template <class Box, int N, class Window>
    KDRT_NOINLINE void closest_packet_with(const Ray<Real>* const (&rays)[N], const Window (&windows)[N],
                                           Hit<Real> (&best)[N]) const {
        Box tested[N];
        Real bound[N];
        for (int i = 0; i < N; ++i) {
            best[i] = Hit<Real>{};
            bound[i] = windows[i].bound();
        }
        const PacketShear<Real, N> shear(rays, config_);
        auto keep = [&](int lane, const Hit<Real>& h) KDRT_HOT_INLINE_LAMBDA {
            if (h.closer_than(best[lane].t, best[lane].id)) best[lane] = h;
            return false;
        };
        auto scalar = [&](int lane, std::uint32_t id) KDRT_HOT_INLINE_LAMBDA {
            Hit<Real> h;
            return test_object(g_, *rays[lane], id, windows[lane], config_, h) && keep(lane, h);
        };
        auto take = [&](int lane, const Hit<Real>& h) KDRT_HOT_INLINE_LAMBDA {
            return windows[lane].contains(h.t) && keep(lane, h);
        };
        auto roots = [&](int lane, std::uint32_t id, Real t0, Real t1) KDRT_HOT_INLINE_LAMBDA {
            Hit<Real> h;
            h.id = static_cast<std::int32_t>(id);
            return windows[lane].first_root(t0, t1, h.t) && keep(lane, h);
        };
        auto visit = [&](std::uint32_t lanes, const std::uint32_t* ids, std::uint32_t count, Real(&done_at)[N])
                         KDRT_HOT_INLINE_LAMBDA {
                             test_leaf_packet(g_, shear, lanes, ids, count, tested, scalar, take, roots);
                             for (int i = 0; i < N; ++i) done_at[i] = best[i].t;
                         };
        traverse_stack_packet(*tree_, rays, bound, visit);
    }

    template <class Box, int N, class Window>
    KDRT_NOINLINE void any_packet_with(const Ray<Real>* const (&rays)[N], const Window (&windows)[N],
                                       bool (&hit)[N]) const {
        Box tested[N];
        Real bound[N];
        for (int i = 0; i < N; ++i) {
            hit[i] = false;
            bound[i] = windows[i].bound();
        }
        const PacketShear<Real, N> shear(rays, config_);
        auto scalar = [&](int lane, std::uint32_t id) KDRT_HOT_INLINE_LAMBDA {
            Hit<Real> h;
            return hit[lane] = test_object(g_, *rays[lane], id, windows[lane], config_, h);
        };
        auto take = [&](int lane, const Hit<Real>& h) KDRT_HOT_INLINE_LAMBDA {
            return hit[lane] = windows[lane].contains(h.t);
        };
        auto roots = [&](int lane, std::uint32_t, Real t0, Real t1) KDRT_HOT_INLINE_LAMBDA {
            Real t;
            return hit[lane] = windows[lane].first_root(t0, t1, t);
        };
        auto visit = [&](std::uint32_t lanes, const std::uint32_t* ids, std::uint32_t count, Real(&done_at)[N])
                         KDRT_HOT_INLINE_LAMBDA {
                             test_leaf_packet(g_, shear, unblocked_lanes(lanes, hit), ids, count, tested, scalar, take,
                                              roots);
                             blocked_done_at(hit, done_at);
                         };
        traverse_stack_packet(*tree_, rays, bound, visit);
    }

    // A query per packet lane, for windows[k] and rays[k].
    template <class Query, int N, class Window>
    std::array<Query, N> queries(const Ray<Real>* const (&rays)[N], const Window (&windows)[N]) const {
        return [&]<std::size_t... I>(std::index_sequence<I...>) {
            return std::array<Query, N>{Query{*this, *rays[I], windows[I]}...};
        }(std::make_index_sequence<N>{});
    }

    // A BVH's packets (traverse_bvh_packet): each lane's leaves through the
    // single-ray packed leaf test, as run_with tests them.
    template <class Queries, int N>
    KDRT_NOINLINE void bvh_packet(Queries& q, const Ray<Real>* const (&rays)[N]) const {
        using Shear = PacketShear<Real, kLeafLanes<Real>>;
        Real bound[N];
        for (int k = 0; k < N; ++k) bound[k] = q[k].window.bound();
        const auto shears = [&]<std::size_t... I>(std::index_sequence<I...>) {
            return std::array<Shear, N>{Shear(*rays[I], config_)...};
        }(std::make_index_sequence<N>{});
        auto leaf = [&](std::uint32_t child, std::uint32_t count, int k) KDRT_HOT_INLINE_LAMBDA {
            NoMailbox tested;
            return visit_leaf(q[k], shears[k], LeafRef{nullptr, 0, true, packed_.node_leaf(child, count)}, tested);
        };
        const std::span<const WideBvhNode> nodes = packed_.nodes();
        traverse_bvh_packet<Queries::value_type::kOrder>(nodes.data(), nodes.size(), rays, bound, leaf,
                                                         block_prefetch());
    }

    // For the BVH traversals: a packed leaf slot's first triangle block
    // prefetched (a leaf holding a sphere has a record instead, left alone).
    auto block_prefetch() const {
        return [this](std::uint32_t child, std::uint32_t count) KDRT_HOT_INLINE_LAMBDA {
            if (!(count & KDRT_BVH_LEAF_RECORD)) prefetch_object(packed_.blocks() + child);
        };
    }

    // The leaves a ray meets, as visit(LeafRef): front to back, a BVH's
    // children in `Order`.
    template <ChildOrder Order, class Visit>
    void traverse(const Ray<Real>& ray, Real t_max, Visit& visit) const {
        if (bvh_ && packed_.packed()) {
            const std::span<const WideBvhNode> nodes = packed_.nodes();
            auto leaf = [&](std::uint32_t child, std::uint32_t count) KDRT_HOT_INLINE_LAMBDA {
                return visit(LeafRef{nullptr, 0, true, packed_.node_leaf(child, count)});
            };
            return traverse_bvh_nodes<Order>(nodes.data(), nodes.size(), ray, t_max, leaf, block_prefetch());
        }
        // A kd-tree's packed leaf is found by where its ids start; an empty leaf has none.
        auto by_ids = [&](const std::uint32_t* ids, std::uint32_t count) KDRT_HOT_INLINE_LAMBDA {
            if (packed_.packed() && count > 0)
                return visit(LeafRef{ids, count, true,
                                     packed_.leaf(static_cast<std::uint32_t>(ids - leaf_objects_.data()))});
            return visit(LeafRef{ids, count, false, {}});
        };
        if (bvh_) return traverse_bvh<Order>(*bvh_, ray, t_max, by_ids);
        if (traversal_ == Traversal::Stack) return traverse_stack(*tree_, ray, t_max, by_ids);
        traverse_others(ray, t_max, LeafIdsVisit(by_ids));
    }

    // The kd-tree's traversals other than its default stack (the study's
    // three and the short stack) take their leaves through a FunctionRef:
    // one copy of each for all queries, windows and mailboxes. An indirect
    // call per leaf is small beside the leaf's tests.
    using LeafIdsVisit = FunctionRef<Real(const std::uint32_t*, std::uint32_t)>;
    KDRT_NOINLINE void traverse_others(const Ray<Real>& ray, Real t_max, LeafIdsVisit visit) const {
        switch (traversal_) {
            case Traversal::None: traverse_none(all_ids_, ray, t_max, visit); break;
            case Traversal::Restart: traverse_restart(*tree_, ray, t_max, visit); break;
            case Traversal::Ropes: traverse_ropes(*tree_, ray, t_max, visit); break;
            case Traversal::ShortStack: traverse_short_stack<ShortStackSize>(*tree_, ray, t_max, visit); break;
            case Traversal::Stack: KDRT_ASSERT(!"traverse() walks the stack traversal"); break;
        }
    }

    const SceneGeometry<Real>& g_;
    const KdTree* tree_;
    const WideBvh* bvh_;
    std::span<const std::uint32_t> leaf_objects_;  // the structure's (what a leaf visit's ids point into)
    Traversal traversal_;
    IntersectConfig config_;
    bool mailbox_ = false;
    bool batch_triangles_ = leaf_batching_pays(g_, config_);
    PackedLeaves<Real, kLeafLanes<Real>> packed_;  // only where the batched test runs over a tree's leaves
    std::vector<std::uint32_t> all_ids_;           // Traversal::None: every object
};

}  // namespace kdrt::detail::KDRT_CPU_ISA
