// The BVH builder and the collapse: every object in exactly one leaf, boxes
// that enclose their objects, the same BVH for any thread count, bounded
// depth on adversarial inputs, the configuration checked, progress and
// cancellation, and the statistics.
#include "bvh/bvh_build.h"
#include "bvh/bvh_check.h"
#include "bvh/bvh_stats.h"

#include <kdrt/error.h>

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

using namespace kdrt;

namespace {

// Random boxes, some flat, some empty (left out), the first `spheres` cubes.
std::vector<Aabb> random_boxes(std::size_t n, std::uint32_t seed, std::size_t spheres = 0, double scale = 1.0) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-4.0, 4.0), s(0.0, 0.3);
    std::vector<Aabb> boxes;
    for (std::size_t i = 0; i < n; ++i) {
        const glm::dvec3 c{u(rng), u(rng), u(rng)};
        glm::dvec3 e{s(rng), s(rng), i % 7 == 0 ? 0.0 : s(rng)};
        if (i < spheres) e = glm::dvec3(e.x);
        boxes.push_back({(c - e) * scale, (c + e) * scale});
    }
    if (n > 10) boxes[n / 2] = Aabb{};  // an object without a box
    return boxes;
}

// The ids the leaves list, sorted.
template <class Bvh>
std::vector<std::uint32_t> listed(const Bvh& bvh) {
    std::vector<std::uint32_t> ids = bvh.leaf_objects;
    std::sort(ids.begin(), ids.end());
    return ids;
}

std::vector<std::uint32_t> ids_with_boxes(const std::vector<Aabb>& boxes) {
    std::vector<std::uint32_t> ids;
    for (std::uint32_t i = 0; i < boxes.size(); ++i)
        if (!boxes[i].empty()) ids.push_back(i);
    return ids;
}

int largest_leaf(const Bvh2& bvh) {
    std::uint32_t most = 0;
    for (const Bvh2Node& n : bvh.nodes)
        if (bvh2_is_leaf(n)) most = std::max(most, n.count);
    return static_cast<int>(most);
}

// Every leaf of the binary BVH as (first, count), sorted.
std::vector<std::pair<std::uint32_t, std::uint32_t>> leaves_of(const Bvh2& bvh) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
    for (const Bvh2Node& n : bvh.nodes)
        if (bvh2_is_leaf(n)) out.emplace_back(n.first, n.count);
    std::sort(out.begin(), out.end());
    return out;
}

template <int N>
std::vector<std::pair<std::uint32_t, std::uint32_t>> leaves_of(const WideBvhN<N>& bvh) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
    for (const auto& node : bvh.nodes)
        for (int i = 0; i < N; ++i)
            if (node.is_leaf(i) && !node.is_empty(i)) out.emplace_back(node.child[i], node.leaf_count(i));
    std::sort(out.begin(), out.end());
    return out;
}

// Every cut of binary subtree n into at most `most` slots (a cut: nodes whose
// subtrees together hold the subtree's leaves, each once).
void cuts(const Bvh2& b, std::uint32_t n, int most, std::vector<std::vector<std::uint32_t>>& out) {
    out.push_back({n});
    const Bvh2Node& node = b.nodes[n];
    if (bvh2_is_leaf(node) || most < 2) return;
    std::vector<std::vector<std::uint32_t>> left;
    cuts(b, node.first, most - 1, left);
    for (const auto& a : left) {
        std::vector<std::vector<std::uint32_t>> right;
        cuts(b, node.first + 1, most - static_cast<int>(a.size()), right);
        for (const auto& r : right) {
            out.push_back(a);
            out.back().insert(out.back().end(), r.begin(), r.end());
        }
    }
}

