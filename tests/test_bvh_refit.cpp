// BVH refit: the same topology with the boxes of moved objects, checked
// against the new boxes and traced against brute force on the moved
// geometry; unchanged boxes give back the built BVH; bad input leaves the BVH
// as it was; the SAH ratio says when a rebuild is due.
#include "bvh_test_scenes.h"
#include "bvh_traversal_checks.h"

#include "bvh/bvh_build.h"
#include "bvh/bvh_check.h"
#include "bvh/bvh_refit.h"
#include "bvh/bvh_stats.h"

#include <kdrt/error.h>

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

using namespace kdrt;
using namespace kdrt::detail;

namespace {

// The scene with every vertex and sphere moved: a jitter of `jitter` and,
// for one object in `every`, a jump of `jump` (objects leave their neighbours).
Scene moved(const Scene& scene, double jitter, double jump, int every, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Scene s = scene;
    int k = 0;
    auto move = [&](glm::dvec3& p) {
        p += jitter * glm::dvec3(u(rng), u(rng), u(rng));
        if (++k % every == 0) p += jump * glm::dvec3(u(rng), u(rng), u(rng));
    };
    for (Sphere& sphere : s.spheres) move(sphere.center);
    for (glm::dvec3& p : s.triangles.positions) move(p);
    return s;
}

// The scene with every object moved whole to a random place in the scene's
// box: objects keep their size, leaves lose their neighbourhoods. Loose
// triangles (add_triangle) have their three vertices of their own.
Scene scattered(const Scene& scene, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-4.0, 4.0);
    Scene s = scene;
    for (Sphere& sphere : s.spheres) sphere.center = {u(rng), u(rng), u(rng)};
    for (std::size_t i = 0; i + 2 < s.triangles.positions.size(); i += 3) {
        const glm::dvec3 to{u(rng), u(rng), u(rng)}, shift = to - s.triangles.positions[i];
        for (std::size_t k = i; k < i + 3; ++k) s.triangles.positions[k] += shift;
    }
    return s;
}

}  // namespace

TEST_CASE("bvh refit: unchanged boxes give back the built BVH", "[bvh][refit]") {
    const PreparedScene p = test::prepare(test::bvh_hard_scene(1), Precision::Float);
    const std::vector<Aabb> boxes = p.object_bounds();
    const WideBvh built = build_wide_bvh(BvhBuildInput{boxes, static_cast<std::uint32_t>(p.geometry_f.spheres.size())});
    for (int threads : {1, 2, 4}) {
        WideBvh w = built;
        const BvhRefitResult r = refit_bvh(w, boxes, threads);
        CHECK(w == built);
        CHECK(r.sah_cost == built.build_sah_cost);
        CHECK(r.ratio() == 1.0);
        CHECK_FALSE(r.rebuild_due());
    }
}

TEST_CASE("bvh refit: moved geometry is traced as brute force traces it", "[bvh][refit]") {
    const Scene scene = test::bvh_hard_scene(2);
    const PreparedScene before = test::prepare(scene, Precision::Float);
    const std::uint32_t spheres = static_cast<std::uint32_t>(before.geometry_f.spheres.size());
    BvhBuildConfig config;
    config.max_leaf_size = 4;
    const WideBvh built = build_wide_bvh(BvhBuildInput{before.object_bounds(), spheres}, config);
    for (auto [jitter, jump] : {std::pair{0.05, 0.0}, std::pair{0.2, 3.0}}) {
        const Scene s = moved(scene, jitter, jump, 5, 7);
        for (Precision precision : {Precision::Float, Precision::Double}) {
            const PreparedScene after = test::prepare(s, precision);
            const std::vector<Aabb> boxes = after.object_bounds();
            WideBvh w = built;
            WideBvh other_threads = built;
            const BvhRefitResult r = refit_bvh(w, boxes);
            refit_bvh(other_threads, boxes, 1);
            CHECK(other_threads == w);
            INFO("jitter " << jitter << ", jump " << jump << ": SAH " << r.sah_cost << " against " << r.build_sah_cost);
            CHECK_NOTHROW(check_bvh(w, boxes));
            CHECK(w.leaf_objects == built.leaf_objects);  // the same topology
            CHECK(w.nodes.size() == built.nodes.size());
            CHECK(r.build_sah_cost == built.build_sah_cost);
            CHECK(r.sah_cost == bvh_sah_cost(w));
            if (jump > 0.0) CHECK(r.ratio() > 1.2);
            auto check = [&](const auto& g) {
                const auto rays = bvh_rays(g, after.bounds, w, 11);
                for (bool batched : {false, true}) {
                    const TraversalReport t = check_wide_bvh(g, w, rays, batched);
                    INFO(t.rays << " rays, " << t.hits << " hits; first mismatch: " << t.first);
                    CHECK(t.hits > t.rays / 10);
                    CHECK(t.mismatches == 0);
                    CHECK(t.blocked_mismatches == 0);
                }
            };
            if (precision == Precision::Double) check(after.geometry_d);
            else check(after.geometry_f);
        }
    }
}

