// kdrt::closest_points on the cpu device: the kd-tree's nearest-first search
// against testing every object, on random points near and far, inside
// spheres and on the grid's shared edges; the closest point on a triangle in
// each of its Voronoi regions.
#include "api_test_scenes.h"

#include "cpu/closest_point.h"
#include "scene/prepared_scene.h"

#include <kdrt/error.h>
#include <kdrt/ray_query.h>

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

using namespace kdrt;

TEST_CASE("closest point on a triangle: vertex, edge and face regions", "[api]") {
    using detail::closest_on_triangle;
    const glm::dvec3 a(0, 0, 0), b(2, 0, 0), c(0, 2, 0);
    double v, w;
    CHECK(closest_on_triangle({-1, -1, 3}, a, b, c, v, w) == a);
    CHECK(closest_on_triangle({3, -1, 0}, a, b, c, v, w) == b);
    CHECK((v == 1.0 && w == 0.0));
    CHECK(closest_on_triangle({1, -5, 1}, a, b, c, v, w) == glm::dvec3(1, 0, 0));
    CHECK((v == 0.5 && w == 0.0));
    CHECK(closest_on_triangle({2, 2, 0}, a, b, c, v, w) == glm::dvec3(1, 1, 0));
    CHECK((v == 0.5 && w == 0.5));
    CHECK(closest_on_triangle({0.5, 0.5, -4}, a, b, c, v, w) == glm::dvec3(0.5, 0.5, 0));
    CHECK((v == 0.25 && w == 0.25));
}

TEST_CASE("api: closest_points equal testing every object", "[api]") {
    const Scene scene = kdrt_test::api_scene(5);
    const Device device = Device::open("cpu");
    for (int structure = 0; structure < 3; ++structure) {
        // Every object, the kd-tree, the BVH.
        const Traversal traversal = structure == 0 ? Traversal::None : Traversal::Stack;
        CAPTURE(to_string(traversal), structure);
        CommitOptions options;
        options.traversal = traversal;
        options.accel = structure == 2 ? Accel::Bvh : Accel::KdTree;
        options.tree.traversal_cost = 0.05;
        const CommittedScene committed = CommittedScene::commit(device, scene, options);
        const detail::PreparedScene p = detail::prepare_scene(scene, options);
        std::mt19937 rng(17);
        auto rnd = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
        std::vector<std::array<float, 3>> points;
        for (int i = 0; i < 500; ++i) {
            const double r = i % 3 == 0 ? 30.0 : 6.0;
            const glm::dvec3 q = p.frame_origin + glm::dvec3(rnd(-r, r), rnd(-r, r), rnd(-r, r));
            points.push_back({float(q.x), float(q.y), float(q.z)});
        }
        for (const Sphere& s : scene.spheres) points.push_back({float(s.center.x), float(s.center.y), float(s.center.z)});
        for (int x = -3; x <= 3; ++x) {
            const glm::dvec3 q = p.frame_origin + glm::dvec3(x, 0.25, 2.5);  // above the grid's edges
            points.push_back({float(q.x), float(q.y), float(q.z)});
        }
        std::vector<ClosestPoint> out(points.size());
        closest_points(committed, points, out);
        const auto& g = p.geometry<float>();
        for (std::size_t i = 0; i < points.size(); ++i) {
            CAPTURE(i);
            const glm::dvec3 q = glm::dvec3(points[i][0], points[i][1], points[i][2]) - p.frame_origin;
            detail::NearestPoint best;
            for (std::uint32_t id = 0; id < g.object_count(); ++id) detail::test_nearest(g, q, id, best);
            REQUIRE(out[i].distance == Approx(std::sqrt(best.d2)).epsilon(1e-6));
            const glm::dvec3 expected = best.point + p.frame_origin;
            for (int a = 0; a < 3; ++a) REQUIRE(out[i].point[a] == Approx(expected[a]).margin(1e-4));
            REQUIRE(out[i].object == p.public_id(best.id));
        }
    }
}

TEST_CASE("api: closest_points of an empty scene and of non-finite points are none", "[api]") {
    Scene empty;
    const CommittedScene committed = CommittedScene::commit(Device::open("cpu"), empty);
    const std::vector<std::array<float, 3>> points = {{{0, 0, 0}}};
    std::vector<ClosestPoint> out(1);
    closest_points(committed, points, out);
    CHECK(out[0].distance == std::numeric_limits<float>::infinity());
    CHECK(out[0].geometry == KDRT_NO_HIT);

    Scene one;
    one.add_sphere({0, 0, 0}, 1.0, 0);
    const CommittedScene sphere = CommittedScene::commit(Device::open("cpu"), one);
    const std::vector<std::array<float, 3>> odd = {{{std::nanf(""), 0, 0}}, {{0, 0, 3}}};
    std::vector<ClosestPoint> out2(2);
    closest_points(sphere, odd, out2);
    CHECK(out2[0].object == KDRT_NO_HIT);
    CHECK(out2[1].distance == 2.0f);
    CHECK(out2[1].point[2] == 1.0f);
    CHECK(out2[1].normal[2] == 1.0f);
}
