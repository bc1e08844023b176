// The BVH tests' scenes: the hard cases, prepared, and their objects' boxes.
#pragma once

#include "scene/prepared_scene.h"

#include <kdrt/scene.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace kdrt::test {

// Spheres and triangles with the hard cases, inside [-4, 4]^3 times `scale`:
// random small triangles and spheres, axis-aligned unit quads on a grid (edges
// and vertices shared, coplanar), walls through the same planes, spheres
// touching each other, degenerate triangles (a point, collinear, repeated
// vertices), and a few long slivers.
inline Scene bvh_hard_scene(std::uint32_t seed, double scale = 1.0) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-4.0, 4.0), small(0.05, 0.6);
    std::uniform_int_distribution<int> grid(-4, 4);
    Scene s;
    const auto m = s.add_material({});
    auto v = [&](double x, double y, double z) { return glm::dvec3(x, y, z) * scale; };
    for (int i = 0; i < 20; ++i) s.add_sphere(v(u(rng), u(rng), u(rng)), small(rng) * scale, m);
    for (int i = 0; i < 6; ++i) s.add_sphere(v(grid(rng), grid(rng), grid(rng)), 0.5 * scale, m);
    for (int i = 0; i < 60; ++i) {
        const glm::dvec3 a{u(rng), u(rng), u(rng)};
        const glm::dvec3 b = a + glm::dvec3(small(rng), small(rng), u(rng) * 0.2);
        const glm::dvec3 c = a + glm::dvec3(-small(rng), small(rng), small(rng));
        s.add_triangle(a * scale, b * scale, c * scale, m);
    }
    for (int x = -3; x < 3; ++x)
        for (int y = -3; y < 3; ++y) {
            s.add_triangle(v(x, y, 1), v(x + 1, y, 1), v(x + 1, y + 1, 1), m);
            s.add_triangle(v(x, y, 1), v(x + 1, y + 1, 1), v(x, y + 1, 1), m);
        }
    for (int i = -2; i < 2; ++i) {
        s.add_triangle(v(0, i, -2), v(0, i + 1, -2), v(0, i + 1, 2), m);
        s.add_triangle(v(i, 2, -2), v(i + 1, 2, 2), v(i, 2, 2), m);
    }
    s.add_triangle(v(1, 1, 1), v(1, 1, 1), v(1, 1, 1), m);
    s.add_triangle(v(0, 0, 0), v(1, 1, 1), v(2, 2, 2), m);
    s.add_triangle(v(-1, 0, 0), v(-1, 0, 0), v(-1, 1, 0), m);
    for (int i = 0; i < 4; ++i)  // slivers across the whole scene
        s.add_triangle(v(-4, u(rng), u(rng)), v(4, u(rng), u(rng)), v(4, u(rng) + 0.01, u(rng)), m);
    return s;
}

inline detail::PreparedScene prepare(const Scene& scene, Precision precision) {
    CommitOptions o;
    o.accuracy.precision = precision;
    return detail::prepare_scene(scene, o);
}

// The objects' boxes with no padding (PreparedScene::object_bounds pads them):
// the vertices' own bounds and the spheres' centre +- radius, rounded outward.
// A BVH over these leaves no margin to the box test.
template <class Real>
std::vector<Aabb> tight_bounds(const detail::SceneGeometry<Real>& g) {
    std::vector<Aabb> out;
    constexpr double inf = std::numeric_limits<double>::infinity();
    for (const auto& s : g.spheres) {
        Aabb b;
        for (int a = 0; a < 3; ++a) {
            b.lo[a] = std::nextafter(double(s.center[a]) - double(s.radius), -inf);
            b.hi[a] = std::nextafter(double(s.center[a]) + double(s.radius), inf);
        }
        out.push_back(b);
    }
    for (const auto& t : g.triangles) {
        Aabb b;
        b.extend(glm::dvec3(t.v0));
        b.extend(glm::dvec3(t.v1));
        b.extend(glm::dvec3(t.v2));
        out.push_back(b);
    }
    return out;
}

}  // namespace kdrt::test