TEST_CASE("bvh refit: the SAH ratio calls for a rebuild when objects scatter, not when they jitter", "[bvh][refit]") {
    // A wavy sheet of 2 x 40 x 40 loose triangles, as a tessellated surface is built.
    Scene scene;
    const auto m = scene.add_material({});
    auto at = [](int i, int j) { return glm::dvec3(0.2 * i - 4.0, 0.2 * j - 4.0, 0.3 * std::sin(0.5 * i) * std::cos(0.4 * j)); };
    for (int i = 0; i < 40; ++i)
        for (int j = 0; j < 40; ++j) {
            scene.add_triangle(at(i, j), at(i + 1, j), at(i + 1, j + 1), m);
            scene.add_triangle(at(i, j), at(i + 1, j + 1), at(i, j + 1), m);
        }
    const PreparedScene before = test::prepare(scene, Precision::Float);
    const WideBvh built = build_wide_bvh(BvhBuildInput{before.object_bounds(), 0});
    auto refit_to = [&](const Scene& s) {
        WideBvh w = built;
        return refit_bvh(w, test::prepare(s, Precision::Float).object_bounds());
    };
    // Every vertex moved by up to a tenth of an edge: the hierarchy still fits.
    const BvhRefitResult jitter = refit_to(moved(scene, 0.02, 0.0, 1, 5));
    INFO("jitter: SAH ratio " << jitter.ratio());
    CHECK(jitter.ratio() < 1.2);
    CHECK_FALSE(jitter.rebuild_due());
    // Every triangle moved whole across the sheet: each leaf spans it.
    const BvhRefitResult thrown = refit_to(scattered(scene, 6));
    INFO("scattered: SAH ratio " << thrown.ratio());
    CHECK(thrown.ratio() > 2 * kBvhRebuildSahRatio);
    CHECK(thrown.rebuild_due());
}

TEST_CASE("bvh refit: bad input is refused and the BVH left as it was", "[bvh][refit]") {
    std::vector<Aabb> boxes;
    for (int i = 0; i < 500; ++i) boxes.push_back({glm::dvec3(i, 0, 0), glm::dvec3(i + 0.5, 1, 1)});
    boxes[100] = Aabb{};  // no box when built: no leaf
    const WideBvh built = build_wide_bvh(BvhBuildInput{boxes, 0});
    auto refused = [&](const std::vector<Aabb>& given, const std::string& needle) {
        WideBvh w = built;
        try {
            refit_bvh(w, given);
            FAIL("refit accepted bad input: " << needle);
        } catch (const Error& e) {
            CHECK(e.code() == ErrorCode::InvalidArgument);
            CHECK(std::string(e.what()).find(needle) != std::string::npos);
        }
        CHECK(w == built);
    };
    refused(std::vector<Aabb>(boxes.begin(), boxes.end() - 1), "499 object boxes");
    std::vector<Aabb> nan_box = boxes;
    nan_box[7].lo.z = std::nan("");
    refused(nan_box, "object 7");
    std::vector<Aabb> huge = boxes;
    huge[8].hi.x = 1e39;
    refused(huge, "object 8");
    std::vector<Aabb> gained = boxes;
    gained[100] = {glm::dvec3(0), glm::dvec3(1)};
    refused(gained, "object 100 has a box now");
    WideBvh w = built;
    CHECK_THROWS_AS(refit_bvh(w, boxes, -1), Error);
    CHECK(w == built);

    // Every object in a leaf, two refused boxes: the smallest id is named and the BVH is left as it was.
    std::vector<Aabb> all_boxes = boxes;
    all_boxes[100] = {glm::dvec3(100, 0, 0), glm::dvec3(100.5, 1, 1)};
    const WideBvh all_built = build_wide_bvh(BvhBuildInput{all_boxes, 0});
    REQUIRE(all_built.leaf_objects.size() == all_boxes.size());
    for (std::size_t bad : {3u, 250u, 499u}) {
        const std::size_t other = (bad + 251) % 500;
        std::vector<Aabb> moved = all_boxes;
        for (Aabb& b : moved) b = {b.lo + glm::dvec3(0.25), b.hi + glm::dvec3(0.25)};
        moved[bad].hi.y = std::nan("");
        moved[other].lo.x = -1e39;
        WideBvh v = all_built;
        try {
            refit_bvh(v, moved);
            FAIL("refit accepted a NaN box");
        } catch (const Error& e) {  // the smallest refused id, whichever thread met it first
            CHECK(std::string(e.what()).find("object " + std::to_string(std::min(bad, other)) + " ") !=
                  std::string::npos);
        }
        CHECK(v == all_built);
    }

    // An object may lose its box: its leaf ignores it, and a leaf of such objects has the empty box.
    std::vector<Aabb> lost = boxes;
    for (int i = 0; i < 500; ++i)
        if (i % 3 == 0) lost[i] = Aabb{};
    WideBvh shrunk = built;
    CHECK_NOTHROW(refit_bvh(shrunk, lost));
    CHECK_NOTHROW(check_bvh(shrunk, lost));
}