// By brute force: the least summed area of the wide nodes of any N-wide BVH
// made from binary subtree n (inner), n its root; memo[n] once known.
template <int N>
double least_area(const Bvh2& b, std::uint32_t n, std::vector<double>& memo) {
    if (memo[n] >= 0.0) return memo[n];
    const Bvh2Node& node = b.nodes[n];
    std::vector<std::vector<std::uint32_t>> left, right;
    cuts(b, node.first, N - 1, left);
    double best = std::numeric_limits<double>::infinity();
    for (const auto& a : left) {
        right.clear();
        cuts(b, node.first + 1, N - static_cast<int>(a.size()), right);
        for (const auto& r : right) {
            double sum = 0.0;
            for (const auto* part : {&a, &r})
                for (std::uint32_t c : *part)
                    if (!bvh2_is_leaf(b.nodes[c])) sum += least_area<N>(b, c, memo);
            best = std::min(best, sum);
        }
    }
    const Aabb box{{node.lo[0], node.lo[1], node.lo[2]}, {node.hi[0], node.hi[1], node.hi[2]}};
    return memo[n] = box.surface_area() + best;
}

template <int N>
double least_area(const Bvh2& b) {
    std::vector<double> memo(b.nodes.size(), -1.0);
    return least_area<N>(b, 0, memo);
}

// The summed area of a wide BVH's nodes, each node's box the union of its slots'.
template <int N>
double node_areas(const WideBvhN<N>& w) {
    double sum = 0.0;
    for (const auto& node : w.nodes) {
        Aabb box;
        for (int i = 0; i < node.used_slots(); ++i) box.extend(node.slot_box(i));
        sum += box.surface_area();
    }
    return sum;
}

template <int N>
void check_collapse(const Bvh2& b2, const std::vector<Aabb>& boxes) {
    const WideBvhN<N> w = collapse_bvh<N>(b2);
    CHECK_NOTHROW(check_bvh(w, boxes));
    CHECK(w.leaf_objects == b2.leaf_objects);
    CHECK(leaves_of(w) == leaves_of(b2));  // the same leaves, regrouped
    CHECK(bvh_stats(w).depth <= bvh2_depth(b2) + 1);
    CHECK(w.build_sah_cost == bvh_sah_cost(w));
}

}  // namespace

TEST_CASE("bvh: every object with a box is in exactly one leaf whose box encloses it", "[bvh]") {
    for (std::size_t n : {std::size_t{1}, std::size_t{2}, std::size_t{9}, std::size_t{300}, std::size_t{5000}}) {
        const std::vector<Aabb> boxes = random_boxes(n, 7 + static_cast<std::uint32_t>(n), n / 3);
        BvhBuildInput in{boxes, static_cast<std::uint32_t>(n / 3)};
        for (int leaf : {1, 4, 8}) {
            BvhBuildConfig config;
            config.max_leaf_size = leaf;
            const Bvh2 b2 = build_bvh2(in, config);
            INFO(n << " objects, leaves of at most " << leaf);
            CHECK_NOTHROW(check_bvh2(b2, boxes));
            CHECK(listed(b2) == ids_with_boxes(boxes));
            CHECK(largest_leaf(b2) <= leaf);
            check_collapse<4>(b2, boxes);
            check_collapse<8>(b2, boxes);
        }
    }
}

TEST_CASE("bvh: the collapse's wide nodes have the least summed area of any collapse", "[bvh]") {
    // Scale 1e30: areas beyond float's range, which the collapse's costs must not reach.
    for (std::uint32_t seed : {1u, 2u, 3u}) {
        for (double scale : {1.0, 1e30}) {
            const std::vector<Aabb> boxes = random_boxes(40, seed, 0, scale);
            BvhBuildConfig config;
            config.max_leaf_size = 1;  // a deep binary tree: many ways to cut it
            const Bvh2 b2 = build_bvh2({boxes, 0}, config);
            REQUIRE(!bvh2_is_leaf(b2.nodes[0]));
            INFO("seed " << seed << ", scale " << scale);
            CHECK(node_areas(collapse_bvh<4>(b2)) == Approx(least_area<4>(b2)).epsilon(1e-5));
            CHECK(node_areas(collapse_bvh<8>(b2)) == Approx(least_area<8>(b2)).epsilon(1e-5));
        }
    }
}

