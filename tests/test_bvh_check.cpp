// check_bvh refuses every kind of corruption a file could carry, naming it:
// indices out of range, cycles and shared nodes, depth past the bound, slot
// layout, leaf ranges, object ids, boxes (non-finite, inverted, not enclosing
// their children or objects), bounds; and, against the objects' boxes,
// objects left out.
#include "bvh/bvh_build.h"
#include "bvh/bvh_check.h"

#include <kdrt/error.h>

#include <catch2/catch.hpp>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

using namespace kdrt;

namespace {

std::vector<Aabb> grid_boxes(int n) {
    std::vector<Aabb> boxes;
    for (int i = 0; i < n; ++i) {
        const glm::dvec3 c(i % 10, (i / 10) % 10, i / 100);
        boxes.push_back({c, c + glm::dvec3(0.5)});
    }
    return boxes;
}

// The CorruptTree message check_bvh gives for `bvh` ("" if it passes).
template <int N>
std::string rejection(const WideBvhN<N>& bvh, const std::vector<Aabb>* boxes = nullptr) {
    try {
        if (boxes) check_bvh(bvh, *boxes);
        else check_bvh(bvh);
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::CorruptTree);
        return e.what();
    }
    return "";
}

std::string rejection2(const Bvh2& bvh, const std::vector<Aabb>* boxes = nullptr) {
    try {
        if (boxes) check_bvh2(bvh, *boxes);
        else check_bvh2(bvh);
    } catch (const Error& e) {
        CHECK(e.code() == ErrorCode::CorruptTree);
        return e.what();
    }
    return "";
}

bool mentions(const std::string& message, const std::string& needle) {
    INFO("message: " << message << "; expected: " << needle);
    return message.find(needle) != std::string::npos;
}

// The first slot below the root satisfying `pick`, as (node, slot).
std::pair<std::size_t, int> find_slot(const WideBvh& bvh, const std::function<bool(const WideBvhNode&, int)>& pick) {
    for (std::size_t n = 1; n < bvh.nodes.size(); ++n)
        for (int i = 0; i < kWideBvhWidth; ++i)
            if (pick(bvh.nodes[n], i)) return {n, i};
    FAIL("no such slot");
    return {0, 0};
}

bool inner(const WideBvhNode& node, int i) { return !node.is_leaf(i); }
bool leaf(const WideBvhNode& node, int i) { return node.is_leaf(i) && !node.is_empty(i); }
bool empty(const WideBvhNode& node, int i) { return node.is_empty(i); }

}  // namespace

TEST_CASE("bvh check: built BVHs pass", "[bvh][check]") {
    for (int n : {0, 1, 2, 100, 1000}) {
        const std::vector<Aabb> boxes = grid_boxes(n);
        const Bvh2 b2 = build_bvh2({boxes, 0});
        CHECK(rejection2(b2, &boxes).empty());
        CHECK(rejection(collapse_bvh<8>(b2), &boxes).empty());
        CHECK(rejection(collapse_bvh<4>(b2), &boxes).empty());
    }
}

