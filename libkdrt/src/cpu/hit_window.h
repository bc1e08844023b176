// Hit windows: which hits along a ray a query accepts, as a policy of the one
// tracer (tracer.h). The renderer's rays accept every hit ahead of them
// (OpenWindow) and its shadow rays those before the light (ShadowWindow); the
// ray queries accept hits on (t_min, t_max] in units of the caller's direction
// (QueryWindow). A window gives the traversal its bound, says whether a hit
// at t counts, and picks a sphere's root.
//
// Every t here is in units of the ray's unit direction, and the tests only
// return t > 0.
#pragma once

#include "cpu/intersect.h"

#include <cmath>
#include <limits>

namespace kdrt::detail::inline KDRT_CPU_ISA {

// Every hit ahead of the ray.
template <class Real>
struct OpenWindow {
    Real bound() const { return std::numeric_limits<Real>::infinity(); }
    bool contains(Real) const { return true; }
    bool first_root(Real t0, Real t1, Real& t) const { return nearest_root(t0, t1, t); }
};

// Hits with t < t_max: what blocks a shadow ray towards a light at t_max.
template <class Real>
struct ShadowWindow {
    Real t_max;
    Real bound() const { return t_max; }
    bool contains(Real t) const { return t < t_max; }
    bool first_root(Real t0, Real t1, Real& t) const { return nearest_root(t0, t1, t) && t < t_max; }
};

// A QueryRay in the working frame: the unit-direction ray the traversals
// need, and the query's window in units of the given direction (t_unit = t * length).
template <class Real>
struct WorkingRay {
    Ray<Real> ray;
    double length;        // |direction|
    double t_min, t_max;  // the query's window, in units of the given direction
    // The window is all of t > 0 (t_min <= 0, t_max infinite): then any hit the
    // tests return (finite, t > 0) is inside, with no division to check it.
    bool whole_ray = false;
};

// (t_min, t_max] of a ray query, applied in double to t / |direction|.
template <class Real>
struct QueryWindow {
    const WorkingRay<Real>* w;

    // The window's end in unit-direction units, a little beyond it (contains() is exact).
    Real bound() const {
        const double t = w->t_max * w->length * (1.0 + 1e-6);
        return t < static_cast<double>(std::numeric_limits<Real>::max()) ? static_cast<Real>(t)
                                                                         : std::numeric_limits<Real>::infinity();
    }
    // Every t_unit > 0 is past a t_min <= 0, also where t_unit / length rounds to 0.
    KDRT_HOT_INLINE bool contains(Real t_unit) const {
        if (!(t_unit > Real(0))) return false;
        if (w->whole_ray) return true;
        const double t = static_cast<double>(t_unit) / w->length;
        return (w->t_min <= 0.0 || t > w->t_min) && t <= w->t_max;
    }
    // Both roots are candidates: a window may start inside the sphere.
    KDRT_HOT_INLINE bool first_root(Real t0, Real t1, Real& t) const {
        if (contains(t0)) { t = t0; return true; }
        if (contains(t1)) { t = t1; return true; }
        return false;
    }
};

// Object `id`'s hit inside the window, into `h`. The self-intersection rule of
// intersect_sphere holds: a ray leaving a sphere (ray.ignore) only meets its far
// side, heading inwards, and never the flat triangle it leaves.
template <class Real, class Window>
KDRT_HOT_INLINE bool test_object(const SceneGeometry<Real>& g, const Ray<Real>& ray, std::uint32_t id,
                                 const Window& window, IntersectConfig config, Hit<Real>& h) {
    const auto sid = static_cast<std::int32_t>(id);
    const auto sphere_count = static_cast<std::uint32_t>(g.spheres.size());
    h.id = sid;
    if (id < sphere_count) {
        const auto& s = g.spheres[id];
        Real t0, t1;
        if (!(config.textbook ? sphere_roots_textbook(ray, s.center, s.radius, t0, t1)
                              : sphere_roots(ray, s.center, s.radius, t0, t1)))
            return false;
        if (sid != ray.ignore) return window.first_root(t0, t1, h.t);
        return far_side_root(ray, s.center, t1, h.t) && window.contains(h.t);
    }
    if (sid == ray.ignore) return false;
    const auto& tri = g.triangles[id - sphere_count];
    const bool hit = config.moller ? intersect_triangle_moller(ray, tri.v0, tri.v1, tri.v2, h.t, h.b1, h.b2)
                                   : intersect_triangle(ray, tri.v0, tri.v1, tri.v2, h.t, h.b1, h.b2);
    return hit && window.contains(h.t);
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
