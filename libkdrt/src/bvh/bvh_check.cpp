#include "bvh/bvh_check.h"

#include "bvh/bvh_boxes.h"

#include <kdrt/error.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

namespace kdrt {

namespace {

template <class... Args>
[[noreturn]] void corrupt(const Args&... parts) {
    std::ostringstream s;
    s << "BVH ";
    (s << ... << parts);
    throw Error(ErrorCode::CorruptTree, s.str());
}

constexpr float kInf = std::numeric_limits<float>::infinity();

// A node and slot (a binary node: no slot), named only when a check fails.
struct Where {
    std::uint64_t node;
    int slot = -1;
};

std::ostream& operator<<(std::ostream& s, const Where& w) {
    s << "node " << w.node;
    if (w.slot >= 0) s << ", slot " << w.slot;
    return s;
}

bool is_empty_pattern(const detail::FloatBox& b) {
    for (int a = 0; a < 3; ++a)
        if (!(b.lo[a] == kInf && b.hi[a] == -kInf)) return false;
    return true;
}

// A used slot's box: finite with lo <= hi, or the empty box.
void check_box(const detail::FloatBox& b, const Where& where) {
    if (is_empty_pattern(b)) return;
    for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(b.lo[a]) || !std::isfinite(b.hi[a]))
            corrupt(where, ": box on axis ", a, " [", b.lo[a], ", ", b.hi[a], "] is not finite");
        if (!(b.lo[a] <= b.hi[a])) corrupt(where, ": box on axis ", a, " is inverted: [", b.lo[a], ", ", b.hi[a], "]");
    }
}

bool encloses(const detail::FloatBox& outer, const detail::FloatBox& inner) {
    return is_empty_pattern(inner) || outer.contains(inner);
}

// The leaves' object lists: each entry of leaf_objects in exactly one leaf,
// each id below the object count and listed once.
class LeafLists {
public:
    LeafLists(const std::vector<std::uint32_t>& leaf_objects, std::uint32_t object_count)
        : objects_(leaf_objects), object_count_(object_count), covered_(leaf_objects.size(), 0) {
        if (leaf_objects.size() > object_count)
            corrupt("lists ", leaf_objects.size(), " objects, more than its ", object_count, " objects");
        // A bitmap of the ids when it is not much larger than the lists; else sorting at the end.
        if (object_count <= 64 * (leaf_objects.size() + 1024)) listed_.assign(object_count, 0);
    }

    void add(std::uint64_t first, std::uint64_t count, const Where& where) {
        if (first + count > objects_.size())
            corrupt(where, ": objects [", first, ", ", first + count, ") exceed the ", objects_.size(),
                    " leaf object entries");
        for (std::uint64_t j = first; j < first + count; ++j) {
            if (covered_[j]) corrupt(where, ": leaf object entry ", j, " belongs to another leaf too");
            covered_[j] = 1;
            const std::uint32_t id = objects_[j];
            if (id >= object_count_) corrupt(where, ": object id ", id, " is not below the object count ", object_count_);
            if (!listed_.empty()) {
                if (listed_[id]) corrupt(where, ": object ", id, " is listed twice");
                listed_[id] = 1;
            }
        }
    }

    void finish() {
        for (std::size_t j = 0; j < covered_.size(); ++j)
            if (!covered_[j]) corrupt("leaf object entry ", j, " belongs to no leaf");
        if (listed_.empty() && !objects_.empty()) {
            std::vector<std::uint32_t> ids = objects_;
            std::sort(ids.begin(), ids.end());
            const auto twice = std::adjacent_find(ids.begin(), ids.end());
            if (twice != ids.end()) corrupt("object ", *twice, " is listed twice");
        }
    }

private:
    const std::vector<std::uint32_t>& objects_;
    std::uint32_t object_count_;
    std::vector<std::uint8_t> covered_, listed_;
};

detail::FloatBox aabb_as_float_box(const Aabb& b) {
    detail::FloatBox f;
    if (b.empty()) return f;
    for (int a = 0; a < 3; ++a) {
        f.lo[a] = static_cast<float>(b.lo[a]);
        f.hi[a] = static_cast<float>(b.hi[a]);
        if (double(f.lo[a]) != b.lo[a] || double(f.hi[a]) != b.hi[a])
            corrupt("bounds on axis ", a, " [", b.lo[a], ", ", b.hi[a], "] are not float values");
    }
    return f;
}

