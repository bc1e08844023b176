// SceneTracer: closest-hit and shadow queries over a prepared scene through
// one of the traversals. Used by the C++ reference renderer and by the
// tests that compare traversals with brute force.
#pragma once

#include "cpu/intersect.h"
#include "cpu/intersect_packet.h"
#include "cpu/mailbox.h"
#include "cpu/packed_leaves.h"
#include "cpu/traverse_none.h"
#include "cpu/traverse_packet.h"
#include "cpu/traverse_restart.h"
#include "cpu/traverse_ropes.h"
#include "cpu/traverse_short_stack.h"
#include "cpu/traverse_stack.h"

#include <kdrt/error.h>
#include <kdrt/commit_options.h>

#include <numeric>

namespace kdrt::detail::inline KDRT_CPU_ISA {

// ShortStackSize: entries of the short-stack traversal (tests use 1 and 2 to force restarts).
template <class Real, int ShortStackSize = KDRT_SHORT_STACK_SIZE>
class SceneTracer {
public:
    // pack_leaves: repack a small enough tree's leaves for the batched leaf
    // test (packed_leaves.h); false keeps test_leaf_ray (tests cover both).
    SceneTracer(const SceneGeometry<Real>& geometry, const KdTree* tree, Traversal traversal,
                IntersectConfig config = {}, bool pack_leaves = true)
        : g_(geometry), tree_(tree), traversal_(traversal), config_(config),
          packed_(pack_leaves && batch_triangles_ && traversal_ != Traversal::None && tree_
                      ? PackedLeaves<Real, kLeafLanes<Real>>(*tree_, g_)
                      : PackedLeaves<Real, kLeafLanes<Real>>()) {
        if (traversal_ == Traversal::None) {
            all_ids_.resize(g_.object_count());
            std::iota(all_ids_.begin(), all_ids_.end(), 0u);
        } else if (!tree_) {
            throw Error(ErrorCode::InvalidArgument, "traversal needs a kd-tree");
        } else if (traversal_ == Traversal::Ropes && !tree_->has_ropes()) {
            throw Error(ErrorCode::InvalidArgument, "the ropes traversal needs a kd-tree with ropes");
        }
    }

    Hit<Real> closest(const Ray<Real>& ray) const {
        if (batch_triangles_) return mailbox_ ? closest_with<Mailbox, true>(ray) : closest_with<NoMailbox, true>(ray);
        return mailbox_ ? closest_with<Mailbox, false>(ray) : closest_with<NoMailbox, false>(ray);
    }

    // True when an object is hit with 0 < t < t_max.
    bool occluded(const Ray<Real>& ray, Real t_max) const {
        if (batch_triangles_)
            return mailbox_ ? occluded_with<Mailbox, true>(ray, t_max) : occluded_with<NoMailbox, true>(ray, t_max);
        return mailbox_ ? occluded_with<Mailbox, false>(ray, t_max) : occluded_with<NoMailbox, false>(ray, t_max);
    }

    // The same for N rays at once: through the packet traversal when the
    // traversal is Stack and the rays are packet_compatible, else ray by ray.
    // The results are those of the single-ray queries, bit for bit.
    template <int N>
    void closest(const Ray<Real>* const (&rays)[N], Hit<Real> (&hits)[N]) const {
        if (!packs(rays)) {
            for (int i = 0; i < N; ++i) hits[i] = closest(*rays[i]);
            return;
        }
        if (mailbox_) closest_packet_with<Mailbox>(rays, hits);
        else closest_packet_with<NoMailbox>(rays, hits);
    }

    template <int N>
    void occluded(const Ray<Real>* const (&rays)[N], const Real (&t_max)[N], bool (&blocked)[N]) const {
        if (!packs(rays)) {
            for (int i = 0; i < N; ++i) blocked[i] = occluded(*rays[i], t_max[i]);
            return;
        }
        if (mailbox_) occluded_packet_with<Mailbox>(rays, t_max, blocked);
        else occluded_packet_with<NoMailbox>(rays, t_max, blocked);
    }

    // Whether closest/occluded of these rays take the packet traversal.
    template <int N>
    bool packs(const Ray<Real>* const (&rays)[N]) const {
        return traversal_ == Traversal::Stack && packet_compatible(rays);
    }

