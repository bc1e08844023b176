// Refit: the boxes recomputed from the leaves up, in place, a subtree per
// task below the top levels (unions of floats: exact, whatever the order).
// Each leaf asks for its objects' boxes as the pass reaches it; the nodes'
// old boxes are kept aside first, so that a refused refit puts them back.
#include "bvh/bvh_refit.h"

#include "bvh/bvh_boxes.h"
#include "bvh/bvh_stats.h"
#include "common/parallel_chunks.h"
#include "common/tsan_fork_join.h"

#include <kdrt/error.h>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <cstring>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace kdrt {

namespace {

// Levels whose inner children are refit as tasks of their own: 8^2 tasks at the third level.
constexpr int kParallelLevels = 2;
// Nodes whose boxes one task copies aside or back.
constexpr std::size_t kNodesPerCopy = 1024;

// The nodes' boxes as they were, left uninitialised before the copy (its
// tasks write every byte), put back when the refit refuses an object.
template <int N>
class SavedBoxes {
public:
    using Boxes = decltype(WideBvhNodeN<N>::box);

    explicit SavedBoxes(const std::vector<WideBvhNodeN<N>>& nodes)
        : boxes_(std::make_unique_for_overwrite<Boxes[]>(nodes.size())) {
        detail::for_each_chunk(
            nodes.size(),
            [&](std::size_t, std::size_t b, std::size_t e) {
                for (std::size_t i = b; i < e; ++i) std::memcpy(boxes_[i], nodes[i].box, sizeof(Boxes));
            },
            kNodesPerCopy);
    }
    void restore(std::vector<WideBvhNodeN<N>>& nodes) const {
        detail::for_each_chunk(
            nodes.size(),
            [&](std::size_t, std::size_t b, std::size_t e) {
                for (std::size_t i = b; i < e; ++i) std::memcpy(nodes[i].box, boxes_[i], sizeof(Boxes));
            },
            kNodesPerCopy);
    }

private:
    std::unique_ptr<Boxes[]> boxes_;
};

// The smallest id among objects offered from several tasks; none: kNone.
class SmallestId {
public:
    static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
    void offer(std::uint32_t id) {
        std::uint32_t seen = id_.load(std::memory_order_relaxed);
        while (id < seen && !id_.compare_exchange_weak(seen, id, std::memory_order_relaxed)) {
        }
    }
    std::uint32_t get() const { return id_.load(std::memory_order_relaxed); }

private:
    std::atomic<std::uint32_t> id_{kNone};
};

// Objects ids' box in floats (the union of those a build takes), asked of
// `leaf_box`; the ids of objects whose box the BVH cannot hold go to `refused`.
detail::FloatBox leaf_float_box(const BvhLeafBox& leaf_box, std::span<const std::uint32_t> ids, SmallestId& refused) {
    const Aabb box = leaf_box(ids);
    switch (detail::box_use(box)) {
        case detail::BoxUse::Held: return detail::round_out(box);
        case detail::BoxUse::Empty: return {};
        case detail::BoxUse::Refused: break;
    }
    // Which of them: one at a time (a union refused though no member alone is blames the first).
    bool named = false;
    for (const std::uint32_t& id : ids)
        if (detail::box_use(leaf_box({&id, 1})) == detail::BoxUse::Refused) {
            refused.offer(id);
            named = true;
        }
    if (!named) refused.offer(ids.front());
    return {};
}

// Objects without a leaf (no box when built): those that now have one go to
// `gained`, those with a refused box to `refused`.
void check_unlisted(const std::vector<std::uint32_t>& leaf_objects, std::uint32_t object_count,
                    const BvhLeafBox& leaf_box, SmallestId& refused, SmallestId& gained) {
    if (leaf_objects.size() == object_count) return;  // every object has a leaf
    std::vector<std::uint8_t> listed(object_count, 0);
    detail::for_each_chunk(leaf_objects.size(), [&](std::size_t, std::size_t b, std::size_t e) {
        for (std::size_t j = b; j < e; ++j) listed[leaf_objects[j]] = 1;  // each id once: no two tasks write one byte
    });
    detail::for_each_chunk(object_count, [&](std::size_t, std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            const std::uint32_t id = static_cast<std::uint32_t>(i);
            if (!listed[id] && !leaf_float_box(leaf_box, {&id, 1}, refused).empty()) gained.offer(id);
        }
    });
}

template <int N>
class Refit {
public:
    Refit(WideBvhN<N>& bvh, const BvhLeafBox& leaf_box, SmallestId& refused)
        : bvh_(bvh), leaf_box_(leaf_box), refused_(refused) {}