void check_bounds(const Aabb& bounds, const detail::FloatBox& root_union) {
    const detail::FloatBox stated = aabb_as_float_box(bounds);
    const bool same = is_empty_pattern(root_union) ? bounds == Aabb{} : stated.to_aabb() == root_union.to_aabb();
    if (!same) corrupt("bounds differ from the union of the root's boxes");
}

// Against the objects' boxes: `box(id)` encloses each listed object's box, every object with a box is listed.
template <class ForEachLeaf>
void check_objects(const std::vector<std::uint32_t>& leaf_objects, std::uint32_t object_count,
                   std::span<const Aabb> object_bounds, ForEachLeaf&& for_each_leaf) {
    if (object_bounds.size() != object_count)
        corrupt("indexes ", object_count, " objects, the scene has ", object_bounds.size());
    std::vector<std::uint8_t> listed(object_count, 0);
    for_each_leaf([&](const detail::FloatBox& box, std::uint32_t first, std::uint32_t count, const Where& where) {
        for (std::uint32_t j = first; j < first + count; ++j) {
            const std::uint32_t id = leaf_objects[j];
            listed[id] = 1;
            const Aabb& b = object_bounds[id];
            if (b.empty()) continue;
            if (!detail::in_float_range(b))
                corrupt(where, ": object ", id, "'s box is not finite or exceeds the float range");
            if (!box.contains(detail::round_out(b))) corrupt(where, ": box does not enclose object ", id);
        }
    });
    for (std::uint32_t id = 0; id < object_count; ++id)
        if (!listed[id] && !object_bounds[id].empty()) corrupt("lists no object ", id, ", which has a box");
}


Where at(std::uint64_t node, int slot) { return {node, slot}; }

}  // namespace

template <int N>
void check_bvh(const WideBvhN<N>& bvh) {
    const std::size_t node_count = bvh.nodes.size();
    if (node_count == 0) corrupt("has no nodes");
    if (node_count > 0xFFFFFFFFull) corrupt("has ", node_count, " nodes, more than 32-bit indices reach");
    LeafLists lists(bvh.leaf_objects, bvh.object_count);
    std::vector<std::uint8_t> reached(node_count, 0);
    struct Item {
        std::uint32_t node;
        int depth;
        detail::FloatBox box;  // the parent's slot box; the root's: the union of its slots
    };
    detail::FloatBox root_union;
    for (int i = 0; i < N; ++i)
        if (!bvh.nodes[0].is_empty(i)) root_union.extend(slot_box(bvh.nodes[0], i));
    check_bounds(bvh.bounds, root_union);
    std::vector<Item> stack{{0, 0, root_union}};
    while (!stack.empty()) {
        const Item item = stack.back();
        stack.pop_back();
        const std::uint32_t n = item.node;
        if (reached[n]) corrupt("node ", n, " is reached twice from the root");
        reached[n] = 1;
        if (item.depth > kBvhMaxDepth)
            corrupt("node ", n, " is at depth ", item.depth, ", deeper than ", kBvhMaxDepth);
        const WideBvhNodeN<N>& node = bvh.nodes[n];
        bool empties = false;
        for (int i = 0; i < N; ++i) {
            const detail::FloatBox box = slot_box(node, i);
            if (node.is_empty(i)) {
                if (node.child[i] != 0 || !is_empty_pattern(box))
                    corrupt(at(n, i), ": an empty slot without the empty box and child 0");
                empties = true;
                continue;
            }
            if (empties) corrupt(at(n, i), ": a used slot after an empty one");
            check_box(box, at(n, i));
            if (!encloses(item.box, box)) corrupt(at(n, i), ": box is not inside its parent's");
            if (node.is_leaf(i)) {
                lists.add(node.child[i], node.leaf_count(i), at(n, i));
                continue;
            }
            const std::uint32_t c = node.child[i];
            if (c <= n) corrupt(at(n, i), ": child ", c, " does not come after its parent");
            if (c >= node_count) corrupt(at(n, i), ": child ", c, " is out of range (", node_count, " nodes)");
            stack.push_back({c, item.depth + 1, box});
        }
    }
    for (std::size_t i = 0; i < node_count; ++i)
        if (!reached[i]) corrupt("node ", i, " is not reachable from the root");
    lists.finish();
}