    const SceneGeometry<Real>& geometry() const { return g_; }
    bool leaves_packed() const { return packed_.packed(); }

private:
    // Out of line: one traversal loop per query and mailbox kind, not copies in every caller.
    // Batched: the leaves' triangles are tested kLeafLanes at a time (test_leaf_ray).
    template <class Box, bool Batched>
    KDRT_NOINLINE Hit<Real> closest_with(const Ray<Real>& ray) const {
        Hit<Real> best;
        Box tested;
        if constexpr (Batched) {
            const PacketShear<Real, kLeafLanes<Real>> lanes(ray, config_);
            auto take = [&](const Hit<Real>& h) KDRT_HOT_INLINE_LAMBDA {
                if (h.closer_than(best.t, best.id)) best = h;
                return false;
            };
            auto single = [&](std::uint32_t id) KDRT_HOT_INLINE_LAMBDA {
                intersect_object(g_, ray, id, best, config_);
                return false;
            };
            auto visit = [&](const std::uint32_t* ids, std::uint32_t count) KDRT_HOT_INLINE_LAMBDA {
                if (!packed_.packed()) test_leaf_ray(g_, lanes, ids, count, tested, take, single);
                else if (count > 0) test_packed_leaf(packed_, packed_leaf(ids), lanes, tested, take, single);
                return best.t;
            };
            traverse(ray, std::numeric_limits<Real>::infinity(), visit);
        } else {
            // Written out rather than through a shared `single` lambda: GCC then
            // inlined less, and lens (spheres only) rendered 3-5 % slower.
            auto visit = [&](const std::uint32_t* ids, std::uint32_t count) KDRT_HOT_INLINE_LAMBDA {
                for (std::uint32_t i = 0; i < count; ++i)
                    if (!tested.seen(ids[i])) intersect_object(g_, ray, ids[i], best, config_);
                return best.t;
            };
            traverse(ray, std::numeric_limits<Real>::infinity(), visit);
        }
        return best;
    }

    template <class Box, bool Batched>
    KDRT_NOINLINE bool occluded_with(const Ray<Real>& ray, Real t_max) const {
        bool blocked = false;
        Box tested;
        auto done_at = [&] {
            return blocked ? -std::numeric_limits<Real>::infinity() : std::numeric_limits<Real>::infinity();
        };
        if constexpr (Batched) {
            const PacketShear<Real, kLeafLanes<Real>> lanes(ray, config_);
            auto take = [&](const Hit<Real>& h) KDRT_HOT_INLINE_LAMBDA { return blocked = h.t < t_max; };
            auto single = [&](std::uint32_t id) KDRT_HOT_INLINE_LAMBDA {
                Hit<Real> h;
                intersect_object(g_, ray, id, h, config_);
                return blocked = h.valid() && h.t < t_max;
            };
            auto visit = [&](const std::uint32_t* ids, std::uint32_t count) KDRT_HOT_INLINE_LAMBDA {
                if (blocked) return done_at();
                if (!packed_.packed()) test_leaf_ray(g_, lanes, ids, count, tested, take, single);
                else if (count > 0) test_packed_leaf(packed_, packed_leaf(ids), lanes, tested, take, single);
                return done_at();
            };
            traverse(ray, t_max, visit);
        } else {
            auto visit = [&](const std::uint32_t* ids, std::uint32_t count) KDRT_HOT_INLINE_LAMBDA {
                for (std::uint32_t i = 0; i < count && !blocked; ++i) {
                    if (tested.seen(ids[i])) continue;
                    Hit<Real> h;
                    intersect_object(g_, ray, ids[i], h, config_);
                    blocked = h.valid() && h.t < t_max;
                }
                return done_at();
            };
            traverse(ray, t_max, visit);
        }
        return blocked;
    }

