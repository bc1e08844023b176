// From a hit to the shading frame: hit point, geometric and shading normals,
// and where secondary rays start.
#pragma once

#include "cpu/intersect.h"

#include <glm/geometric.hpp>

#include <algorithm>

namespace kdrt::detail::inline KDRT_CPU_ISA {

// glm::length and glm::normalize square their argument, which overflows in
// float beyond 1.8e19 (a sphere of radius 1e20, the normal of a triangle
// 1e10 across). Such vectors are scaled by 2^-64 first: exact, so shorter
// ones keep every bit. The kernels' length3 and normalize3 (cl/common.cl)
// do the same.
template <class Real>
KDRT_HOT_INLINE Real safe_length(const glm::vec<3, Real>& v) {
    const glm::vec<3, Real> a = glm::abs(v);
    if (std::max({a.x, a.y, a.z}) > Real(1.152921504606846976e18))  // 2^60
        return Real(18446744073709551616.0) * glm::length(v * Real(5.42101086242752217e-20));
    return glm::length(v);
}

template <class Real>
KDRT_HOT_INLINE glm::vec<3, Real> safe_normalize(const glm::vec<3, Real>& v) {
    const glm::vec<3, Real> a = glm::abs(v);
    if (std::max({a.x, a.y, a.z}) > Real(1.152921504606846976e18))
        return glm::normalize(v * Real(5.42101086242752217e-20));
    return glm::normalize(v);
}

template <class Real>
struct Surface {
    using Vec = glm::vec<3, Real>;
    Vec p;          // hit point, recomputed from the object (not org + t dir)
    Vec ng, ns;     // geometric and shading normals, facing the incoming ray
    Real magnitude; // largest coordinate of the object: the scale of p's rounding error
    bool inside;    // the ray hit the back side
    std::uint32_t material;
};

// The hit point is rebuilt from the object itself (barycentrics; projection
// onto the sphere) so its error depends on the object's coordinates only, not
// on how far the ray travelled (Wächter and Binder, Ray Tracing Gems ch. 6).
template <class Real>
Surface<Real> make_surface(const SceneGeometry<Real>& g, const Ray<Real>& ray, const Hit<Real>& hit) {
    using Vec = glm::vec<3, Real>;
    Surface<Real> s;
    const auto sphere_count = static_cast<std::uint32_t>(g.spheres.size());
    const auto id = static_cast<std::uint32_t>(hit.id);
    if (id < sphere_count) {
        const auto& sp = g.spheres[id];
        Vec p = ray.org + hit.t * ray.dir;
        s.ng = safe_normalize(p - sp.center);
        s.p = sp.center + sp.radius * s.ng;
        s.ns = s.ng;
        Vec ac = glm::abs(sp.center);
        s.magnitude = std::max({ac.x, ac.y, ac.z}) + sp.radius;
        s.material = sp.material;
    } else {
        const auto& tri = g.triangles[id - sphere_count];
        const Real b0 = Real(1) - hit.b1 - hit.b2;
        s.p = b0 * tri.v0 + hit.b1 * tri.v1 + hit.b2 * tri.v2;
        s.ng = safe_normalize(glm::cross(tri.v1 - tri.v0, tri.v2 - tri.v0));
        s.ns = s.ng;
        if (tri.normals != kNoNormal) {
            // Vertex normals that cancel out leave the geometric normal in charge.
            const Vec* n = &g.normals[tri.normals];
            const Vec ns = b0 * n[0] + hit.b1 * n[1] + hit.b2 * n[2];
            if (glm::dot(ns, ns) > Real(1e-12)) s.ns = glm::normalize(ns);
        }
        Vec m = glm::max(glm::max(glm::abs(tri.v0), glm::abs(tri.v1)), glm::abs(tri.v2));
        s.magnitude = std::max({m.x, m.y, m.z});
        // A huge triangle seen close up (a ground of half-size 1e9 under a
        // camera 1 unit above it): the barycentric point carries the vertices'
        // rounding, tens of units in float, the ray's point that of its origin
        // and t. Take the ray's, and its scale for the offset, when that is
        // 2^8 times smaller; ordinary hits never meet this.
        const Vec ao = glm::abs(ray.org);
        const Real ray_magnitude = std::max({ao.x, ao.y, ao.z}) + hit.t;
        if (Real(256) * ray_magnitude < s.magnitude) {
            s.p = ray.org + hit.t * ray.dir;
            s.magnitude = ray_magnitude;
        }
        s.material = tri.material;
    }
    s.inside = glm::dot(ray.dir, s.ng) > Real(0);
    if (s.inside) {
        s.ng = -s.ng;
        s.ns = -s.ns;
    }
    // FORMAT.md step 2: vertex normals that disagree with the winding (common
    // in models from elsewhere) are turned to the geometric normal's side.
    if (glm::dot(s.ns, s.ng) < Real(0)) s.ns = -s.ns;
    return s;
}

// Origin of a ray leaving the surface in direction `dir`: pushed off the
// surface along the geometric normal, to the side `dir` goes, by a few dozen
// ulps of the object's magnitude. Relative to the object, so the same in a
// scene moved or scaled; together with the ray's `ignore` id it keeps
// secondary rays from re-hitting their own surface.
// With a fixed epsilon (the accuracy knob) the offset is absolute instead,
// in scene units: what most renderers do, and what breaks when the scene is
// scaled.
template <class Real>
KDRT_HOT_INLINE glm::vec<3, Real> offset_origin(const Surface<Real>& s, const glm::vec<3, Real>& dir,
                                                Real fixed_epsilon = Real(0)) {
    constexpr Real rel = sizeof(Real) == sizeof(double) ? Real(7.105427357601002e-15)  // 2^-47
                                                         : Real(3.814697265625e-06);   // 2^-18
    const Real eps = fixed_epsilon > Real(0) ? fixed_epsilon : rel * s.magnitude;
    return glm::dot(dir, s.ng) >= Real(0) ? s.p + eps * s.ng : s.p - eps * s.ng;
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
