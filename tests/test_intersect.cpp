// Ray/sphere and ray/triangle tests of the C++ reference (cpu/intersect.h).
#include "cpu/intersect.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>

using namespace kdrt::detail;
using Vec = glm::vec3;

namespace {

Ray<float> ray(Vec o, Vec d, std::int32_t ignore = kNoObject) { return Ray<float>(o, glm::normalize(d), ignore); }

bool hit_sphere(const Ray<float>& r, Vec c, float radius, float& t, std::int32_t id = 0) {
    return intersect_sphere(r, id, c, radius, t);
}

}  // namespace

TEST_CASE("sphere: hits, misses and the near root", "[intersect]") {
    float t = 0;
    REQUIRE(hit_sphere(ray({0, 0, -5}, {0, 0, 1}), {0, 0, 0}, 1.0f, t));
    CHECK(t == Approx(4.0f));
    CHECK_FALSE(hit_sphere(ray({0, 2, -5}, {0, 0, 1}), {0, 0, 0}, 1.0f, t));
    CHECK_FALSE(hit_sphere(ray({0, 0, 5}, {0, 0, 1}), {0, 0, 0}, 1.0f, t));  // sphere behind the ray
}

TEST_CASE("sphere: a ray from inside hits the far side", "[intersect]") {
    float t = 0;
    REQUIRE(hit_sphere(ray({0.2f, 0, 0}, {1, 0, 0}), {0, 0, 0}, 1.0f, t));
    CHECK(t == Approx(0.8f));
    REQUIRE(hit_sphere(ray({0, 0, 0}, {0, -1, 0}), {0, 0, 0}, 2.0f, t));
    CHECK(t == Approx(2.0f));
}

TEST_CASE("sphere: grazing rays", "[intersect]") {
    float t = 0;
    // Tangent to the sphere: the discriminant is zero, a hit at the touching point.
    REQUIRE(hit_sphere(ray({1, 0, -5}, {0, 0, 1}), {0, 0, 0}, 1.0f, t));
    CHECK(t == Approx(5.0f));
    CHECK_FALSE(hit_sphere(ray({1.0001f, 0, -5}, {0, 0, 1}), {0, 0, 0}, 1.0f, t));
}

TEST_CASE("sphere: the careful test survives a far-away small sphere", "[intersect]") {
    // Radius 1e-3 at distance 1e4: the textbook b^2 - c loses all digits in float.
    float t = 0;
    REQUIRE(hit_sphere(ray({0, 0, -1e4f}, {0, 0, 1}), {0, 0, 0}, 1e-3f, t));
    CHECK(t == Approx(1e4f - 1e-3f).epsilon(1e-6));
    REQUIRE(hit_sphere(ray({0, 0.0009f, -1e4f}, {0, 0, 1}), {0, 0, 0}, 1e-3f, t));
}

TEST_CASE("sphere: a ray leaving its own sphere", "[intersect]") {
    float t = 0;
    // Outward from the surface: never the same sphere again.
    CHECK_FALSE(hit_sphere(ray({0, 0, -1.00001f}, {0, 0.3f, -1}, 7), {0, 0, 0}, 1.0f, t, 7));
    // Inward (refraction): the far side, never the near root at ~0.
    REQUIRE(hit_sphere(ray({0, 0, -0.99999f}, {0, 0, 1}, 7), {0, 0, 0}, 1.0f, t, 7));
    CHECK(t == Approx(2.0f).epsilon(1e-4));
}

TEST_CASE("triangle: hits, misses, both faces, degenerate", "[intersect]") {
    const Vec a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
    float t, b1, b2;
    REQUIRE(intersect_triangle(ray({0.25f, 0.25f, -1}, {0, 0, 1}), a, b, c, t, b1, b2));
    CHECK(t == Approx(1.0f));
    CHECK(b1 == Approx(0.25f));
    CHECK(b2 == Approx(0.25f));
    REQUIRE(intersect_triangle(ray({0.25f, 0.25f, 1}, {0, 0, -1}), a, b, c, t, b1, b2));  // back face
    CHECK_FALSE(intersect_triangle(ray({0.75f, 0.75f, -1}, {0, 0, 1}), a, b, c, t, b1, b2));
    CHECK_FALSE(intersect_triangle(ray({0.25f, 0.25f, 1}, {0, 0, 1}), a, b, c, t, b1, b2));  // behind
    // Zero area: never hit.
    CHECK_FALSE(intersect_triangle(ray({0.5f, 0, -1}, {0, 0, 1}), a, b, Vec{2, 0, 0}, t, b1, b2));
    CHECK_FALSE(intersect_triangle(ray({0, 0, -1}, {0, 0, 1}), a, a, a, t, b1, b2));
    // A ray in the triangle's plane: no hit.
    CHECK_FALSE(intersect_triangle(ray({-1, 0.25f, 0}, {1, 0, 0}), a, b, c, t, b1, b2));
}

// A fan of triangles around a centre vertex, not axis-aligned and not planar,
// so edge functions come out of real rounding. Rays aimed exactly at the
// shared vertex, at points on the shared edges and at random points must hit
// at least one triangle: no cracks.
TEST_CASE("triangle: a fan is watertight at shared edges and vertices", "[intersect]") {
    const int n = 7;
    const Vec centre{0.3f, -0.2f, 0.1f};
    std::vector<Vec> rim;
    for (int i = 0; i < n; ++i) {
        double a = 2.0 * 3.14159265358979 * i / n + 0.1;
        rim.push_back(Vec(static_cast<float>(std::cos(a)), static_cast<float>(std::sin(a)),
                          0.2f * static_cast<float>(std::sin(3 * a))) + centre);
    }
    std::mt19937 rng(1234);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    int rays = 0;
    auto hits = [&](const Ray<float>& r) {
        int count = 0;
        for (int i = 0; i < n; ++i) {
            float t, b1, b2;
            count += intersect_triangle(r, centre, rim[i], rim[(i + 1) % n], t, b1, b2) ? 1 : 0;
        }
        return count;
    };
    for (int k = 0; k < 2000; ++k) {
        const Vec origin = Vec(u(rng), u(rng), 3.0f + u(rng));
        // At the shared vertex.
        ++rays;
        CHECK(hits(Ray<float>(origin, glm::normalize(centre - origin))) >= 1);
        // At a point on a shared edge (centre -> rim[i]), as close as float gets.
        const int i = k % n;
        const float s = 0.05f + 0.9f * (0.5f + 0.5f * u(rng));
        const Vec on_edge = centre + s * (rim[i] - centre);
        ++rays;
        CHECK(hits(Ray<float>(origin, glm::normalize(on_edge - origin))) >= 1);
    }
    // Axis-parallel rays straight down through the edges too.
    for (int i = 0; i < n; ++i) {
        const Vec on_edge = centre + 0.5f * (rim[i] - centre);
        CHECK(hits(Ray<float>(Vec(on_edge.x, on_edge.y, 5.0f), Vec(0, 0, -1))) >= 1);
        ++rays;
    }
    CHECK(rays > 4000);
}

TEST_CASE("triangle: double precision agrees with float on an easy hit", "[intersect]") {
    const glm::dvec3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
    double t, b1, b2;
    Ray<double> r({0.25, 0.25, -1}, {0, 0, 1});
    REQUIRE(intersect_triangle(r, a, b, c, t, b1, b2));
    CHECK(t == 1.0);
}
