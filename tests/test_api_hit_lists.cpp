// kdrt::count_hits / kdrt::all_hits on the cpu device: every traversal and
// both precisions against testing every object (each triangle once, each
// sphere root in the window), on trees that reference objects from several
// leaves; and the geometry and primitive ids every query reports.
#include "api_test_scenes.h"
#include "walks.h"

#include "cpu/intersect.h"
#include "scene/prepared_scene.h"

#include <kdrt/error.h>
#include <kdrt/ray_query.h>

#include <catch2/catch.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

using namespace kdrt;

namespace {

QueryRay query(glm::dvec3 o, glm::dvec3 d, float t_min = 0.0f, float t_max = std::numeric_limits<float>::infinity()) {
    return {{float(o.x), float(o.y), float(o.z)}, t_min, {float(d.x), float(d.y), float(d.z)}, t_max};
}

// Every hit by testing every object: (internal id, query t) pairs, sorted.
template <class Real>
std::vector<std::pair<double, std::uint32_t>> every_hit(const detail::PreparedScene& p, const QueryRay& q) {
    using Vec = glm::vec<3, Real>;
    const glm::dvec3 o(q.origin[0], q.origin[1], q.origin[2]), d(q.direction[0], q.direction[1], q.direction[2]);
    const double len = glm::length(d);
    const detail::Ray<Real> ray(Vec(o - p.frame_origin), Vec(d / len));
    const auto& g = p.geometry<Real>();
    std::vector<std::pair<double, std::uint32_t>> hits;
    auto consider = [&](std::uint32_t id, Real t_unit) {
        const double t = double(t_unit) / len;
        if (t_unit > 0 && t > q.t_min && t <= q.t_max) hits.push_back({double(float(t)), id});
    };
    for (std::uint32_t i = 0; i < g.spheres.size(); ++i) {
        Real t0, t1;
        if (!detail::sphere_roots(ray, g.spheres[i].center, g.spheres[i].radius, t0, t1)) continue;
        consider(i, t0);
        consider(i, t1);
    }
    for (std::uint32_t i = 0; i < g.triangles.size(); ++i) {
        const auto& t = g.triangles[i];
        Real th, b1, b2;
        if (detail::intersect_triangle(ray, t.v0, t.v1, t.v2, th, b1, b2))
            consider(std::uint32_t(g.spheres.size()) + i, th);
    }
    std::sort(hits.begin(), hits.end());
    return hits;
}

std::vector<QueryRay> random_rays(const glm::dvec3& c, std::uint32_t seed, int n) {
    std::mt19937 rng(seed);
    auto rnd = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
    std::vector<QueryRay> rays;
    for (int i = 0; i < n; ++i) {
        const glm::dvec3 o = c + glm::dvec3(rnd(-7, 7), rnd(-7, 7), rnd(-7, 7));
        const glm::dvec3 t = c + glm::dvec3(rnd(-4, 4), rnd(-4, 4), rnd(-4, 4));
        const float t_min = i % 5 == 0 ? float(rnd(0, 0.5)) : 0.0f;
        const float t_max = i % 7 == 0 ? float(rnd(0.3, 1.0)) : std::numeric_limits<float>::infinity();
        rays.push_back(query(o, (t - o) * rnd(0.2, 3.0), t_min, t_max));
    }
    // Along the grid's shared edges and through its vertices (the grid lies at z = 2).
    for (int x = -3; x <= 3; ++x) rays.push_back(query(c + glm::dvec3(x, 0.5, -6), {0, 0, 1}));
    for (int x = -3; x <= 3; ++x) rays.push_back(query(c + glm::dvec3(x, x * 0.5, -6), {0, 0, 1}));
    return rays;
}

}  // namespace