TEST_CASE("bvh: objects at one point still fill the wide nodes", "[bvh]") {
    // Every box of area 0: every cut costs the same, and the collapse fills the slots.
    const std::vector<Aabb> boxes(64, Aabb{glm::dvec3(1.0), glm::dvec3(1.0)});
    BvhBuildConfig config;
    config.max_leaf_size = 1;
    const Bvh2 b2 = build_bvh2({boxes, 0}, config);
    const WideBvh w = collapse_bvh<8>(b2);
    CHECK_NOTHROW(check_bvh(w, boxes));
    INFO(w.nodes.size() << " nodes, " << bvh_stats(w).empty_slots << " empty slots");
    CHECK(w.nodes.size() <= 10);  // 64 leaves take at least 9 nodes of 8 slots (63 / 7)
}

TEST_CASE("bvh: the same BVH for 1, 2 and 4 threads", "[bvh][parallel]") {
    // Large enough for the parallel binning, partition and subtrees (2^15 and 2^12 objects).
    const std::vector<Aabb> boxes = random_boxes(120000, 3, 20000);
    BvhBuildInput in{boxes, 20000};
    BvhBuildConfig config;
    config.threads = 1;
    const Bvh2 one = build_bvh2(in, config);
    const WideBvh wide_one = collapse_bvh<8>(one, 1);
    CHECK_NOTHROW(check_bvh(wide_one, boxes));
    for (int threads : {2, 4}) {
        config.threads = threads;
        const Bvh2 b2 = build_bvh2(in, config);
        CHECK(b2 == one);
        CHECK(collapse_bvh<8>(b2, threads) == wide_one);
        CHECK(build_wide_bvh<4>(in, config) == collapse_bvh<4>(one, 1));
    }
    // And == sees a difference.
    Bvh2 other = one;
    other.nodes[1].lo[0] = std::nextafter(other.nodes[1].lo[0], -1e30f);
    CHECK_FALSE(other == one);
    WideBvh wide_other = wide_one;
    wide_other.leaf_objects[0] ^= 1;
    CHECK_FALSE(wide_other == wide_one);
}

TEST_CASE("bvh: inputs with no object, one object, and no boxes", "[bvh]") {
    for (const std::vector<Aabb>& boxes :
         {std::vector<Aabb>{}, std::vector<Aabb>{Aabb{}}, std::vector<Aabb>(5, Aabb{}),
          std::vector<Aabb>{Aabb{glm::dvec3(1), glm::dvec3(2)}}}) {
        const Bvh2 b2 = build_bvh2({boxes, 0});
        const WideBvh w = build_wide_bvh({boxes, 0});
        CHECK_NOTHROW(check_bvh2(b2, boxes));
        CHECK_NOTHROW(check_bvh(w, boxes));
        CHECK(w.nodes.size() == 1);
        CHECK(w.object_count == boxes.size());
        const bool one = boxes.size() == 1 && !boxes[0].empty();
        CHECK(b2.nodes.size() == (one ? 1u : 0u));
        CHECK(w.nodes[0].used_slots() == (one ? 1 : 0));
        CHECK(w.bounds == (one ? Aabb{glm::dvec3(1), glm::dvec3(2)} : Aabb{}));
        CHECK(bvh_stats(w).sah_cost == (one ? 2.0 : 1.0));  // the root, and its one leaf
    }
}

