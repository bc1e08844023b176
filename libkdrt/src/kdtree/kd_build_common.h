// What both kd-tree builders share: rounding to float-representable values
// (splits and cells are stored as float, so every comparison the builders make
// must already be a comparison between floats), the root cell, and the leaf
// emission into the flat layout.
#pragma once

#include "common/float_step.h"

#include <kdrt/error.h>
#include <kdrt/kd_tree.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <mutex>
#include <optional>
#include <span>

namespace kdrt::detail {

// Largest float <= v and smallest float >= v. Callers guarantee |v| <= FLT_MAX
// (kd_root_cell checks the input), so the conversions are defined.
inline float round_down_to_float(double v) {
    float f = static_cast<float>(v);
    if (static_cast<double>(f) > v) f = float_step_down(f);
    return f;
}
inline float round_up_to_float(double v) {
    float f = static_cast<float>(v);
    if (static_cast<double>(f) < v) f = float_step_up(f);
    return f;
}

// The box rounded outward to float-representable values.
inline Aabb round_out_to_float(const Aabb& b) {
    Aabb r;
    for (int k = 0; k < 3; ++k) {
        r.lo[k] = round_down_to_float(b.lo[k]);
        r.hi[k] = round_up_to_float(b.hi[k]);
    }
    return r;
}

// Checks the input (at most 2^32-1 objects; every non-empty box finite and
// inside the float range: kdrt::Error(InvalidArgument) otherwise) and returns
// the root cell: the union of the non-empty boxes rounded outward to floats, or
// an empty Aabb when there is none. Objects with empty bounds are skipped.
Aabb kd_root_cell(const KdBuildInput& input);  // in parallel on the caller's task arena

// Appends a leaf node listing `ids` (sorted by the caller) to the tree.
void kd_emit_leaf(KdTree& tree, std::span<const std::uint32_t> ids);

// A node of a depth-first subtree built apart (in a parallel task), moved to
// where the subtree's root lands in the tree (node_offset) and its leaf lists
// (ref_offset): a leaf's list start and an inner node's above child shift.
inline KdNode kd_shifted(KdNode n, std::uint32_t node_offset, std::uint32_t ref_offset) {
    if (kd_is_leaf(n)) n.word0 += ref_offset;  // the first object's index
    else n.word1 += node_offset << 2;           // the above child's index, above the axis bits
    return n;
}

// An object's box clipped to a node's cell, rounded outward to floats once
// (every plane a builder tries is a float, so comparing floats classifies
// exactly as the stored tree will), and its id.
struct KdRef {
    // Left uninitialised, also by std::vector's resize: the builders write
    // every element they size a list for, and zeroing a big mesh's lists
    // first was one thread's serial work (and page faults) at the top levels.
    KdRef() {}
    float lo[3], hi[3];
    std::uint32_t id;
};
KdRef kd_make_ref(std::uint32_t id, const Aabb& b);  // b non-empty, inside a float cell
inline Aabb kd_ref_box(const KdRef& r) {
    Aabb b;
    for (int k = 0; k < 3; ++k) {
        b.lo[k] = r.lo[k];
        b.hi[k] = r.hi[k];
    }
    return b;
}

// The conservative bounds of the part of object `id` inside `cell`: the
// input's clip (perfect splits) when it has one, else its box cut to the cell.
Aabb kd_clip_object(const KdBuildInput& input, std::uint32_t id, const Aabb& cell);

// The same for both halves of `cell` cut at `pos` on `axis` (input.split when
// it has one, else kd_clip_object twice). Both may come out empty for a clip
// that disagrees with the bounds: the caller then falls back on the box.
void kd_split_object(const KdBuildInput& input, std::uint32_t id, const Aabb& cell, int axis, float pos,
                     Aabb& below, Aabb& above);

// What every builder shares during one build: the per-object intersection
// costs, and the guard that bounds its cost (memory budget, duplication
// allowance) and lets the caller follow and cancel it. Thread-safe.
//
// Duplication: the root holds an allowance of duplication_limit x N leaf
// references; a node may split only when its children together hold no more
// references than its allowance, which they share in proportion to their
// counts, so the leaves never list more than the root allowance. The rule is
// local to each node, so the tree does not depend on the build's scheduling.
class KdBuildContext {
public:
    KdBuildContext(const KdBuildInput& input, const KdBuildConfig& config, std::size_t objects);

    // Fixed-point intersection cost of one object (kCostScale = one node step);
    // integer sums are exact, so parallel reductions stay deterministic.
    static constexpr double kCostScale = 1024.0;
    std::uint64_t weight(std::uint32_t id) const { return id < sphere_count_ ? sphere_weight_ : triangle_weight_; }
    double traversal_cost() const { return traversal_cost_; }

    double root_allowance() const { return root_allowance_; }

    // Throws kdrt::Error(Cancelled) once the caller has cancelled.
    void check_cancelled() const;
    // Records the first failure, stops the other tasks and throws it.
    [[noreturn]] void fail(Error error);
    // Accounts bytes the build holds (tree, working lists); throws
    // kdrt::Error(ResourceLimit) when the budget would be exceeded.
    void charge(std::size_t bytes);
    void release(std::size_t bytes) { held_.fetch_sub(bytes, std::memory_order_relaxed); }
    // A leaf with `allowance` of the root's is done: reports progress now and then.
    void leaf_done(double allowance);
    // The tree bytes of one leaf listing `count` objects (its node, its parent's share, its list).
    static std::size_t leaf_bytes(std::size_t count) { return 16 + 4 * count; }

    const KdBuildInput& input;

private:
    std::uint32_t sphere_count_;
    std::uint64_t sphere_weight_, triangle_weight_;
    double traversal_cost_;
    double root_allowance_;
    std::size_t budget_;
    std::size_t objects_;
    std::atomic<std::size_t> held_{0};
    std::atomic<bool> cancelled_{false};
    mutable std::mutex failure_mutex_;
    std::optional<Error> failure_;  // the first failure, rethrown by every task; guarded by failure_mutex_
    const std::function<bool(double)>* progress_;
    std::mutex progress_mutex_;
    double done_ = 0.0, reported_ = 0.0;  // guarded by progress_mutex_
};

}  // namespace kdrt::detail
