// Ray/object intersection for the C++ reference, templated on the precision.
// The OpenCL twin is cl/intersect.cl; keep the two in step.
#pragma once

#include "cpu/ray.h"
#include "scene/prepared_scene.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace kdrt::detail::inline KDRT_CPU_ISA {

template <class Real>
struct Hit {
    Real t = std::numeric_limits<Real>::infinity();
    std::int32_t id = kNoObject;
    Real b1 = 0, b2 = 0;  // triangle barycentrics of v1 and v2

    bool valid() const { return id != kNoObject; }
    // The one ordering every traversal uses: nearer first, then the lower id,
    // so that a kd-tree finds exactly what brute force finds.
    bool closer_than(Real other_t, std::int32_t other_id) const {
        return t < other_t || (t == other_t && id < other_id);
    }
};

// Watertight ray/triangle test (Woop, Benthin, Wald, JCGT 2013). Edge
// functions are evaluated the same way for both triangles of a shared edge, so
// a ray through the edge hits at least one of them; zero edge functions are
// recomputed in double as the paper prescribes. Both faces are hit; t > 0.
template <class Real>
KDRT_HOT_INLINE bool intersect_triangle(const Ray<Real>& ray, const glm::vec<3, Real>& v0, const glm::vec<3, Real>& v1,
                                        const glm::vec<3, Real>& v2, Real& t_out, Real& b1_out, Real& b2_out) {
    using Vec = glm::vec<3, Real>;
    const Vec A = v0 - ray.org, B = v1 - ray.org, C = v2 - ray.org;
    const Real Akz = axis_of(A, ray.kz), Bkz = axis_of(B, ray.kz), Ckz = axis_of(C, ray.kz);
    const Real ax = axis_of(A, ray.kx) - ray.sx * Akz, ay = axis_of(A, ray.ky) - ray.sy * Akz;
    const Real bx = axis_of(B, ray.kx) - ray.sx * Bkz, by = axis_of(B, ray.ky) - ray.sy * Bkz;
    const Real cx = axis_of(C, ray.kx) - ray.sx * Ckz, cy = axis_of(C, ray.ky) - ray.sy * Ckz;
    Real u = cx * by - cy * bx;
    Real v = ax * cy - ay * cx;
    Real w = bx * ay - by * ax;
    if constexpr (sizeof(Real) < sizeof(double)) {
        if (u == Real(0) || v == Real(0) || w == Real(0)) {
            u = static_cast<Real>(double(cx) * double(by) - double(cy) * double(bx));
            v = static_cast<Real>(double(ax) * double(cy) - double(ay) * double(cx));
            w = static_cast<Real>(double(bx) * double(ay) - double(by) * double(ax));
        }
    }
    if ((u < 0 || v < 0 || w < 0) && (u > 0 || v > 0 || w > 0)) return false;
    const Real det = u + v + w;
    if (det == Real(0)) return false;  // degenerate, or the ray lies in its plane
    const Real az = ray.sz * Akz, bz = ray.sz * Bkz, cz = ray.sz * Ckz;
    const Real T = u * az + v * bz + w * cz;
    Real t = T / det;
    // T sums depths of vertices far beyond the hit (a huge triangle seen close
    // up): when they exceed the hit distance by 2^8, or overflow, t has lost
    // that many bits (a ground of half-size 1e9 seen from 1 unit loses all).
    // The plane equation keeps them: exact for an axis-aligned plane, whose
    // normal has exact zeros. Rarely taken, so ordinary hits keep their bits.
    const Real zmax = std::max({std::abs(az), std::abs(bz), std::abs(cz)});
    if (zmax > Real(256) * std::abs(t) || !std::isfinite(t)) {
        const Vec n = glm::cross(v1 - v0, v2 - v0);
        t = glm::dot(n, A) / glm::dot(n, ray.dir);
    }
    if (!(t > Real(0)) || !std::isfinite(t)) return false;
    t_out = t;
    b1_out = v / det;
    b2_out = w / det;
    return true;
}

// Moller-Trumbore (1997): the classic test, kept to measure what
// watertightness costs. Not watertight: rays through shared edges can slip
// between two triangles.
template <class Real>
inline bool intersect_triangle_moller(const Ray<Real>& ray, const glm::vec<3, Real>& v0, const glm::vec<3, Real>& v1,
                                      const glm::vec<3, Real>& v2, Real& t_out, Real& b1_out, Real& b2_out) {
    using Vec = glm::vec<3, Real>;
    const Vec e1 = v1 - v0, e2 = v2 - v0;
    const Vec p = glm::cross(ray.dir, e2);
    const Real det = glm::dot(e1, p);
    if (det == Real(0)) return false;
    const Real inv = Real(1) / det;
    const Vec s = ray.org - v0;
    const Real u = glm::dot(s, p) * inv;
    if (u < Real(0) || u > Real(1)) return false;
    const Vec q = glm::cross(s, e1);
    const Real v = glm::dot(ray.dir, q) * inv;
    if (v < Real(0) || u + v > Real(1)) return false;
    const Real t = glm::dot(e2, q) * inv;
    if (!(t > Real(0))) return false;
    t_out = t;
    b1_out = u;
    b2_out = v;
    return true;
}