TEST_CASE("bvh: objects in one point, in a line and spread exponentially keep within the depth bound", "[bvh]") {
    std::vector<std::vector<Aabb>> inputs;
    inputs.push_back(std::vector<Aabb>(20000, Aabb{glm::dvec3(0.5), glm::dvec3(0.5)}));  // all in one point
    std::vector<Aabb> same_centre;  // nested boxes around one centre
    for (int i = 0; i < 5000; ++i) same_centre.push_back({glm::dvec3(-1.0 - i), glm::dvec3(1.0 + i)});
    inputs.push_back(same_centre);
    std::vector<Aabb> exponential;  // every SAH split cuts off one object
    for (int i = 0; i < 3000; ++i) {
        const double x = std::ldexp(1.0, i % 120 - 60) * (1 + i / 120);
        exponential.push_back({glm::dvec3(x, 0, 0), glm::dvec3(x, 1e-3, 1e-3)});
    }
    inputs.push_back(exponential);
    std::vector<Aabb> line;
    for (int i = 0; i < 10000; ++i) line.push_back({glm::dvec3(i, 0, 0), glm::dvec3(i + 0.5, 0, 0)});
    inputs.push_back(line);
    for (const auto& boxes : inputs) {
        BvhBuildConfig config;
        config.max_leaf_size = 4;
        const Bvh2 b2 = build_bvh2({boxes, 0}, config);
        CHECK_NOTHROW(check_bvh2(b2, boxes));
        CHECK(bvh2_depth(b2) <= kBvhMaxDepth);
        CHECK(largest_leaf(b2) <= 4);
        const WideBvh w = collapse_bvh<8>(b2);
        CHECK_NOTHROW(check_bvh(w, boxes));
    }
    // One point: the halves fallback gives a balanced tree.
    const Bvh2 point = build_bvh2({inputs[0], 0});
    CHECK(bvh2_depth(point) <= 13);
}

TEST_CASE("bvh: tiny and huge scales build the same hierarchy", "[bvh]") {
    const std::vector<Aabb> unit = random_boxes(2000, 11);
    const Bvh2 reference = build_bvh2({unit, 0});
    for (double scale : {0x1p-66, 0x1p50}) {  // about 1e-20 and 1e15, powers of two: exact
        const std::vector<Aabb> boxes = random_boxes(2000, 11, 0, scale);
        const Bvh2 b2 = build_bvh2({boxes, 0});
        INFO("scale " << scale);
        CHECK_NOTHROW(check_bvh2(b2, boxes));
        CHECK(b2.leaf_objects == reference.leaf_objects);
        CHECK(leaves_of(b2) == leaves_of(reference));
        CHECK_NOTHROW(check_bvh(collapse_bvh<8>(b2), boxes));
    }
}

TEST_CASE("bvh: boxes out of range and bad inputs are refused, naming the object", "[bvh]") {
    std::vector<Aabb> boxes = random_boxes(100, 5);
    for (double bad : {std::numeric_limits<double>::infinity(), std::nan(""), 1e39}) {
        std::vector<Aabb> b = boxes;
        b[42].hi.y = bad;
        try {
            build_bvh2({b, 0});
            FAIL("accepted a box reaching " << bad);
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::InvalidArgument);
            CHECK(std::string(e.what()).find("object 42") != std::string::npos);
        }
    }
    CHECK_THROWS_AS(build_bvh2({boxes, 101}), Error);  // more spheres than objects
}

