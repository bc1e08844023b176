// Refit: first every input checked (so that a refused refit leaves the BVH as
// it was), then the boxes recomputed from the leaves up, a subtree per task
// below the top levels (unions of floats: exact, whatever the order).
#include "bvh/bvh_refit.h"

#include "bvh/bvh_boxes.h"
#include "bvh/bvh_stats.h"
#include "common/parallel_chunks.h"
#include "common/tsan_fork_join.h"

#include <kdrt/error.h>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <string>
#include <vector>

namespace kdrt {

namespace {

// Levels whose inner children are refit as tasks of their own: 8^2 tasks at the third level.
constexpr int kParallelLevels = 2;

void check_input(const std::vector<std::uint32_t>& leaf_objects, std::uint32_t object_count,
                 std::span<const Aabb> bounds) {
    if (bounds.size() != object_count)
        throw Error(ErrorCode::InvalidArgument, "BVH refit: " + std::to_string(bounds.size()) +
                                                    " object boxes for a BVH over " + std::to_string(object_count));
    const std::size_t first_bad = detail::first_index_where(
        bounds.size(), [&](std::size_t id) { return detail::box_use(bounds[id]) == detail::BoxUse::Refused; });
    if (first_bad < bounds.size())
        throw Error(ErrorCode::InvalidArgument, "BVH refit: object " + std::to_string(first_bad) +
                                                    " has bounds that are NaN, infinite or beyond the float range");
    if (leaf_objects.size() == object_count) return;  // every object has a leaf
    std::vector<std::uint8_t> listed(object_count, 0);
    detail::for_each_chunk(leaf_objects.size(), [&](std::size_t, std::size_t b, std::size_t e) {
        for (std::size_t j = b; j < e; ++j) listed[leaf_objects[j]] = 1;  // each id once: no two tasks write one byte
    });
    const std::size_t gained =
        detail::first_index_where(bounds.size(), [&](std::size_t id) { return !listed[id] && !bounds[id].empty(); });
    if (gained < bounds.size())
        throw Error(ErrorCode::InvalidArgument, "BVH refit: object " + std::to_string(gained) +
                                                    " has a box now but none when the BVH was built, so no leaf: "
                                                    "rebuild the BVH");
}

template <int N>
class Refit {
public:
    Refit(WideBvhN<N>& bvh, std::span<const Aabb> bounds) : bvh_(bvh), bounds_(bounds) {}

    // Refits node `n`'s slots; returns their union.
    detail::FloatBox node(std::uint32_t n, int level) {
        WideBvhNodeN<N>& node = bvh_.nodes[n];
        detail::FloatBox boxes[N];
        const int used = node.used_slots();
        // The objects' boxes lie scattered in memory: asked for all at once,
        // their cache misses overlap.
        for (int i = 0; i < used; ++i) {
            if (!node.is_leaf(i)) continue;
            const std::uint32_t* ids = bvh_.leaf_objects.data() + node.child[i];
            for (std::uint32_t k = 0; k < node.leaf_count(i); ++k) {
                const char* box = reinterpret_cast<const char*>(&bounds_[ids[k]]);
                __builtin_prefetch(box);
                __builtin_prefetch(box + sizeof(Aabb) - 1);
            }
        }
        auto slot = [&](int i) {
            if (node.is_leaf(i)) {
                const std::uint32_t* ids = bvh_.leaf_objects.data() + node.child[i];
                for (std::uint32_t k = 0; k < node.leaf_count(i); ++k) {
                    const Aabb& b = bounds_[ids[k]];
                    if (!b.empty()) boxes[i].extend(detail::round_out(b));
                }
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
    std::span<const Aabb> bounds_;
};

}  // namespace

template <int N>
BvhRefitResult refit_bvh(WideBvhN<N>& bvh, std::span<const Aabb> object_bounds, int threads) {
    if (threads < 0 || threads > 1024)
        throw Error(ErrorCode::InvalidArgument,
                    "BVH refit: threads must be in [0, 1024] (0: all cores), got " + std::to_string(threads));
    if (bvh.nodes.empty()) throw Error(ErrorCode::InvalidArgument, "BVH refit: the BVH has no nodes");
    BvhRefitResult result;
    tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
    auto run = [&] {
        check_input(bvh.leaf_objects, bvh.object_count, object_bounds);
        const detail::FloatBox all = Refit<N>(bvh, object_bounds).node(0, 0);
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

}  // namespace kdrt
