// The BVH traversal checks against brute force: adversarial rays, the
// oracle, the queries as the cpu device makes them. Templates in the cpu
// device's instruction-set namespace, so that a test file compiles them in the
// copy it tests (test_bvh_traversal_avx2.cpp: the AVX2 one, inside its target
// pragma, with every header from outside cpu/ included before); they return
// counts, which the test cases check.
#pragma once

#include "bvh/bvh.h"
#include "cpu/intersect_packet.h"
#include "cpu/mailbox.h"
#include "cpu/traverse_bvh.h"
#include "scene/prepared_scene.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace kdrt::detail::inline KDRT_CPU_ISA {

template <class Real>
std::string describe(const Ray<Real>& r) {
    std::ostringstream s;
    s.precision(9);
    s << "o=(" << r.org.x << "," << r.org.y << "," << r.org.z << ") d=(" << r.dir.x << "," << r.dir.y << "," << r.dir.z
      << ")";
    return s.str();
}

// Random and adversarial rays: from inside and outside the scene's box;
// axis-parallel with +0 and -0 in the other components; starting on the faces,
// edges and corners of the BVH's slot boxes and lying in their planes; aimed
// at their corners; starting on triangle vertices and sphere surfaces and at
// sphere centres; aimed at shared vertices; grazing along triangles' planes.
template <class Real, int N>
std::vector<Ray<Real>> bvh_rays(const SceneGeometry<Real>& g, const Aabb& bounds, const WideBvhN<N>& bvh,
                                std::uint32_t seed) {
    using Vec = glm::vec<3, Real>;
    std::mt19937 rng(seed);
    const Aabb box = bounds.empty() ? Aabb{glm::dvec3(-1), glm::dvec3(1)} : bounds;
    const glm::dvec3 ext = glm::max(box.extent(), glm::dvec3(1e-30));
    auto rnd = [&](double a, double c) { return std::uniform_real_distribution<double>(a, c)(rng); };
    auto point = [&](bool inside) {
        const glm::dvec3 l = inside ? box.lo : box.lo - 0.5 * ext, h = inside ? box.hi : box.hi + 0.5 * ext;
        return Vec(Real(rnd(l.x, h.x)), Real(rnd(l.y, h.y)), Real(rnd(l.z, h.z)));
    };
    auto dir = [&]() {
        Vec d;
        do d = Vec(Real(rnd(-1, 1)), Real(rnd(-1, 1)), Real(rnd(-1, 1)));
        while (glm::length(d) < Real(0.1));
        return glm::normalize(d);
    };
    std::vector<Ray<Real>> rays;
    auto add = [&](const Vec& o, Vec d) {
        if (!(glm::length(d) > Real(0))) return;
        rays.emplace_back(o, glm::normalize(d));
    };
    for (int i = 0; i < 300; ++i) {
        const Vec o = point(i % 2 == 0);
        add(o, point(true) - o);
        add(o, dir());
    }
    const Real zeros[2] = {Real(0), -Real(0)};
    for (int i = 0; i < 200; ++i) {
        Vec d(zeros[i & 1], zeros[(i >> 1) & 1], zeros[(i >> 2) & 1]);
        d[i % 3] = (i & 8) ? Real(1) : Real(-1);
        rays.emplace_back(point(i % 3 != 0), d);
    }
    // The slot boxes' planes, corners and edges.
    std::vector<Aabb> slots;
    for (const auto& node : bvh.nodes)
        for (int i = 0; i < N && !node.is_empty(i); ++i) slots.push_back(node.slot_box(i));
    std::shuffle(slots.begin(), slots.end(), rng);
    if (slots.size() > 150) slots.resize(150);
    for (const Aabb& b : slots) {
        if (b.empty()) continue;
        const int axis = int(rng() % 3);
        const Real plane = Real(rng() & 1 ? b.hi[axis] : b.lo[axis]);
        Vec o = point(true);
        o[axis] = plane;
        Vec in_plane = dir();
        in_plane[axis] = zeros[rng() & 1];
        add(o, in_plane);  // lying in the face's plane
        add(o, dir());     // starting on it
        Vec along(0);
        along[(axis + 1) % 3] = (rng() & 1) ? Real(1) : Real(-1);
        add(o, along);  // axis-parallel in the plane
        const Vec corner(Real(rng() & 1 ? b.hi.x : b.lo.x), Real(rng() & 1 ? b.hi.y : b.lo.y),
                         Real(rng() & 1 ? b.hi.z : b.lo.z));
        const Vec from = point(false);
        add(from, corner - from);  // at a corner
        add(corner, dir());        // from a corner
        Vec edge = corner;
        edge[axis] = Real(rnd(b.lo[axis], b.hi[axis]));
        add(from, edge - from);  // at an edge
    }
    for (std::size_t i = 0; i < g.triangles.size(); i += 2) {
        const auto& t = g.triangles[i];
        add(t.v1, dir());  // from a vertex
        const Vec o = point(false);
        add(o, t.v0 - o);  // at a vertex (grid quads share them)
        const Vec e1 = t.v1 - t.v0, e2 = t.v2 - t.v0;
        add(t.v0 - e1 * Real(0.5), e1 + e2 * Real(rnd(0, 1)));  // grazing: in the triangle's plane
    }
    for (const auto& s : g.spheres) {
        add(s.center + Vec(0, s.radius, 0), dir());  // on the surface
        add(s.center, dir());                        // inside
    }
    return rays;
}

