#include "kdtree/kd_build_common.h"

#include "common/parallel_chunks.h"

#include <kdrt/error.h>

#include <cstdio>
#include <limits>
#include <string>
#include <vector>

namespace kdrt::detail {

Aabb kd_root_cell(const KdBuildInput& input) {
    if (input.bounds.size() > std::numeric_limits<std::uint32_t>::max())
        throw Error(ErrorCode::Unsupported, "kd-tree input: " + std::to_string(input.bounds.size()) +
                                                " objects exceed the 32-bit object id range");
    constexpr double kFloatMax = std::numeric_limits<float>::max();
    // In parallel chunks (on the caller's task arena): each chunk's box, or
    // its first object out of range, which is then reported in id order.
    const std::size_t count = input.bounds.size();
    std::vector<Aabb> boxes(chunk_count(count));
    std::vector<std::size_t> first_bad(chunk_count(count), count);
    for_each_chunk(count, [&](std::size_t c, std::size_t begin, std::size_t end) {
        Aabb box;
        for (std::size_t id = begin; id < end; ++id) {
            const Aabb& b = input.bounds[id];
            if (b.empty()) continue;
            for (int k = 0; k < 3; ++k)
                if (!(b.lo[k] >= -kFloatMax && b.hi[k] <= kFloatMax)) {
                    first_bad[c] = id;
                    return;
                }
            box.extend(b);
        }
        boxes[c] = box;
    });
    Aabb root;
    for (std::size_t c = 0; c < boxes.size(); ++c) {
        if (first_bad[c] < count)
            throw Error(ErrorCode::InvalidArgument, "kd-tree input: object " + std::to_string(first_bad[c]) +
                                                        " has bounds that are not finite or exceed the float range");
        root.extend(boxes[c]);
    }
    return root.empty() ? Aabb{} : round_out_to_float(root);
}

void kd_emit_leaf(KdTree& tree, std::span<const std::uint32_t> ids) {
    auto count = static_cast<std::uint32_t>(ids.size());
    if (tree.leaf_objects.size() + ids.size() > std::numeric_limits<std::uint32_t>::max())
        throw Error(ErrorCode::Unsupported, "kd-tree too large: more than 2^32-1 leaf references");
    tree.nodes.push_back(kd_make_leaf(static_cast<std::uint32_t>(tree.leaf_objects.size()), count));
    tree.leaf_objects.insert(tree.leaf_objects.end(), ids.begin(), ids.end());
}

KdRef kd_make_ref(std::uint32_t id, const Aabb& b) {
    KdRef r;
    for (int k = 0; k < 3; ++k) {
        r.lo[k] = round_down_to_float(b.lo[k]) + 0.0f;  // + 0.0f turns -0 into +0
        r.hi[k] = round_up_to_float(b.hi[k]) + 0.0f;
    }
    r.id = id;
    return r;
}

Aabb kd_clip_object(const KdBuildInput& input, std::uint32_t id, const Aabb& cell) {
    const Aabb b = input.clip ? input.clip(id, cell).intersect(input.bounds[id]) : input.bounds[id];
    return b.intersect(cell);
}

void kd_split_object(const KdBuildInput& input, std::uint32_t id, const Aabb& cell, int axis, float pos,
                     Aabb& below, Aabb& above) {
    Aabb below_cell = cell, above_cell = cell;
    below_cell.hi[axis] = pos;
    above_cell.lo[axis] = pos;
    if (input.split) {
        input.split(id, cell, axis, pos, below, above);
        below = below.intersect(input.bounds[id]).intersect(below_cell);
        above = above.intersect(input.bounds[id]).intersect(above_cell);
    } else {
        below = kd_clip_object(input, id, below_cell);
        above = kd_clip_object(input, id, above_cell);
    }
}

KdBuildContext::KdBuildContext(const KdBuildInput& in, const KdBuildConfig& config, std::size_t objects)
    : input(in),
      sphere_count_(in.sphere_count),
      sphere_weight_(static_cast<std::uint64_t>(std::llround(config.sphere_intersection_cost * kCostScale))),
      triangle_weight_(static_cast<std::uint64_t>(std::llround(config.intersection_cost * kCostScale))),
      traversal_cost_(config.traversal_cost * kCostScale),
      root_allowance_(config.duplication_limit * static_cast<double>(std::max<std::size_t>(objects, 1))),
      budget_(config.effective_memory_budget()),
      objects_(objects),
      progress_(config.progress ? &config.progress : nullptr) {
    sphere_weight_ = std::max<std::uint64_t>(sphere_weight_, 1);
    triangle_weight_ = std::max<std::uint64_t>(triangle_weight_, 1);
}

void KdBuildContext::check_cancelled() const {
    if (!cancelled_.load(std::memory_order_relaxed)) return;
    // Every task stops with the first failure's error, whichever task TBB
    // happens to propagate: a budget overrun stays a budget overrun.
    std::lock_guard lock(failure_mutex_);
    throw failure_ ? *failure_ : Error(ErrorCode::Cancelled, "kd-tree build cancelled");
}

void KdBuildContext::fail(Error error) {
    std::unique_lock lock(failure_mutex_);
    if (!failure_) failure_ = std::move(error);
    Error first = *failure_;
    lock.unlock();
    cancelled_.store(true, std::memory_order_relaxed);  // stop the other tasks early
    throw first;
}

void KdBuildContext::charge(std::size_t bytes) {
    const std::size_t now = held_.fetch_add(bytes, std::memory_order_relaxed) + bytes;
    if (now > budget_) {
        char msg[256];
        std::snprintf(msg, sizeof msg,
                      "kd-tree build of %zu objects exceeds its memory budget of %.0f MiB (KdBuildConfig::memory_budget); "
                      "the geometry makes the tree explode: lower max_depth or duplication_limit, or raise the budget",
                      objects_, static_cast<double>(budget_) / (1024.0 * 1024.0));
        fail(Error(ErrorCode::ResourceLimit, msg));
    }
}

void KdBuildContext::leaf_done(double allowance) {
    check_cancelled();
    if (!progress_) return;
    std::lock_guard lock(progress_mutex_);
    done_ += allowance / root_allowance_;
    if (done_ - reported_ < 0.01) return;
    reported_ = done_;
    if (!(*progress_)(std::min(done_, 1.0))) fail(Error(ErrorCode::Cancelled, "kd-tree build cancelled"));
}

}  // namespace kdrt::detail