TEST_CASE("api: count_hits and all_hits equal testing every object, each object once", "[api]") {
    const Scene scene = kdrt_test::api_scene(7);
    const Device device = Device::open("cpu");
    for (Precision precision : {Precision::Float, Precision::Double})
        for (const kdrt_test::Walk walk : kdrt_test::kAllWalks) {
            CAPTURE(walk, to_string(precision));
            CommitOptions options;
            walk.apply(options);
            options.accuracy.precision = precision;
            options.tree.traversal_cost = 0.05;  // deep trees: objects in several leaves
            const CommittedScene committed = CommittedScene::commit(device, scene, options);
            if (walk.traversal != Traversal::None && walk.accel == Accel::KdTree)
                REQUIRE(committed.tree()->leaf_objects.size() > committed.tree()->object_count);
            const detail::PreparedScene p = detail::prepare_scene(scene, options);
            const std::vector<QueryRay> rays = random_rays(p.frame_origin, 11, 400);
            std::vector<std::uint32_t> counts(rays.size());
            count_hits(committed, rays, counts);
            const RayHitLists lists = all_hits(committed, rays);
            REQUIRE(lists.ray_splits.size() == rays.size() + 1);
            REQUIRE(lists.ray_splits.back() == lists.hits.size());
            std::size_t several = 0;  // rays with more than one hit
            for (std::size_t i = 0; i < rays.size(); ++i) {
                CAPTURE(i);
                const auto expected = precision == Precision::Float ? every_hit<float>(p, rays[i])
                                                                    : every_hit<double>(p, rays[i]);
                REQUIRE(counts[i] == expected.size());
                REQUIRE(lists.ray_splits[i + 1] - lists.ray_splits[i] == expected.size());
                for (std::size_t k = 0; k < expected.size(); ++k) {
                    const QueryHit& h = lists.hits[lists.ray_splits[i] + k];
                    REQUIRE(h.object == p.public_id(expected[k].second));
                    REQUIRE(h.t == float(expected[k].first));
                    if (k > 0) REQUIRE(lists.hits[lists.ray_splits[i] + k - 1].t <= h.t);
                }
                several += expected.size() > 1 ? 1 : 0;
            }
            REQUIRE(several >= 20);  // the lists are lists

            // Counted once per geometry, by the counting pass and by the merged lists alike.
            std::vector<std::uint32_t> once(rays.size());
            count_hits(committed, rays, once, CoincidentHits::OncePerGeometry);
            const RayHitLists merged = all_hits(committed, rays, CoincidentHits::OncePerGeometry);
            for (std::size_t i = 0; i < rays.size(); ++i) {
                CAPTURE(i);
                REQUIRE(once[i] == merged.ray_splits[i + 1] - merged.ray_splits[i]);
                REQUIRE(once[i] <= counts[i]);
            }
        }
}