// The oracle: every object through intersect_object.
template <class Real>
struct BruteForce {
    const SceneGeometry<Real>& g;
    Hit<Real> closest(const Ray<Real>& ray) const {
        Hit<Real> best;
        for (std::uint32_t id = 0; id < g.object_count(); ++id) intersect_object(g, ray, id, best);
        return best;
    }
    bool occluded(const Ray<Real>& ray, Real t_max) const {
        for (std::uint32_t id = 0; id < g.object_count(); ++id) {
            Hit<Real> h;
            intersect_object(g, ray, id, h);
            if (h.valid() && h.t < t_max) return true;
        }
        return false;
    }
};

// Closest-hit and any-hit queries through a traversal, as SceneTracer makes
// them: each leaf's objects one by one through intersect_object, or
// (batched) through test_leaf_ray, the cpu device's leaf test for big trees.
// `traverse(ray, t_max, visit)` runs the traversal under test for closest
// hits, `any_traverse` for any-hit queries (the same unless given).
template <class Real, class Traverse, class AnyTraverse = Traverse>
struct LeafQueries {
    const SceneGeometry<Real>& g;
    Traverse traverse;
    bool batched;
    AnyTraverse any_traverse = traverse;

    Hit<Real> closest(const Ray<Real>& ray) const {
        Hit<Real> best;
        NoMailbox tested;
        const PacketShear<Real, kLeafLanes<Real>> lanes(ray, IntersectConfig{});
        auto take = [&](const Hit<Real>& h) {
            if (h.closer_than(best.t, best.id)) best = h;
            return false;
        };
        auto single = [&](std::uint32_t id) {
            intersect_object(g, ray, id, best);
            return false;
        };
        traverse(ray, std::numeric_limits<Real>::infinity(), [&](const std::uint32_t* ids, std::uint32_t count) {
            if (batched) test_leaf_ray(g, lanes, ids, count, tested, take, single);
            else
                for (std::uint32_t i = 0; i < count; ++i) single(ids[i]);
            return best.t;
        });
        return best;
    }

    bool occluded(const Ray<Real>& ray, Real t_max) const {
        bool blocked = false;
        NoMailbox tested;
        const PacketShear<Real, kLeafLanes<Real>> lanes(ray, IntersectConfig{});
        auto take = [&](const Hit<Real>& h) { return blocked = h.t < t_max; };
        auto single = [&](std::uint32_t id) {
            Hit<Real> h;
            intersect_object(g, ray, id, h);
            return blocked = h.valid() && h.t < t_max;
        };
        any_traverse(ray, t_max, [&](const std::uint32_t* ids, std::uint32_t count) {
            if (batched) test_leaf_ray(g, lanes, ids, count, tested, take, single);
            else
                for (std::uint32_t i = 0; i < count && !blocked; ++i) single(ids[i]);
            return blocked ? -std::numeric_limits<Real>::infinity() : std::numeric_limits<Real>::infinity();
        });
        return blocked;
    }
};

struct TraversalReport {
    std::size_t rays = 0, hits = 0, mismatches = 0, blocked_mismatches = 0;
    std::string first;  // the first mismatch, described
};

// Every ray's closest hit (id, t, barycentrics) and its any-hit answers
// just before, just beyond and well beyond that hit, against brute force.
template <class Real, class Queries>
TraversalReport compare_with_brute_force(const SceneGeometry<Real>& g, const std::vector<Ray<Real>>& rays,
                                         const Queries& fast) {
    const BruteForce<Real> brute{g};
    TraversalReport r;
    r.rays = rays.size();
    for (const Ray<Real>& ray : rays) {
        const Hit<Real> a = brute.closest(ray), b = fast.closest(ray);
        r.hits += a.valid();
        if (a.id != b.id || a.t != b.t || a.b1 != b.b1 || a.b2 != b.b2) {
            if (r.first.empty()) {
                std::ostringstream s;
                s.precision(9);
                s << describe(ray) << ": brute force " << a.id << " at " << a.t << ", traversal " << b.id << " at " << b.t;
                r.first = s.str();
            }
            ++r.mismatches;
        }
        for (Real f : {Real(0.999), Real(1.001), Real(1.5)}) {
            const Real t_max = a.valid() ? a.t * f : Real(100);
            const bool blocked = fast.occluded(ray, t_max);
            r.blocked_mismatches += brute.occluded(ray, t_max) != blocked;
            if (a.valid() && f < Real(1)) r.blocked_mismatches += blocked;
        }
    }
    return r;
}

// The wide traversal (any-hit queries walking the children as stored, as the
// cpu device's do), the binary one, each with both leaf tests.
template <class Real, int N>
TraversalReport check_wide_bvh(const SceneGeometry<Real>& g, const WideBvhN<N>& bvh,
                               const std::vector<Ray<Real>>& rays, bool batched) {
    auto traverse = [&bvh](const Ray<Real>& ray, Real t_max, auto&& visit) { traverse_bvh(bvh, ray, t_max, visit); };
    auto any_traverse = [&bvh](const Ray<Real>& ray, Real t_max, auto&& visit) {
        traverse_bvh<ChildOrder::AsStored>(bvh, ray, t_max, visit);
    };
    using Queries = LeafQueries<Real, decltype(traverse), decltype(any_traverse)>;
    return compare_with_brute_force(g, rays, Queries{g, traverse, batched, any_traverse});
}

template <class Real>
TraversalReport check_bvh2_traversal(const SceneGeometry<Real>& g, const Bvh2& bvh,
                                     const std::vector<Ray<Real>>& rays, bool batched) {
    auto traverse = [&bvh](const Ray<Real>& ray, Real t_max, auto&& visit) { traverse_bvh2(bvh, ray, t_max, visit); };
    return compare_with_brute_force(g, rays, LeafQueries<Real, decltype(traverse)>{g, traverse, batched});
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
