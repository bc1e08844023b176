// SceneTracer: closest-hit and shadow queries over a prepared scene through
// one of the traversals. Used by the C++ reference renderer and by the
// tests that compare traversals with brute force.
#pragma once

#include "cpu/intersect.h"
#include "cpu/mailbox.h"
#include "cpu/traverse_none.h"
#include "cpu/traverse_restart.h"
#include "cpu/traverse_ropes.h"
#include "cpu/traverse_short_stack.h"
#include "cpu/traverse_stack.h"

#include <kdrt/error.h>
#include <kdrt/render_options.h>

#include <numeric>

namespace kdrt::detail {

// ShortStackSize: entries of the short-stack traversal (tests use 1 and 2 to force restarts).
template <class Real, int ShortStackSize = KDRT_SHORT_STACK_SIZE>
class SceneTracer {
public:
    SceneTracer(const SceneGeometry<Real>& geometry, const KdTree* tree, Traversal traversal,
                IntersectConfig config = {})
        : g_(geometry), tree_(tree), traversal_(traversal), config_(config) {
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
        return mailbox_ ? closest_with<Mailbox>(ray) : closest_with<NoMailbox>(ray);
    }

    // True when an object is hit with 0 < t < t_max.
    bool occluded(const Ray<Real>& ray, Real t_max) const {
        return mailbox_ ? occluded_with<Mailbox>(ray, t_max) : occluded_with<NoMailbox>(ray, t_max);
    }

    const SceneGeometry<Real>& geometry() const { return g_; }

private:
    // Out of line: one traversal loop per query and mailbox kind, not copies in every caller.
    template <class Box>
    KDRT_NOINLINE Hit<Real> closest_with(const Ray<Real>& ray) const {
        Hit<Real> best;
        Box tested;
        auto visit = [&](const std::uint32_t* ids, std::uint32_t count) KDRT_HOT_INLINE_LAMBDA {
            for (std::uint32_t i = 0; i < count; ++i)
                if (!tested.seen(ids[i])) intersect_object(g_, ray, ids[i], best, config_);
            return best.t;
        };
        traverse(ray, std::numeric_limits<Real>::infinity(), visit);
        return best;
    }

    template <class Box>
    KDRT_NOINLINE bool occluded_with(const Ray<Real>& ray, Real t_max) const {
        bool blocked = false;
        Box tested;
        auto visit = [&](const std::uint32_t* ids, std::uint32_t count) KDRT_HOT_INLINE_LAMBDA {
            for (std::uint32_t i = 0; i < count && !blocked; ++i) {
                if (tested.seen(ids[i])) continue;
                Hit<Real> h;
                intersect_object(g_, ray, ids[i], h, config_);
                blocked = h.valid() && h.t < t_max;
            }
            return blocked ? -std::numeric_limits<Real>::infinity() : std::numeric_limits<Real>::infinity();
        };
        traverse(ray, t_max, visit);
        return blocked;
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
    std::vector<std::uint32_t> all_ids_;
};

}  // namespace kdrt::detail