TEST_CASE("bvh check: every kind of structural damage is named", "[bvh][check]") {
    const std::vector<Aabb> boxes = grid_boxes(1000);
    BvhBuildConfig config;
    config.max_leaf_size = 2;
    const WideBvh good = build_wide_bvh(BvhBuildInput{boxes, 0}, config);
    REQUIRE(good.nodes.size() > 20);
    REQUIRE(rejection(good, &boxes).empty());
    // Not structured bindings: lambdas below capture them (which C++20 allows and clang 15 does not).
    const std::pair<std::size_t, int> inner_slot = find_slot(good, inner), leaf_slot = find_slot(good, leaf),
                                      empty_slot = find_slot(good, empty);
    const std::size_t in = inner_slot.first, lf = leaf_slot.first, em = empty_slot.first;
    const int in_slot = inner_slot.second, lf_slot = leaf_slot.second, em_slot = empty_slot.second;
    auto damaged = [&](const std::function<void(WideBvh&)>& harm) {
        WideBvh w = good;
        harm(w);
        return rejection(w);
    };
    CHECK(mentions(damaged([](WideBvh& w) { w.nodes.clear(); }), "has no nodes"));
    CHECK(mentions(damaged([&](WideBvh& w) { w.nodes[in].child[in_slot] = static_cast<std::uint32_t>(w.nodes.size()); }),
                   "out of range"));
    CHECK(mentions(damaged([&](WideBvh& w) { w.nodes[in].child[in_slot] = static_cast<std::uint32_t>(in); }),
                   "does not come after its parent"));
    CHECK(mentions(damaged([&](WideBvh& w) {  // two slots naming one node
                       WideBvhNode& node = w.nodes[in];
                       const int other = in_slot == 0 ? 1 : 0;
                       node.set_inner(other, node.child[in_slot]);
                       for (int s = 0; s < 2; ++s)
                           for (int a = 0; a < 3; ++a) node.box[s][a][other] = node.box[s][a][in_slot];
                   }),
                   "reached twice"));
    CHECK(mentions(damaged([&](WideBvh& w) { w.nodes.push_back(w.nodes.back()); }), "not reachable"));
    CHECK(mentions(damaged([&](WideBvh& w) { w.nodes[em].child[em_slot] = 1; }), "empty slot"));
    CHECK(mentions(damaged([&](WideBvh& w) { w.nodes[em].box[0][0][em_slot] = 0.0f; }), "empty slot"));
    CHECK(mentions(damaged([&](WideBvh& w) {
                       std::swap(w.nodes[em].count[em_slot], w.nodes[em].count[0]);  // an empty slot first
                       std::swap(w.nodes[em].child[em_slot], w.nodes[em].child[0]);
                       for (int s = 0; s < 2; ++s)
                           for (int a = 0; a < 3; ++a) std::swap(w.nodes[em].box[s][a][em_slot], w.nodes[em].box[s][a][0]);
                   }),
                   "used slot after an empty one"));
    CHECK(mentions(damaged([&](WideBvh& w) { w.nodes[lf].child[lf_slot] = static_cast<std::uint32_t>(w.leaf_objects.size()); }),
                   "exceed the"));
    CHECK(mentions(damaged([&](WideBvh& w) { w.nodes[lf].count[lf_slot] = kBvhLeafFlag | 0x7FFFFFFFu; }), "exceed the"));
    CHECK(mentions(damaged([&](WideBvh& w) {  // two leaves over the same entries
                       const std::uint32_t other = w.nodes[lf].child[lf_slot] ? 0 : 2;
                       w.nodes[lf].child[lf_slot] = other;
                   }),
                   "belongs to another leaf"));
    CHECK(mentions(damaged([&](WideBvh& w) { w.leaf_objects.push_back(w.object_count - 1); }), "more than its"));
    CHECK(mentions(damaged([&](WideBvh& w) { w.leaf_objects.push_back(w.object_count++); }), "belongs to no leaf"));
    CHECK(mentions(damaged([&](WideBvh& w) { w.leaf_objects[0] = w.object_count; }), "not below the object count"));
    CHECK(mentions(damaged([&](WideBvh& w) { w.leaf_objects[0] = w.leaf_objects[1]; }), "listed twice"));
    CHECK(mentions(damaged([&](WideBvh& w) { w.nodes[lf].box[1][2][lf_slot] = std::nanf(""); }), "not finite"));
    CHECK(mentions(damaged([&](WideBvh& w) { w.nodes[lf].box[0][1][lf_slot] = std::numeric_limits<float>::infinity(); }),
                   "not finite"));
    CHECK(mentions(damaged([&](WideBvh& w) {
                       std::swap(w.nodes[lf].box[0][0][lf_slot], w.nodes[lf].box[1][0][lf_slot]);
                       w.nodes[lf].box[0][0][lf_slot] += 1.0f;
                   }),
                   "inverted"));
    CHECK(mentions(damaged([&](WideBvh& w) { w.nodes[w.nodes.size() - 1].box[1][0][0] += 100.0f; }),
                   "not inside its parent's"));
    CHECK(mentions(damaged([&](WideBvh& w) { w.bounds.hi.x += 1.0; }), "bounds differ"));
    CHECK(mentions(damaged([&](WideBvh& w) { w.bounds.hi.x = std::nextafter(w.bounds.hi.x, 1e9); }), "not float values"));

    // A chain deeper than kBvhMaxDepth: each node's slot 0 the next node.
    WideBvh deep;
    deep.object_count = 1;
    deep.leaf_objects = {0};
    for (int d = 0; d <= kBvhMaxDepth + 1; ++d) {
        WideBvhNode node = WideBvhNode::empty_node();
        const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
        node.set_box(0, lo, hi);
        if (d == kBvhMaxDepth + 1) node.set_leaf(0, 0, 1);
        else node.set_inner(0, static_cast<std::uint32_t>(d + 1));
        deep.nodes.push_back(node);
    }
    deep.bounds = {glm::dvec3(0), glm::dvec3(1)};
    CHECK(mentions(rejection(deep), "deeper than"));
    deep.nodes.pop_back();
    deep.nodes.back() = deep.nodes.front();
    deep.nodes.back().set_leaf(0, 0, 1);
    CHECK(rejection(deep).empty());  // at the bound: accepted
}

