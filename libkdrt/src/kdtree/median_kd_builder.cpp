// The spatial-median builder of the 2016 study, kept as its baseline:
//  - the split axis cycles with depth (depth % 3 first, then the next ones);
//  - the split lies halfway between the smallest lower bound m and the largest
//    upper bound M of the node's objects on that axis, s = (m + M) / 2;
//  - an object on both sides of s goes to both children;
//  - when the children would together hold more than median_max_duplication
//    (1.8) times the node's objects, the axis is abandoned for the next one in
//    the cycle; when all three are abandoned the node becomes a leaf;
//  - a node with at most one object, or at the depth limit (10 by default),
//    is a leaf.
// What we changed: m and M are taken over the objects' bounds clipped to the
// node's cell, so s always lies in the cell (the study's unclipped m and M can
// put it outside, making a child with an empty cell), and an axis whose split
// would fall on the cell's boundary is abandoned like one that duplicates too
// much. s is rounded to float before the objects are classified against it,
// so the stored tree agrees exactly with the classification. A split must also
// fit the node's duplication allowance (KdBuildContext), which bounds the
// cost of deep trees over crossing objects.
#include "kdtree/median_kd_builder.h"

#include "kdtree/kd_build_common.h"

#include <algorithm>
#include <limits>
#include <utility>
#include <vector>

namespace kdrt {

namespace {

class MedianBuild {
public:
    MedianBuild(detail::KdBuildContext& ctx, const KdBuildConfig& config, KdTree& tree)
        : ctx_(ctx), input_(ctx.input), max_duplication_(config.median_max_duplication), tree_(tree) {}

    void node(std::vector<std::uint32_t> ids, const Aabb& cell, int depth, double allowance) {
        ctx_.check_cancelled();
        if (ids.size() > 1 && depth < tree_.max_depth) {
            for (int t = 0; t < 3; ++t) {
                int axis = (depth + t) % 3;
                if (try_split(ids, cell, depth, axis, allowance)) return;
            }
        }
        ctx_.charge(detail::KdBuildContext::leaf_bytes(ids.size()));
        detail::kd_emit_leaf(tree_, ids);
        ctx_.leaf_done(allowance);
    }

private:
    // Object sides for a split at s: touching s from one side puts the object
    // on that side only; an object lying in the plane s goes below.
    static bool goes_below(const Aabb& b, int axis, double s) { return b.lo[axis] < s || b.hi[axis] <= s; }
    static bool goes_above(const Aabb& b, int axis, double s) { return b.hi[axis] > s; }

    bool try_split(const std::vector<std::uint32_t>& ids, const Aabb& cell, int depth, int axis, double allowance) {
        double m = std::numeric_limits<double>::infinity();
        double big_m = -std::numeric_limits<double>::infinity();
        for (std::uint32_t id : ids) {
            const Aabb& b = input_.bounds[id];
            m = std::min(m, std::max(b.lo[axis], cell.lo[axis]));
            big_m = std::max(big_m, std::min(b.hi[axis], cell.hi[axis]));
        }
        // m and M lie in the cell, whose faces are floats, so the rounded
        // midpoint does too; only a split strictly inside makes progress.
        const float split = static_cast<float>(0.5 * (m + big_m));
        const double s = split;
        if (!(cell.lo[axis] < s && s < cell.hi[axis])) return false;

        std::vector<std::uint32_t> below, above;
        for (std::uint32_t id : ids) {
            const Aabb& b = input_.bounds[id];
            if (goes_below(b, axis, s)) below.push_back(id);
            if (goes_above(b, axis, s)) above.push_back(id);
        }
        const std::size_t total = below.size() + above.size();
        if (static_cast<double>(total) > max_duplication_ * static_cast<double>(ids.size())) return false;
        if (static_cast<double>(total) > allowance) return false;
        const double share = allowance / static_cast<double>(total);
        const std::size_t held = total * sizeof(std::uint32_t);
        ctx_.charge(held);  // the children's lists

        Aabb below_cell = cell, above_cell = cell;
        below_cell.hi[axis] = s;
        above_cell.lo[axis] = s;
        const std::size_t index = tree_.nodes.size();
        tree_.nodes.emplace_back();
        const double below_allowance = share * static_cast<double>(below.size());
        const double above_allowance = share * static_cast<double>(above.size());
        node(std::move(below), below_cell, depth + 1, below_allowance);
        const auto above_index = static_cast<std::uint32_t>(
            std::min<std::size_t>(tree_.nodes.size(), std::numeric_limits<std::uint32_t>::max()));
        tree_.nodes[index] = kd_make_inner(axis, split, above_index);  // throws if the index does not fit
        node(std::move(above), above_cell, depth + 1, above_allowance);
        ctx_.release(held);
        return true;
    }

    detail::KdBuildContext& ctx_;
    const KdBuildInput& input_;
    double max_duplication_;
    KdTree& tree_;
};

}  // namespace

KdTree detail::build_median_kd_tree(const KdBuildInput& input, const KdBuildConfig& config) {
    KdTree tree;
    tree.bounds = detail::kd_root_cell(input);
    tree.object_count = static_cast<std::uint32_t>(input.bounds.size());
    tree.max_depth = config.max_depth > 0 ? config.max_depth : 10;

    std::vector<std::uint32_t> ids;
    for (std::uint32_t id = 0; id < tree.object_count; ++id)
        if (!input.bounds[id].empty()) ids.push_back(id);
    detail::KdBuildContext ctx(input, config, ids.size());
    MedianBuild(ctx, config, tree).node(std::move(ids), tree.bounds, 0, ctx.root_allowance());
    return tree;
}

}  // namespace kdrt
