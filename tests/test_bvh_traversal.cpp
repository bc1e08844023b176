// The BVH traversals (cpu/traverse_bvh.h) return exactly what brute force
// returns (closest hit: id, t, barycentrics; any hit before, at and beyond
// it), in float and double, for wide BVHs of 4 and 8 children and the binary
// BVH, with the leaf tests of the cpu device, on random and adversarial rays
// and scenes. This file tests the baseline copy; test_bvh_traversal_avx2.cpp
// the AVX2 one.
#include "bvh_test_scenes.h"
#include "bvh_traversal_checks.h"

#include "bvh/bvh_build.h"
#include "bvh/bvh_check.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

using namespace kdrt;
using namespace kdrt::detail;

namespace {

void check_report(const TraversalReport& r, const std::string& what, bool expect_hits = true) {
    INFO(what << ": " << r.rays << " rays, " << r.hits << " hits; first mismatch: " << r.first);
    if (expect_hits) CHECK(r.hits > r.rays / 10);
    CHECK(r.mismatches == 0);
    CHECK(r.blocked_mismatches == 0);
}

// Every traversal, leaf test and width over a scene, for BVHs built over the
// boxes the renderer gives (padded) and over the tight ones.
template <class Real>
void check_scene(const Scene& scene, std::uint32_t seed, const std::string& name, bool expect_hits = true) {
    const PreparedScene p = test::prepare(scene, sizeof(Real) == sizeof(double) ? Precision::Double : Precision::Float);
    const SceneGeometry<Real>& g = p.geometry<Real>();
    const std::vector<Aabb> padded = p.object_bounds(), tight = test::tight_bounds(g);
    for (const auto& [boxes, kind] : {std::pair{&padded, "padded boxes"}, std::pair{&tight, "tight boxes"}}) {
        const BvhBuildInput in{*boxes, static_cast<std::uint32_t>(g.spheres.size())};
        BvhBuildConfig config;
        config.max_leaf_size = 4;
        const Bvh2 b2 = build_bvh2(in, config);
        const WideBvhN<8> w8 = collapse_bvh<8>(b2);
        const WideBvhN<4> w4 = collapse_bvh<4>(b2);
        REQUIRE_NOTHROW(check_bvh(w8, *boxes));
        const auto rays = bvh_rays(g, p.bounds, w8, seed);
        const std::string what = name + ", " + kind + (sizeof(Real) == 8 ? ", double" : ", float");
        for (bool batched : {false, true}) {
            const std::string leaf = batched ? " (batched leaf test)" : "";
            check_report(check_wide_bvh(g, w8, rays, batched), what + ", BVH8" + leaf, expect_hits);
            check_report(check_wide_bvh(g, w4, rays, batched), what + ", BVH4" + leaf, expect_hits);
        }
        check_report(check_bvh2_traversal(g, b2, rays, false), what + ", BVH2", expect_hits);
    }
}

void check_scene_both(const Scene& scene, std::uint32_t seed, const std::string& name, bool expect_hits = true) {
    check_scene<float>(scene, seed, name, expect_hits);
    check_scene<double>(scene, seed + 1000, name, expect_hits);
}

}  // namespace

TEST_CASE("bvh traversal: every traversal equals brute force on hard random scenes", "[bvh][traversal]") {
    for (std::uint32_t seed : {1u, 2u, 3u}) check_scene_both(test::bvh_hard_scene(seed), seed, "hard scene");
}

TEST_CASE("bvh traversal: scenes at 1e-20 and 1e15 scale equal brute force", "[bvh][traversal]") {
    check_scene_both(test::bvh_hard_scene(4, 1e-20), 4, "hard scene at 1e-20");
    check_scene_both(test::bvh_hard_scene(5, 1e15), 5, "hard scene at 1e15");
}