// The textbook quadratic, kept to measure what the careful test buys: b^2 - c
// cancels catastrophically for small or distant spheres.
template <class Real>
inline bool sphere_roots_textbook(const Ray<Real>& ray, const glm::vec<3, Real>& center, Real radius, Real& t0,
                                  Real& t1) {
    const glm::vec<3, Real> f = ray.org - center;
    const Real b = glm::dot(f, ray.dir);
    const Real c = glm::dot(f, f) - radius * radius;
    const Real disc = b * b - c;
    if (disc < Real(0)) return false;
    const Real sq = std::sqrt(disc);
    t0 = -b - sq;
    t1 = -b + sq;
    return true;
}

// Ray/sphere test after Haines et al., "Precision Improvements for Ray/Sphere
// Intersection" (Ray Tracing Gems, ch. 7): the discriminant from the distance
// of the centre to the ray, and the smaller root from c / q to avoid
// cancellation. The ray direction is normalised (a = 1).
// Returns both roots in ascending order; false when the ray misses.
template <class Real>
inline bool sphere_roots(const Ray<Real>& ray, const glm::vec<3, Real>& center, Real radius, Real& t0, Real& t1) {
    using Vec = glm::vec<3, Real>;
    Vec f = ray.org - center;
    // A radius whose square overflows (float: above 1.8e19) is worked in units
    // of 2^64: an exact scaling, so smaller spheres keep every bit.
    Real scale = Real(1);
    if (radius > Real(1.152921504606846976e18)) {  // 2^60
        f *= Real(5.42101086242752217e-20);        // 2^-64
        radius *= Real(5.42101086242752217e-20);
        scale = Real(18446744073709551616.0);      // 2^64
    }
    const Real b = -glm::dot(f, ray.dir);           // -b/2 of the textbook quadratic
    const Vec l = f + b * ray.dir;                  // centre to the ray's closest point
    const Real r2 = radius * radius;
    const Real disc = r2 - glm::dot(l, l);
    if (disc < Real(0)) return false;
    const Real c = glm::dot(f, f) - r2;
    const Real q = b + std::copysign(std::sqrt(disc), b);
    if (q == Real(0)) {  // ray origin at the centre's closest point with zero discriminant
        t0 = t1 = Real(0);
        return c <= Real(0);
    }
    t0 = scale * (c / q);
    t1 = scale * q;
    if (t0 > t1) std::swap(t0, t1);
    return true;
}

// The sphere hit a ray from outside takes: the nearer root in front of the origin.
template <class Real>
KDRT_HOT_INLINE bool nearest_root(Real t0, Real t1, Real& t_out) {
    if (t0 > Real(0)) { t_out = t0; return true; }
    if (t1 > Real(0)) { t_out = t1; return true; }
    return false;
}

// The hit a ray leaving a sphere (starting on its surface) may take: the far
// root, and only when heading inwards.
template <class Real>
KDRT_HOT_INLINE bool far_side_root(const Ray<Real>& ray, const glm::vec<3, Real>& center, Real t1, Real& t_out) {
    if (glm::dot(ray.dir, ray.org - center) >= Real(0) || !(t1 > Real(0))) return false;
    t_out = t1;
    return true;
}

// The nearest admissible sphere hit. A ray leaving this very sphere (ray.ignore)
// starts on its surface: it can only hit the far side, and only when heading
// inwards, so the near root (~0) is never taken: no self-intersection whatever
// the scale.
template <class Real>
inline bool intersect_sphere(const Ray<Real>& ray, std::int32_t id, const glm::vec<3, Real>& center, Real radius,
                             Real& t_out, bool textbook = false) {
    Real t0, t1;
    if (!(textbook ? sphere_roots_textbook(ray, center, radius, t0, t1) : sphere_roots(ray, center, radius, t0, t1)))
        return false;
    if (id == ray.ignore) return far_side_root(ray, center, t1, t_out);
    return nearest_root(t0, t1, t_out);
}

// Which tests intersect_object uses (the accuracy knobs).
struct IntersectConfig {
    bool moller = false;    // Moller-Trumbore instead of the watertight test
    bool textbook = false;  // the textbook sphere quadratic instead of the careful one
};

// Tests object `id` and keeps it in `best` if it is closer (Hit::closer_than).
template <class Real>
inline void intersect_object(const SceneGeometry<Real>& g, const Ray<Real>& ray, std::uint32_t id, Hit<Real>& best,
                             IntersectConfig config = {}) {
    const auto sid = static_cast<std::int32_t>(id);
    const std::uint32_t sphere_count = static_cast<std::uint32_t>(g.spheres.size());
    Hit<Real> h;
    h.id = sid;
    if (id < sphere_count) {
        const auto& s = g.spheres[id];
        if (!intersect_sphere(ray, sid, s.center, s.radius, h.t, config.textbook)) return;
    } else {
        if (sid == ray.ignore) return;  // a flat triangle cannot be hit again by a ray leaving it
        const auto& tri = g.triangles[id - sphere_count];
        const bool hit = config.moller ? intersect_triangle_moller(ray, tri.v0, tri.v1, tri.v2, h.t, h.b1, h.b2)
                                       : intersect_triangle(ray, tri.v0, tri.v1, tri.v2, h.t, h.b1, h.b2);
        if (!hit) return;
    }
    if (h.closer_than(best.t, best.id)) best = h;
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