    // Refits node `n`'s slots; returns their union.
    detail::FloatBox node(std::uint32_t n, int level) {
        WideBvhNodeN<N>& node = bvh_.nodes[n];
        detail::FloatBox boxes[N];
        const int used = node.used_slots();
        auto slot = [&](int i) {
            if (node.is_leaf(i)) {
                const std::uint32_t* ids = bvh_.leaf_objects.data() + node.child[i];
                boxes[i] = leaf_float_box(leaf_box_, {ids, node.leaf_count(i)}, refused_);
            } else {
                boxes[i] = this->node(node.child[i], level + 1);
            }
        };
        if (level < kParallelLevels) {
            detail::TsanForkJoin tsan;
            tbb::parallel_for(0, used, tsan.task(slot));
        } else {
            for (int i = 0; i < used; ++i) slot(i);
        }
        detail::FloatBox all;
        for (int i = 0; i < used; ++i) {
            node.set_box(i, boxes[i].lo, boxes[i].hi);
            all.extend(boxes[i]);
        }
        return all;
    }

private:
    WideBvhN<N>& bvh_;
    const BvhLeafBox& leaf_box_;
    SmallestId& refused_;
};

}  // namespace

template <int N>
BvhRefitResult refit_bvh(WideBvhN<N>& bvh, std::span<const Aabb> object_bounds, int threads) {
    if (object_bounds.size() != bvh.object_count)
        throw Error(ErrorCode::InvalidArgument, "BVH refit: " + std::to_string(object_bounds.size()) +
                                                    " object boxes for a BVH over " + std::to_string(bvh.object_count));
    auto leaf_box = [object_bounds](std::span<const std::uint32_t> ids) {
        Aabb box;
        for (std::uint32_t id : ids) switch (detail::box_use(object_bounds[id])) {
                case detail::BoxUse::Held: box.extend(object_bounds[id]); break;
                case detail::BoxUse::Empty: break;
                case detail::BoxUse::Refused: return object_bounds[id];
            }
        return box;
    };
    return refit_bvh(bvh, BvhLeafBox(leaf_box), threads);
}

template <int N>
BvhRefitResult refit_bvh(WideBvhN<N>& bvh, const BvhLeafBox& leaf_box, int threads) {
    if (threads < 0 || threads > 1024)
        throw Error(ErrorCode::InvalidArgument,
                    "BVH refit: threads must be in [0, 1024] (0: all cores), got " + std::to_string(threads));
    if (bvh.nodes.empty()) throw Error(ErrorCode::InvalidArgument, "BVH refit: the BVH has no nodes");
    BvhRefitResult result;
    tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
    auto run = [&] {
        SmallestId refused, gained;
        check_unlisted(bvh.leaf_objects, bvh.object_count, leaf_box, refused, gained);
        const SavedBoxes<N> saved(bvh.nodes);
        detail::FloatBox all;
        try {
            all = Refit<N>(bvh, leaf_box, refused).node(0, 0);
        } catch (...) {  // from leaf_box
            saved.restore(bvh.nodes);
            throw;
        }
        // A refused box is named before a gained one.
        std::string fault;
        if (refused.get() != SmallestId::kNone)
            fault = "BVH refit: object " + std::to_string(refused.get()) +
                    " has bounds that are NaN, infinite or beyond the float range";
        else if (gained.get() != SmallestId::kNone)
            fault = "BVH refit: object " + std::to_string(gained.get()) +
                    " has a box now but none when the BVH was built, so no leaf: rebuild the BVH";
        if (!fault.empty()) {
            saved.restore(bvh.nodes);
            throw Error(ErrorCode::InvalidArgument, fault);
        }
        bvh.bounds = all.to_aabb();
        result.sah_cost = bvh_sah_cost(bvh);
    };
    {
        detail::TsanForkJoin tsan;
        arena.execute(tsan.task(run));
    }
    result.build_sah_cost = bvh.build_sah_cost;
    return result;
}

template BvhRefitResult refit_bvh<4>(WideBvhN<4>&, std::span<const Aabb>, int);
template BvhRefitResult refit_bvh<8>(WideBvhN<8>&, std::span<const Aabb>, int);
template BvhRefitResult refit_bvh<4>(WideBvhN<4>&, const BvhLeafBox&, int);
template BvhRefitResult refit_bvh<8>(WideBvhN<8>&, const BvhLeafBox&, int);

}  // namespace kdrt
