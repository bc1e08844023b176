// Structural check of a kd-tree: everything a traversal (CPU or OpenCL, with
// its fixed-size stack bounded by max_depth) relies on, so a tree read from a
// file can never make one index out of bounds or loop. Throws
// kdrt::Error(CorruptTree) naming the first violation.
#include "kdtree/check_kd_tree_covers.h"

#include <kdrt/error.h>
#include <kdrt/kd_tree.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace kdrt {

namespace {

template <class... Args>
[[noreturn]] void corrupt(const Args&... parts) {
    std::ostringstream s;
    s << "kd-tree ";
    (s << ... << parts);
    throw Error(ErrorCode::CorruptTree, s.str());
}

const char* const kFaceNames[6] = {"-x", "+x", "-y", "+y", "-z", "+z"};
const char kAxisNames[3] = {'x', 'y', 'z'};

// Finite and exactly representable as a float (cells are stored as floats).
bool is_float_value(double v) {
    return std::abs(v) <= std::numeric_limits<float>::max() && static_cast<double>(static_cast<float>(v)) == v;
}

void check_bounds(const KdTree& tree) {
    const Aabb& b = tree.bounds;
    if (b == Aabb{}) {  // the empty box is the bounds of a tree over no objects
        const KdNode& root = tree.nodes[0];
        if (tree.nodes.size() != 1 || !kd_is_leaf(root) || (root.word1 >> 2) != 0)
            corrupt("bounds are empty but the tree is not a single empty leaf");
        return;
    }
    for (int k = 0; k < 3; ++k) {
        if (!is_float_value(b.lo[k]) || !is_float_value(b.hi[k]))
            corrupt("bounds on ", kAxisNames[k], " [", b.lo[k], ", ", b.hi[k],
                    "] are not finite float-representable values");
        if (b.lo[k] > b.hi[k]) corrupt("bounds on ", kAxisNames[k], " are inverted: [", b.lo[k], ", ", b.hi[k], "]");
    }
}

using FloatCell = std::array<float, 6>;  // lo xyz, hi xyz

void check_ropes(const KdTree& tree, const std::vector<FloatCell>& cells) {
    if (tree.ropes.size() != tree.nodes.size())
        corrupt("has ", tree.ropes.size(), " rope entries for ", tree.nodes.size(), " nodes");
    const FloatCell& root = cells[0];
    for (std::size_t i = 0; i < tree.nodes.size(); ++i) {
        if (!kd_is_leaf(tree.nodes[i])) continue;
        const KdLeafRopes& r = tree.ropes[i];
        const FloatCell& c = cells[i];
        for (int k = 0; k < 3; ++k)
            if (!(r.box_min[k] == c[k] && r.box_max[k] == c[3 + k]))
                corrupt("leaf node ", i, ": rope box differs from the leaf's cell on ", kAxisNames[k]);
        for (int face = 0; face < 6; ++face) {
            const int a = face / 2;
            const bool positive = (face & 1) != 0;
            const bool boundary = positive ? c[3 + a] == root[3 + a] : c[a] == root[a];
            const std::uint32_t t = r.rope[face];
            if (boundary) {
                if (t != KDRT_ROPE_NONE)
                    corrupt("leaf node ", i, ": rope ", kFaceNames[face], " is ", t,
                            " but the face is on the scene boundary");
                continue;
            }
            if (t == KDRT_ROPE_NONE)
                corrupt("leaf node ", i, ": face ", kFaceNames[face], " is inside the scene but has no rope");
            if (t >= tree.nodes.size())
                corrupt("leaf node ", i, ": rope ", kFaceNames[face], " = ", t, " is out of range (",
                        tree.nodes.size(), " nodes)");
            // The target must lie beyond the face and cover all of it.
            const FloatCell& tc = cells[t];
            bool ok = positive ? tc[a] == c[3 + a] : tc[3 + a] == c[a];
            for (int b = 0; b < 3; ++b)
                if (b != a) ok = ok && tc[b] <= c[b] && c[3 + b] <= tc[3 + b];
            if (!ok)
                corrupt("leaf node ", i, ": rope ", kFaceNames[face], " leads to node ", t,
                        " whose cell does not cover the face from outside");
        }
    }
}

}  // namespace

