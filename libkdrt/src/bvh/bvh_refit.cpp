// Refit: first every object's box made and checked, in floats, in one pass
// (so that a refused refit leaves the BVH as it was), then the boxes
// recomputed from the leaves up, a subtree per task below the top levels
// (unions of floats: exact, whatever the order).
#include "bvh/bvh_refit.h"

#include "bvh/bvh_boxes.h"
#include "bvh/bvh_stats.h"
#include "common/parallel_chunks.h"
#include "common/tsan_fork_join.h"

#include <kdrt/error.h>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace kdrt {

namespace {

// Levels whose inner children are refit as tasks of their own: 8^2 tasks at the third level.
constexpr int kParallelLevels = 2;

// Storage for every object's box, left uninitialised: the checking pass's
// tasks construct each box, so no serial clearing pass precedes them.
class ObjectBoxes {
public:
    explicit ObjectBoxes(std::size_t n) : n_(n), boxes_(std::allocator<detail::FloatBox>().allocate(n)) {}
    ~ObjectBoxes() { std::allocator<detail::FloatBox>().deallocate(boxes_, n_); }
    ObjectBoxes(const ObjectBoxes&) = delete;
    ObjectBoxes& operator=(const ObjectBoxes&) = delete;

    void set(std::size_t id, const detail::FloatBox& box) { std::construct_at(boxes_ + id, box); }
    // Once every box is set.
    std::span<const detail::FloatBox> all() const { return {boxes_, n_}; }

private:
    std::size_t n_;
    detail::FloatBox* boxes_;
    static_assert(std::is_trivially_destructible_v<detail::FloatBox>, "the storage is freed without destroying boxes");
};

// Every object's box, rounded out to floats as a build rounds it, in one
// pass that also checks them: throws for a box the BVH cannot hold, or for
// an object without a leaf that gained a box. Nothing of the BVH is changed yet.
void checked_float_boxes(const std::vector<std::uint32_t>& leaf_objects, std::uint32_t object_count,
                         const BvhObjectBox& box_of, ObjectBoxes& boxes) {
    const std::size_t first_bad = detail::first_index_where(object_count, [&](std::size_t id) {
        const Aabb b = box_of(static_cast<std::uint32_t>(id));
        const detail::BoxUse use = detail::box_use(b);
        boxes.set(id, use == detail::BoxUse::Held ? detail::round_out(b) : detail::FloatBox{});
        return use == detail::BoxUse::Refused;
    });
    if (first_bad < object_count)
        throw Error(ErrorCode::InvalidArgument, "BVH refit: object " + std::to_string(first_bad) +
                                                    " has bounds that are NaN, infinite or beyond the float range");
    if (leaf_objects.size() == object_count) return;  // every object has a leaf
    std::vector<std::uint8_t> listed(object_count, 0);
    detail::for_each_chunk(leaf_objects.size(), [&](std::size_t, std::size_t b, std::size_t e) {
        for (std::size_t j = b; j < e; ++j) listed[leaf_objects[j]] = 1;  // each id once: no two tasks write one byte
    });
    const std::span<const detail::FloatBox> all = boxes.all();
    const std::size_t gained =
        detail::first_index_where(object_count, [&](std::size_t id) { return !listed[id] && !all[id].empty(); });
    if (gained < object_count)
        throw Error(ErrorCode::InvalidArgument, "BVH refit: object " + std::to_string(gained) +
                                                    " has a box now but none when the BVH was built, so no leaf: "
                                                    "rebuild the BVH");
}

template <int N>
class Refit {
public:
    Refit(WideBvhN<N>& bvh, std::span<const detail::FloatBox> boxes) : bvh_(bvh), boxes_(boxes) {}

    // Refits node `n`'s slots; returns their union.
    detail::FloatBox node(std::uint32_t n, int level) {
        WideBvhNodeN<N>& node = bvh_.nodes[n];
        detail::FloatBox boxes[N];
        const int used = node.used_slots();
        auto slot = [&](int i) {
            if (node.is_leaf(i)) {
                const std::uint32_t* ids = bvh_.leaf_objects.data() + node.child[i];
                for (std::uint32_t k = 0; k < node.leaf_count(i); ++k) boxes[i].extend(boxes_[ids[k]]);
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
    std::span<const detail::FloatBox> boxes_;  // by object id; empty ones extend nothing
};

}  // namespace

template <int N>
BvhRefitResult refit_bvh(WideBvhN<N>& bvh, std::span<const Aabb> object_bounds, int threads) {
    if (object_bounds.size() != bvh.object_count)
        throw Error(ErrorCode::InvalidArgument, "BVH refit: " + std::to_string(object_bounds.size()) +
                                                    " object boxes for a BVH over " + std::to_string(bvh.object_count));
    return refit_bvh(bvh, BvhObjectBox([object_bounds](std::uint32_t id) { return object_bounds[id]; }), threads);
}

template <int N>
BvhRefitResult refit_bvh(WideBvhN<N>& bvh, const BvhObjectBox& box_of, int threads) {
    if (threads < 0 || threads > 1024)
        throw Error(ErrorCode::InvalidArgument,
                    "BVH refit: threads must be in [0, 1024] (0: all cores), got " + std::to_string(threads));
    if (bvh.nodes.empty()) throw Error(ErrorCode::InvalidArgument, "BVH refit: the BVH has no nodes");
    BvhRefitResult result;
    tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
    auto run = [&] {
        ObjectBoxes boxes(bvh.object_count);
        checked_float_boxes(bvh.leaf_objects, bvh.object_count, box_of, boxes);
        const detail::FloatBox all = Refit<N>(bvh, boxes.all()).node(0, 0);
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
template BvhRefitResult refit_bvh<4>(WideBvhN<4>&, const BvhObjectBox&, int);
template BvhRefitResult refit_bvh<8>(WideBvhN<8>&, const BvhObjectBox&, int);

}  // namespace kdrt
