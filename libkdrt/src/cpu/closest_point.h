// Closest points on the scene's primitives to a query point, in double from
// the working geometry: on a triangle by its Voronoi regions (Ericson,
// Real-Time Collision Detection, 5.1.5), on a sphere along the ray from its
// centre. The query's nearest-first search is traverse_nearest.h.
#pragma once

#include "cpu/cpu_isa.h"
#include "scene/prepared_scene.h"

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <cstdint>
#include <limits>

namespace kdrt::detail::inline KDRT_CPU_ISA {

// The closest point found so far: squared distance, object (internal id), the
// point and, on a triangle, its barycentrics of v1 and v2.
struct NearestPoint {
    double d2 = std::numeric_limits<double>::infinity();
    std::uint32_t id = 0xFFFFFFFFu;
    glm::dvec3 point{0.0};
    double b1 = 0.0, b2 = 0.0;

    bool valid() const { return id != 0xFFFFFFFFu; }
    // Nearer first, then the lower id: the same answer whatever the search order.
    bool closer_than(const NearestPoint& o) const { return d2 < o.d2 || (d2 == o.d2 && id < o.id); }
};

// The point of triangle (a, b, c) closest to p, with its barycentrics of b and c.
inline glm::dvec3 closest_on_triangle(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b,
                                      const glm::dvec3& c, double& v_out, double& w_out) {
    const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) { v_out = 0.0; w_out = 0.0; return a; }
    const glm::dvec3 bp = p - b;
    const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) { v_out = 1.0; w_out = 0.0; return b; }
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        const double v = d1 / (d1 - d3);
        v_out = v; w_out = 0.0;
        return a + v * ab;
    }
    const glm::dvec3 cp = p - c;
    const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) { v_out = 0.0; w_out = 1.0; return c; }
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        const double w = d2 / (d2 - d6);
        v_out = 0.0; w_out = w;
        return a + w * ac;
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        v_out = 1.0 - w; w_out = w;
        return b + w * (c - b);
    }
    const double denom = 1.0 / (va + vb + vc);
    const double v = vb * denom, w = vc * denom;
    v_out = v; w_out = w;
    return a + ab * v + ac * w;
}

// Object `id`'s closest point to p, into `best` when it is nearer.
template <class Real>
inline void test_nearest(const SceneGeometry<Real>& g, const glm::dvec3& p, std::uint32_t id, NearestPoint& best) {
    NearestPoint n;
    n.id = id;
    if (id < g.spheres.size()) {
        const auto& s = g.spheres[id];
        const glm::dvec3 c(s.center);
        const glm::dvec3 d = p - c;
        const double len = glm::length(d);
        // A query at the centre is equally near every point: take the one towards +x.
        const glm::dvec3 dir = len > 0.0 ? d / len : glm::dvec3(1.0, 0.0, 0.0);
        n.point = c + static_cast<double>(s.radius) * dir;
    } else {
        const auto& t = g.triangles[id - g.spheres.size()];
        n.point = closest_on_triangle(p, glm::dvec3(t.v0), glm::dvec3(t.v1), glm::dvec3(t.v2), n.b1, n.b2);
    }
    const glm::dvec3 e = n.point - p;
    n.d2 = glm::dot(e, e);
    if (n.closer_than(best)) best = n;
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