void check_kd_tree(const KdTree& tree) {
    const std::size_t node_count = tree.nodes.size();
    if (node_count == 0) corrupt("has no nodes");
    if (node_count > std::size_t{KDRT_MAX_NODE_INDEX} + 1)
        corrupt("has ", node_count, " nodes, more than the layout can index");
    if (tree.max_depth < 0 || tree.max_depth > KDRT_MAX_TREE_DEPTH) corrupt("max_depth ", tree.max_depth, " is outside [0, 64]");
    check_bounds(tree);

    // One pass over the references first: a leaf's own ids are then only
    // looked at again to name the leaf of a bad one.
    std::uint32_t largest_id = 0;
    for (std::uint32_t id : tree.leaf_objects) largest_id = std::max(largest_id, id);
    const bool ids_in_range = tree.leaf_objects.empty() || largest_id < tree.object_count;

    const bool ropes = !tree.ropes.empty();
    std::vector<FloatCell> cells(ropes ? node_count : 0);
    std::vector<std::uint8_t> reached(node_count, 0);
    // Cells in float: the bounds are float values (check_bounds) and so are
    // the splits, so every cell is exact, at half the size of an Aabb.
    struct Item {
        std::uint32_t node;
        int depth;
        FloatCell cell;
    };
    FloatCell root{};
    for (int k = 0; k < 3; ++k) {
        root[k] = static_cast<float>(tree.bounds.lo[k]);
        root[3 + k] = static_cast<float>(tree.bounds.hi[k]);
    }
    // Depth-first with an explicit stack of above children, which the
    // max_depth check keeps short; the walk goes down each below chain in place.
    // A child's cell is narrowed where it lies (in the stack, or in `item`),
    // not in a copy that is read back at once: a store the next load only
    // partly covers stalls that load.
    std::vector<Item> stack{{0, 0, root}};
    stack.reserve(KDRT_MAX_TREE_DEPTH + 2);
    while (!stack.empty()) {
        Item item = stack.back();
        stack.pop_back();
        for (;;) {
            const std::uint32_t i = item.node;
            if (reached[i]) corrupt("node ", i, " is reached twice from the root");
            reached[i] = 1;
            if (item.depth > tree.max_depth)
                corrupt("node ", i, " is at depth ", item.depth, ", deeper than the tree's max_depth ", tree.max_depth);
            if (ropes) cells[i] = item.cell;

            const KdNode& n = tree.nodes[i];
            if (kd_is_leaf(n)) {
                const std::uint64_t first = kd_leaf_first(n), end = first + kd_leaf_count(n);
                if (end > tree.leaf_objects.size())
                    corrupt("leaf node ", i, ": objects [", first, ", ", end, ") exceed the ",
                            tree.leaf_objects.size(), " leaf object entries");
                if (!ids_in_range)
                    for (std::uint64_t j = first; j < end; ++j)
                        if (tree.leaf_objects[j] >= tree.object_count)
                            corrupt("leaf node ", i, ": object id ", tree.leaf_objects[j],
                                    " is not below the object count ", tree.object_count);
                break;
            }

            const int axis = kd_axis(n);
            const float split = kd_split(n);
            if (!std::isfinite(split)) corrupt("node ", i, ": split is not finite");
            if (split < item.cell[axis] || split > item.cell[3 + axis])
                corrupt("node ", i, ": split ", split, " on ", kAxisNames[axis], " lies outside the node's cell [",
                        item.cell[axis], ", ", item.cell[3 + axis], "]");
            const std::uint64_t below = std::uint64_t{i} + 1, above = kd_above_child(n);
            if (below >= node_count)
                corrupt("node ", i, ": below child ", below, " is out of range (", node_count, " nodes)");
            if (above <= below)
                corrupt("node ", i, ": above child ", above, " does not come after the below child ", below,
                        " (nodes are depth-first)");
            if (above >= node_count)
                corrupt("node ", i, ": above child ", above, " is out of range (", node_count, " nodes)");
            ++item.depth;
            stack.push_back(item);
            stack.back().node = static_cast<std::uint32_t>(above);
            stack.back().cell[axis] = split;
            item.node = static_cast<std::uint32_t>(below);
            item.cell[3 + axis] = split;
        }
    }
    for (std::size_t i = 0; i < node_count; ++i)
        if (!reached[i]) corrupt("node ", i, " is not reachable from the root");
    if (ropes) check_ropes(tree, cells);
}

void check_kd_tree_covers(const KdTree& tree, const std::vector<Aabb>& object_bounds) {
    if (object_bounds.size() > std::numeric_limits<std::uint32_t>::max() || object_bounds.size() != tree.object_count)
        corrupt("indexes ", tree.object_count, " objects, the scene has ", object_bounds.size());
    detail::check_kd_tree_covers(tree, [&](std::uint32_t id) { return object_bounds[id]; });
}

namespace detail {

void check_kd_tree_covers(const KdTree& tree, const std::function<Aabb(std::uint32_t)>& object_box) {
    const std::uint32_t object_count = tree.object_count;
    std::vector<std::uint8_t> referenced(object_count, 0);
    for (std::uint32_t id : tree.leaf_objects)
        if (id < object_count) referenced[id] = 1;
    for (std::uint32_t id = 0; id < object_count; ++id) {
        if (referenced[id]) continue;
        const Aabb b = object_box(id);
        if (!b.empty() && !b.intersect(tree.bounds).empty())
            corrupt("leaves reference no object ", id, ", which lies inside the tree's box");
    }
}

}  // namespace detail

}  // namespace kdrt