TEST_CASE("bvh traversal: adversarial scenes equal brute force", "[bvh][traversal]") {
    {  // every object in one place: triangles sharing a vertex and spheres sharing a centre
        Scene s;
        const auto m = s.add_material({});
        std::mt19937 rng(8);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        for (int i = 0; i < 60; ++i) s.add_triangle({0, 0, 0}, {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, m);
        for (int i = 0; i < 20; ++i) s.add_sphere({0, 0, 0}, 0.1 + 0.02 * i, m);
        for (int i = 0; i < 40; ++i) s.add_triangle({0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, m);
        check_scene_both(s, 21, "objects in one place");
    }
    {  // degenerate and huge triangles: a ground of half-size 1e6 under small and degenerate ones
        Scene s;
        const auto m = s.add_material({});
        s.add_triangle({-1e6, 0, -1e6}, {1e6, 0, -1e6}, {0, 0, 1e6}, m);
        s.add_triangle({-1e6, -1, 1e6}, {1e6, 5, 1e6}, {0, 1e6, 1e6}, m);
        const Scene hard = test::bvh_hard_scene(6);
        for (std::size_t i = 0; i < hard.triangles.triangles.size(); ++i) {
            const auto& t = hard.triangles.triangles[i];
            s.add_triangle(hard.triangles.positions[t.v[0]], hard.triangles.positions[t.v[1]],
                           hard.triangles.positions[t.v[2]], m);
        }
        check_scene_both(s, 22, "huge and degenerate triangles");
    }
    {  // spheres only, touching and nested
        Scene s;
        const auto m = s.add_material({});
        for (int x = 0; x < 5; ++x)
            for (int y = 0; y < 5; ++y) s.add_sphere({x, y, 0}, 0.5, m);
        s.add_sphere({2, 2, 0}, 3.0, m);
        s.add_sphere({2, 2, 0}, 0.25, m);
        check_scene_both(s, 23, "spheres only");
    }
    {  // one object
        Scene a;
        a.add_sphere({0, 0, 0}, 1.0, a.add_material({}));
        check_scene_both(a, 24, "one sphere");
        Scene b;
        b.add_triangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, b.add_material({}));
        check_scene_both(b, 25, "one triangle", false);  // a flat triangle: few rays hit it
    }
}

TEST_CASE("bvh traversal: a BVH over no objects is never hit", "[bvh][traversal]") {
    const WideBvh w = build_wide_bvh(BvhBuildInput{});
    const Bvh2 b2 = build_bvh2(BvhBuildInput{});
    const WideBvh unbuilt{};  // no nodes at all
    std::size_t visits = 0;
    auto visit = [&](const std::uint32_t*, std::uint32_t) {
        ++visits;
        return std::numeric_limits<float>::infinity();
    };
    for (const Ray<float>& ray : {Ray<float>({0, 0, 0}, {1, 0, 0}), Ray<float>({1, 2, 3}, {0, -1, 0})}) {
        traverse_bvh(w, ray, std::numeric_limits<float>::infinity(), visit);
        traverse_bvh(unbuilt, ray, std::numeric_limits<float>::infinity(), visit);
        traverse_bvh2(b2, ray, std::numeric_limits<float>::infinity(), visit);
    }
    CHECK(visits == 0);
}

// The conservative box test: a ray that touches a leaf's box only at its
// boundary (running along an edge or a face, or starting on a corner) visits
// that leaf; the leaves are handed over once each, and a visit that returns
// -inf ends the traversal.
TEST_CASE("bvh traversal: rays touching a box on its boundary visit its leaf", "[bvh][traversal]") {
    const PreparedScene p = test::prepare(test::bvh_hard_scene(9), Precision::Float);
    const std::vector<Aabb> boxes = test::tight_bounds(p.geometry_f);
    BvhBuildConfig config;
    config.max_leaf_size = 2;
    const WideBvh w = build_wide_bvh(BvhBuildInput{boxes, static_cast<std::uint32_t>(p.geometry_f.spheres.size())},
                                     config);
    std::mt19937 rng(10);
    std::size_t rays = 0, missed = 0, twice = 0, after_stop = 0;
    for (const WideBvhNode& node : w.nodes)
        for (int i = 0; i < kWideBvhWidth; ++i) {
            if (!node.is_leaf(i) || node.is_empty(i)) continue;
            const Aabb b = node.slot_box(i);
            const std::uint32_t* leaf = w.leaf_objects.data() + node.child[i];
            for (int k = 0; k < 6; ++k) {
                const int axis = k % 3, side = k / 3;
                // Along an edge (the other two coordinates on the box's planes), or
                // along a face (one of them on a plane, the other inside).
                glm::vec3 o(static_cast<float>(b.lo.x), static_cast<float>(b.lo.y), static_cast<float>(b.lo.z));
                const int u = (axis + 1) % 3, v = (axis + 2) % 3;
                o[u] = static_cast<float>(rng() & 1 ? b.hi[u] : b.lo[u]);
                o[v] = static_cast<float>(k < 3 ? (rng() & 1 ? b.hi[v] : b.lo[v]) : 0.5 * (b.lo[v] + b.hi[v]));
                o[axis] = static_cast<float>(side ? b.hi[axis] + 1.0 : b.lo[axis] - 1.0);
                glm::vec3 d(0.0f);
                d[axis] = side ? -1.0f : 1.0f;
                const glm::vec3 corner(static_cast<float>(b.hi.x), static_cast<float>(b.lo.y), static_cast<float>(b.hi.z));
                for (const Ray<float>& ray : {Ray<float>(o, d), Ray<float>(corner, glm::normalize(glm::vec3(rng() % 3 + 0.5f, -1.0f, 0.3f)))}) {
                    ++rays;
                    std::vector<const std::uint32_t*> seen;
                    traverse_bvh(w, ray, std::numeric_limits<float>::infinity(),
                                 [&](const std::uint32_t* ids, std::uint32_t) {
                                     seen.push_back(ids);
                                     return std::numeric_limits<float>::infinity();
                                 });
                    missed += std::find(seen.begin(), seen.end(), leaf) == seen.end();
                    std::sort(seen.begin(), seen.end());
                    twice += std::adjacent_find(seen.begin(), seen.end()) != seen.end();
                    std::size_t visits = 0;
                    traverse_bvh(w, ray, std::numeric_limits<float>::infinity(), [&](const std::uint32_t*, std::uint32_t) {
                        ++visits;
                        return -std::numeric_limits<float>::infinity();
                    });
                    after_stop += visits > 1;
                }
            }
        }
    INFO(rays << " rays");
    CHECK(rays > 500);
    CHECK(missed == 0);
    CHECK(twice == 0);
    CHECK(after_stop == 0);
}