TEST_CASE("bvh refit: a scene's leaf boxes, taken as one union, refit as its objects' boxes do", "[bvh][refit]") {
    const Scene scene = test::bvh_hard_scene(3);
    const PreparedScene before = test::prepare(scene, Precision::Float);
    const std::uint32_t spheres = static_cast<std::uint32_t>(before.geometry_f.spheres.size());
    REQUIRE(spheres > 0);
    BvhBuildConfig config;
    config.max_leaf_size = 6;
    const WideBvh built = build_wide_bvh(BvhBuildInput{before.object_bounds(), spheres}, config);
    const PreparedScene after = test::prepare(moved(scene, 0.1, 2.0, 7, 3), Precision::Float);
    const std::vector<Aabb> boxes = after.object_bounds();

    // Any set of objects, spheres and triangles mixed: the union of their boxes, bit for bit.
    std::mt19937 rng(5);
    std::uniform_int_distribution<std::uint32_t> any_id(0, after.geometry_f.object_count() - 1);
    for (int trial = 0; trial < 200; ++trial) {
        std::vector<std::uint32_t> ids(1 + trial % 9);
        for (std::uint32_t& id : ids) id = any_id(rng);
        Aabb expected;
        for (std::uint32_t id : ids) expected.extend(boxes[id]);
        CHECK(after.objects_bound(ids) == expected);
    }

    // The refit from leaf boxes is the refit from the objects' boxes, for any thread count.
    WideBvh from_objects = built;
    const BvhRefitResult r = refit_bvh(from_objects, boxes);
    for (int threads : {1, 2}) {
        WideBvh from_leaves = built;
        const BvhRefitResult l = refit_bvh(
            from_leaves, BvhLeafBox([&](std::span<const std::uint32_t> ids) { return after.objects_bound(ids); }),
            threads);
        CHECK(from_leaves == from_objects);
        CHECK(l.sah_cost == r.sah_cost);
    }
    CHECK_NOTHROW(check_bvh(from_objects, boxes));
}

TEST_CASE("bvh refit: a leaf box refused names its smallest refused object, and the BVH is left as it was",
          "[bvh][refit]") {
    // Smaller ids further along x: a walk that met the larger refused id first and kept it would be caught.
    std::vector<Aabb> boxes;
    for (int i = 0; i < 400; ++i) boxes.push_back({glm::dvec3(399 - i, 0, 0), glm::dvec3(399.5 - i, 1, 1)});
    const WideBvh built = build_wide_bvh(BvhBuildInput{boxes, 0});
    for (std::uint32_t bad : {0u, 177u, 399u}) {
        // A leaf's union is NaN when it holds `bad` or `bad` + 101; alone, each of them is NaN.
        auto refused = [&](std::uint32_t id) { return id == bad || id == (bad + 101) % 400; };
        const BvhLeafBox leaf_box = [&](std::span<const std::uint32_t> ids) {
            Aabb box;
            for (std::uint32_t id : ids) {
                if (refused(id)) return Aabb{glm::dvec3(std::nan("")), glm::dvec3(1)};
                box.extend({boxes[id].lo + glm::dvec3(0.1), boxes[id].hi + glm::dvec3(0.1)});
            }
            return box;
        };
        WideBvh w = built;
        try {
            refit_bvh(w, leaf_box);
            FAIL("refit accepted a NaN leaf box");
        } catch (const Error& e) {
            const std::uint32_t smallest = std::min(bad, (bad + 101) % 400);
            CHECK(std::string(e.what()).find("object " + std::to_string(smallest) + " ") != std::string::npos);
        }
        CHECK(w == built);
    }
}

TEST_CASE("bvh refit: a leaf box that throws leaves the BVH as it was", "[bvh][refit]") {
    std::vector<Aabb> boxes;
    for (int i = 0; i < 300; ++i) boxes.push_back({glm::dvec3(i, 0, 0), glm::dvec3(i + 0.5, 1, 1)});
    const WideBvh built = build_wide_bvh(BvhBuildInput{boxes, 0});
    for (std::uint32_t thrower : {0u, 150u, 299u}) {
        const BvhLeafBox leaf_box = [&](std::span<const std::uint32_t> ids) {
            Aabb box;
            for (std::uint32_t id : ids) {
                if (id == thrower) throw std::runtime_error("leaf box failed");
                box.extend({boxes[id].lo + glm::dvec3(0.2), boxes[id].hi + glm::dvec3(0.2)});
            }
            return box;
        };
        WideBvh w = built;
        CHECK_THROWS_AS(refit_bvh(w, leaf_box), std::runtime_error);
        CHECK(w == built);
    }
}