TEST_CASE("api: a ray through a closed mesh counts its entry and exit, a ray from inside one", "[api]") {
    Scene scene;
    Mesh box;  // the unit cube, 12 triangles
    for (int i = 0; i < 8; ++i) box.positions.push_back({double(i & 1), double((i >> 1) & 1), double((i >> 2) & 1)});
    const std::uint32_t faces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                        {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    for (const auto& f : faces) box.triangles.push_back({{f[0], f[1], f[2]}});
    scene.add_mesh(box);  // no materials: a query-only scene
    const CommittedScene committed = CommittedScene::commit(Device::open("cpu"), scene);
    const std::vector<QueryRay> rays = {query({0.3, 0.4, -2}, {0, 0, 1}), query({0.3, 0.4, 0.5}, {0, 0, 1}),
                                        query({0.3, 0.4, 2}, {0, 0, 1}), query({0.3, 0.4, 0.5}, {0.1, 0.2, -1})};
    std::vector<std::uint32_t> counts(rays.size());
    count_hits(committed, rays, counts);
    CHECK(counts == std::vector<std::uint32_t>{2, 1, 0, 1});

    // Through the diagonals the z faces' two triangles share: each triangle,
    // or each geometry once (Open3D's rule), which keeps the parity.
    const std::vector<QueryRay> edge = {query({0.5, 0.5, -2}, {0, 0, 1}), query({0.25, 0.75, 0.5}, {0, 0, 1})};
    std::vector<std::uint32_t> each(2), once(2);
    count_hits(committed, edge, each);
    count_hits(committed, edge, once, CoincidentHits::OncePerGeometry);
    CHECK(each == std::vector<std::uint32_t>{4, 2});
    CHECK(once == std::vector<std::uint32_t>{2, 1});
    const RayHitLists lists = all_hits(committed, edge, CoincidentHits::OncePerGeometry);
    REQUIRE(lists.ray_splits == std::vector<std::uint64_t>{0, 2, 3});
    CHECK(lists.hits[0].t == 2.0f);
    CHECK(lists.hits[1].t == 3.0f);
    CHECK(lists.hits[2].t == 0.5f);

    // A second box on the first: coincident hits of two geometries both count,
    // in a new commit and after update() of one that counted a box alone.
    CommittedScene updated = CommittedScene::commit(Device::open("cpu"), scene);
    count_hits(updated, edge, once, CoincidentHits::OncePerGeometry);
    CHECK(once == std::vector<std::uint32_t>{2, 1});
    scene.add_mesh(box);
    const CommittedScene twice = CommittedScene::commit(Device::open("cpu"), scene);
    count_hits(twice, edge, once, CoincidentHits::OncePerGeometry);
    CHECK(once == std::vector<std::uint32_t>{4, 2});
    updated.update(scene);
    count_hits(updated, edge, once, CoincidentHits::OncePerGeometry);
    CHECK(once == std::vector<std::uint32_t>{4, 2});
}

TEST_CASE("api: hits name the geometry of each add_* call and the primitive within it", "[api]") {
    Scene scene;
    Mesh quad;  // z = 0, two triangles
    quad.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    quad.triangles = {{{0, 1, 2}}, {{0, 2, 3}}};
    scene.add_sphere({5, 5, 0}, 0.5, 0);                                 // geometry 0
    REQUIRE(scene.geometry_count() == 1);
    scene.add_mesh(quad);                                                // geometry 1
    Mesh moved = quad;
    for (auto& v : moved.positions) v.z = 1;
    scene.add_mesh(moved);                                               // geometry 2
    scene.add_spheres({{{-5, 0, 0}, 0.5, 0}, {{-7, 0, 0}, 0.5, 0}});     // geometry 3
    scene.add_sphere({9, 9, 0}, 0.5, 0);                                 // geometry 4
    REQUIRE(scene.geometry_count() == 5);
    const CommittedScene committed = CommittedScene::commit(Device::open("cpu"), scene);
    const std::vector<QueryRay> rays = {query({0.75, 0.25, -1}, {0, 0, 1}), query({0.25, 0.75, 2}, {0, 0, -1}),
                                        query({-7, 0, -3}, {0, 0, 1}), query({9, 9, -3}, {0, 0, 1}),
                                        query({20, 20, -3}, {0, 0, 1})};
    std::vector<QueryHit> hits(rays.size());
    intersect(committed, rays, hits);
    auto named = [](const QueryHit& h) { return std::vector<std::uint32_t>{h.object, h.geometry, h.primitive}; };
    CHECK(named(hits[0]) == std::vector<std::uint32_t>{1, 1, 0});
    CHECK(named(hits[1]) == std::vector<std::uint32_t>{4, 2, 1});
    CHECK(named(hits[2]) == std::vector<std::uint32_t>{6, 3, 1});
    CHECK(named(hits[3]) == std::vector<std::uint32_t>{7, 4, 0});
    CHECK(named(hits[4]) == std::vector<std::uint32_t>{KDRT_NO_HIT, KDRT_NO_HIT, KDRT_NO_HIT});
    const RayHitLists lists = all_hits(committed, std::span(rays).first(2));
    REQUIRE(lists.hits.size() == 4);  // each ray crosses both quads
    CHECK(named(lists.hits[0]) == std::vector<std::uint32_t>{1, 1, 0});
    CHECK(named(lists.hits[1]) == std::vector<std::uint32_t>{3, 2, 0});
    CHECK(named(lists.hits[2]) == std::vector<std::uint32_t>{4, 2, 1});
    CHECK(named(lists.hits[3]) == std::vector<std::uint32_t>{2, 1, 1});
}

TEST_CASE("api: count_hits and closest_points refuse spans of other sizes", "[api]") {
    const Scene scene = kdrt_test::api_scene(3);
    const CommittedScene committed = CommittedScene::commit(Device::open("cpu"), scene);
    std::vector<QueryRay> rays(3);
    std::vector<std::uint32_t> counts(2);
    CHECK_THROWS_AS(count_hits(committed, rays, counts), Error);
    std::vector<std::array<float, 3>> points(3);
    std::vector<ClosestPoint> out(4);
    CHECK_THROWS_AS(closest_points(committed, points, out), Error);
    CommittedScene moved = committed;
    CommittedScene gone = std::move(moved);
    CHECK_THROWS_AS(count_hits(moved, rays, std::span(counts).first(0)), Error);
}