template <int N>
void check_bvh(const WideBvhN<N>& bvh, std::span<const Aabb> object_bounds) {
    check_bvh(bvh);
    check_objects(bvh.leaf_objects, bvh.object_count, object_bounds, [&](auto&& leaf) {
        for (std::size_t n = 0; n < bvh.nodes.size(); ++n)
            for (int i = 0; i < N; ++i)
                if (bvh.nodes[n].is_leaf(i) && !bvh.nodes[n].is_empty(i))
                    leaf(slot_box(bvh.nodes[n], i), bvh.nodes[n].child[i], bvh.nodes[n].leaf_count(i), at(n, i));
    });
}

namespace {

detail::FloatBox node_box(const Bvh2Node& n) {
    detail::FloatBox b;
    for (int a = 0; a < 3; ++a) {
        b.lo[a] = n.lo[a];
        b.hi[a] = n.hi[a];
    }
    return b;
}

}  // namespace

void check_bvh2(const Bvh2& bvh) {
    const std::size_t node_count = bvh.nodes.size();
    LeafLists lists(bvh.leaf_objects, bvh.object_count);
    if (node_count == 0) {
        lists.finish();
        return;
    }
    if (node_count > 0xFFFFFFFFull) corrupt("has ", node_count, " nodes, more than 32-bit indices reach");
    std::vector<std::uint8_t> reached(node_count, 0);
    struct Item {
        std::uint32_t node;
        int depth;
        detail::FloatBox parent;
    };
    detail::FloatBox all;
    all.lo[0] = all.lo[1] = all.lo[2] = -kInf;
    all.hi[0] = all.hi[1] = all.hi[2] = kInf;
    std::vector<Item> stack{{0, 0, all}};
    while (!stack.empty()) {
        const Item item = stack.back();
        stack.pop_back();
        const std::uint32_t i = item.node;
        if (reached[i]) corrupt("node ", i, " is reached twice from the root");
        reached[i] = 1;
        if (item.depth > kBvhMaxDepth) corrupt("node ", i, " is at depth ", item.depth, ", deeper than ", kBvhMaxDepth);
        const Bvh2Node& n = bvh.nodes[i];
        const detail::FloatBox box = node_box(n);
        const Where where{i};
        check_box(box, where);
        if (!encloses(item.parent, box)) corrupt(where, ": box is not inside its parent's");
        if (bvh2_is_leaf(n)) {
            lists.add(n.first, n.count, where);
            continue;
        }
        const std::uint64_t first = n.first;
        if (first <= i) corrupt(where, ": children ", first, " do not come after their parent");
        if (first + 1 >= node_count) corrupt(where, ": children ", first, ", ", first + 1, " are out of range");
        stack.push_back({n.first, item.depth + 1, box});
        stack.push_back({n.first + 1, item.depth + 1, box});
    }
    for (std::size_t i = 0; i < node_count; ++i)
        if (!reached[i]) corrupt("node ", i, " is not reachable from the root");
    lists.finish();
}

void check_bvh2(const Bvh2& bvh, std::span<const Aabb> object_bounds) {
    check_bvh2(bvh);
    check_objects(bvh.leaf_objects, bvh.object_count, object_bounds, [&](auto&& leaf) {
        for (std::size_t i = 0; i < bvh.nodes.size(); ++i)
            if (bvh2_is_leaf(bvh.nodes[i]))
                leaf(node_box(bvh.nodes[i]), bvh.nodes[i].first, bvh.nodes[i].count, Where{i});
    });
}

template void check_bvh<4>(const WideBvhN<4>&);
template void check_bvh<8>(const WideBvhN<8>&);
template void check_bvh<4>(const WideBvhN<4>&, std::span<const Aabb>);
template void check_bvh<8>(const WideBvhN<8>&, std::span<const Aabb>);

}  // namespace kdrt