TEST_CASE("bvh check: against the objects' boxes, objects left out or outside their leaf are named", "[bvh][check]") {
    const std::vector<Aabb> boxes = grid_boxes(300);
    const WideBvh good = build_wide_bvh(BvhBuildInput{boxes, 0});
    {
        std::vector<Aabb> moved = boxes;
        moved[42].hi += glm::dvec3(0.25);
        CHECK(mentions(rejection(good, &moved), "does not enclose object 42"));
    }
    {
        std::vector<Aabb> fewer(boxes.begin(), boxes.end() - 1);
        CHECK(mentions(rejection(good, &fewer), "the scene has 299"));
    }
    {  // a forger's BVH without object 7: sound in itself, refused against the scene
        WideBvh w = good;
        std::vector<Aabb> left = boxes;
        left[7] = Aabb{};
        w = build_wide_bvh(BvhBuildInput{left, 0});
        CHECK(rejection(w).empty());
        CHECK(mentions(rejection(w, &boxes), "lists no object 7"));
        CHECK(rejection(w, &left).empty());
    }
    {
        std::vector<Aabb> bad = boxes;
        bad[3].lo.x = -1e39;
        CHECK(mentions(rejection(good, &bad), "object 3's box"));
    }
}

TEST_CASE("bvh check: binary BVHs are checked the same way", "[bvh][check]") {
    const std::vector<Aabb> boxes = grid_boxes(500);
    const Bvh2 good = build_bvh2({boxes, 0});
    REQUIRE(rejection2(good, &boxes).empty());
    auto damaged = [&](const std::function<void(Bvh2&)>& harm) {
        Bvh2 b = good;
        harm(b);
        return rejection2(b);
    };
    std::size_t inner_node = 0;
    while (bvh2_is_leaf(good.nodes[inner_node])) ++inner_node;
    std::size_t leaf_node = 0;
    while (!bvh2_is_leaf(good.nodes[leaf_node])) ++leaf_node;
    CHECK(mentions(damaged([&](Bvh2& b) { b.nodes[inner_node].first = static_cast<std::uint32_t>(b.nodes.size() - 1); }),
                   "out of range"));
    CHECK(mentions(damaged([&](Bvh2& b) { b.nodes[inner_node].first = 0; }), "do not come after"));
    CHECK(mentions(damaged([&](Bvh2& b) { b.nodes[leaf_node].count += 1000000; }), "exceed the"));
    CHECK(mentions(damaged([&](Bvh2& b) { b.nodes[leaf_node].hi[0] = std::nanf(""); }), "not finite"));
    CHECK(mentions(damaged([&](Bvh2& b) { b.nodes[leaf_node].hi[0] += 100.0f; }), "not inside its parent's"));
    CHECK(mentions(damaged([&](Bvh2& b) { b.leaf_objects[0] = b.leaf_objects[1]; }), "listed twice"));
    std::vector<Aabb> moved = boxes;
    moved[10].lo -= glm::dvec3(1.0);
    CHECK(mentions(rejection2(good, &moved), "does not enclose object 10"));
}