    // Leaves are tested for all of a packet's lanes at once (test_leaf_packet).
    template <class Box, int N>
    KDRT_NOINLINE void closest_packet_with(const Ray<Real>* const (&rays)[N], Hit<Real> (&hits)[N]) const {
        Box tested[N];
        Real t_max[N];
        for (int i = 0; i < N; ++i) {
            hits[i] = Hit<Real>{};
            t_max[i] = std::numeric_limits<Real>::infinity();
        }
        const PacketShear<Real, N> shear(rays, config_);
        auto scalar = [&](int lane, std::uint32_t id) KDRT_HOT_INLINE_LAMBDA {
            intersect_object(g_, *rays[lane], id, hits[lane], config_);
            return false;
        };
        auto take = [&](int lane, const Hit<Real>& h) KDRT_HOT_INLINE_LAMBDA {
            if (h.closer_than(hits[lane].t, hits[lane].id)) hits[lane] = h;
            return false;
        };
        auto roots = [&](int lane, std::uint32_t id, Real t0, Real t1) KDRT_HOT_INLINE_LAMBDA {
            Hit<Real> h;
            h.id = static_cast<std::int32_t>(id);
            if (nearest_root(t0, t1, h.t) && h.closer_than(hits[lane].t, hits[lane].id)) hits[lane] = h;
            return false;
        };
        auto visit = [&](std::uint32_t lanes, const std::uint32_t* ids, std::uint32_t count, Real(&done_at)[N])
                         KDRT_HOT_INLINE_LAMBDA {
                             test_leaf_packet(g_, shear, lanes, ids, count, tested, scalar, take, roots);
                             for (int i = 0; i < N; ++i) done_at[i] = hits[i].t;
                         };
        traverse_stack_packet(*tree_, rays, t_max, visit);
    }

    template <class Box, int N>
    KDRT_NOINLINE void occluded_packet_with(const Ray<Real>* const (&rays)[N], const Real (&t_max)[N],
                                            bool (&blocked)[N]) const {
        Box tested[N];
        for (int i = 0; i < N; ++i) blocked[i] = false;
        const PacketShear<Real, N> shear(rays, config_);
        auto scalar = [&](int lane, std::uint32_t id) KDRT_HOT_INLINE_LAMBDA {
            Hit<Real> h;
            intersect_object(g_, *rays[lane], id, h, config_);
            return blocked[lane] = h.valid() && h.t < t_max[lane];
        };
        auto take = [&](int lane, const Hit<Real>& h) KDRT_HOT_INLINE_LAMBDA {
            return blocked[lane] = h.t < t_max[lane];
        };
        auto roots = [&](int lane, std::uint32_t, Real t0, Real t1) KDRT_HOT_INLINE_LAMBDA {
            Real t;
            return blocked[lane] = nearest_root(t0, t1, t) && t < t_max[lane];
        };
        auto visit = [&](std::uint32_t lanes, const std::uint32_t* ids, std::uint32_t count, Real(&done_at)[N])
                         KDRT_HOT_INLINE_LAMBDA {
                             test_leaf_packet(g_, shear, unblocked_lanes(lanes, blocked), ids, count, tested,
                                              scalar, take, roots);
                             blocked_done_at(blocked, done_at);
                         };
        traverse_stack_packet(*tree_, rays, t_max, visit);
    }

    // The packed leaf whose objects a traversal's visit got (a tree's leaf, not traverse_none's list).
    const typename PackedLeaves<Real, kLeafLanes<Real>>::Leaf& packed_leaf(const std::uint32_t* ids) const {
        return packed_.leaf(static_cast<std::uint32_t>(ids - tree_->leaf_objects.data()));
    }

    template <class Visit>
    void traverse(const Ray<Real>& ray, Real t_max, Visit& visit) const {
        switch (traversal_) {
            case Traversal::None: traverse_none(all_ids_, ray, t_max, visit); break;
            case Traversal::Restart: traverse_restart(*tree_, ray, t_max, visit); break;
            case Traversal::Ropes: traverse_ropes(*tree_, ray, t_max, visit); break;
            case Traversal::Stack: traverse_stack(*tree_, ray, t_max, visit); break;
            case Traversal::ShortStack: traverse_short_stack<ShortStackSize>(*tree_, ray, t_max, visit); break;
        }
    }

    const SceneGeometry<Real>& g_;
    const KdTree* tree_;
    Traversal traversal_;
    IntersectConfig config_;
    bool mailbox_ = tree_duplicates_objects(traversal_ == Traversal::None ? nullptr : tree_);
    bool batch_triangles_ = leaf_batching_pays(g_, config_);
    PackedLeaves<Real, kLeafLanes<Real>> packed_;  // only where the batched test runs over a tree's leaves
    std::vector<std::uint32_t> all_ids_;
};

}  // namespace kdrt::detail::KDRT_CPU_ISA