TEST_CASE("bvh: the build configuration is checked, naming the field", "[bvh]") {
    auto refused = [](auto change, const char* field) {
        BvhBuildConfig c;
        change(c);
        try {
            c.validate();
            FAIL("accepted a bad " << field);
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::InvalidArgument);
            CHECK(std::string(e.what()).find(field) != std::string::npos);
        }
        const std::vector<Aabb> boxes = random_boxes(10, 1);
        CHECK_THROWS_AS(build_bvh2({boxes, 0}, c), Error);
    };
    CHECK_NOTHROW(BvhBuildConfig{}.validate());
    refused([](BvhBuildConfig& c) { c.bins = 3; }, "bins");
    refused([](BvhBuildConfig& c) { c.bins = 257; }, "bins");
    refused([](BvhBuildConfig& c) { c.max_leaf_size = 0; }, "max_leaf_size");
    refused([](BvhBuildConfig& c) { c.max_leaf_size = 65; }, "max_leaf_size");
    refused([](BvhBuildConfig& c) { c.traversal_cost = 0.0; }, "traversal_cost");
    refused([](BvhBuildConfig& c) { c.intersection_cost = std::nan(""); }, "intersection_cost");
    refused([](BvhBuildConfig& c) { c.sphere_intersection_cost = 1e7; }, "sphere_intersection_cost");
    refused([](BvhBuildConfig& c) { c.leaf_block = 3; }, "leaf_block");
    refused([](BvhBuildConfig& c) { c.leaf_block = 32; }, "leaf_block");
    refused([](BvhBuildConfig& c) { c.threads = -1; }, "threads");
}

TEST_CASE("bvh: progress is reported in order and a build can be cancelled", "[bvh]") {
    const std::vector<Aabb> boxes = random_boxes(60000, 9);
    std::vector<double> seen;
    BvhBuildConfig config;
    config.progress = [&](double f) {
        seen.push_back(f);
        return true;
    };
    const Bvh2 done = build_bvh2({boxes, 0}, config);
    REQUIRE(seen.size() >= 10);
    CHECK(std::is_sorted(seen.begin(), seen.end()));
    CHECK(seen.front() > 0.0);
    CHECK(seen.back() <= 1.0);
    CHECK(seen.back() > 0.95);
    config.progress = nullptr;
    CHECK(build_bvh2({boxes, 0}, config) == done);  // following the build does not change it

    for (int threads : {1, 2}) {
        int calls = 0;
        config.threads = threads;
        config.progress = [&](double f) { return ++calls < 3 && f < 0.5; };
        try {
            build_bvh2({boxes, 0}, config);
            FAIL("a cancelled build finished");
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::Cancelled);
        }
        CHECK(calls == 3);  // no call after the one that cancelled
    }
}

TEST_CASE("bvh: statistics count nodes, leaves, depth and bytes, and the SAH cost follows areas", "[bvh]") {
    // Two unit cubes side by side: a root with two leaf slots, each a third of the root's area... of
    // surface: the root is 2x1x1 (area 10), each cube 6: cost 1 + 6/10 + 6/10.
    const std::vector<Aabb> two = {{glm::dvec3(0), glm::dvec3(1)}, {glm::dvec3(1, 0, 0), glm::dvec3(2, 1, 1)}};
    BvhBuildConfig config;
    config.max_leaf_size = 1;
    const WideBvh w = build_wide_bvh(BvhBuildInput{two, 0}, config);
    const BvhStats s = bvh_stats(w);
    CHECK(s.nodes == 1);
    CHECK(s.leaves == 2);
    CHECK(s.empty_slots == kWideBvhWidth - 2);
    CHECK(s.depth == 1);
    CHECK(s.mean_leaf_size == 1.0);
    CHECK(s.sah_cost == Approx(1.0 + 0.6 + 0.6));
    CHECK(s.node_bytes == sizeof(WideBvhNode));
    CHECK(s.leaf_object_bytes == 8);
    CHECK(s.per_object(s.total_bytes()) == Approx((256.0 + 8.0) / 2.0));

    const std::vector<Aabb> boxes = random_boxes(20000, 4);
    const WideBvh big = build_wide_bvh(BvhBuildInput{boxes, 0});
    const BvhStats b = bvh_stats(big);
    CHECK(b.nodes == big.nodes.size());
    CHECK(b.leaves * b.mean_leaf_size == Approx(static_cast<double>(big.leaf_objects.size())));
    CHECK(b.depth >= 4);
    CHECK(b.depth <= 12);
    CHECK(b.sah_cost > 1.0);
    CHECK(b.sah_cost == b.build_sah_cost);
    CHECK(b.per_object(b.total_bytes()) < 48.0);
}
