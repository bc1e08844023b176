// The work of the cpu device's ray queries (ray_queries.h): the working-frame
// rays, the query tracer over the traversals, and the parallel loops over
// the rays. Compiled once per instruction set (cpu_isa.h): ray_queries.cpp
// and ray_queries_avx2.cpp.
#pragma once

#include "common/tsan_fork_join.h"

#include "cpu/cpu_isa.h"
#include "cpu/intersect.h"
#include "cpu/intersect_packet.h"
#include "cpu/mailbox.h"
#include "cpu/ray_query_setup.h"
#include "cpu/surface.h"
#include "cpu/traverse_none.h"
#include "cpu/traverse_packet.h"
#include "cpu/traverse_restart.h"
#include "cpu/traverse_ropes.h"
#include "cpu/traverse_short_stack.h"
#include "cpu/traverse_stack.h"

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>
#include <optional>
#include <span>

namespace kdrt::detail::inline KDRT_CPU_ISA {

// A QueryRay in the working frame: the unit-direction ray the traversals
// need, and the window in its units (t_unit = t * length).
template <class Real>
struct WorkingRay {
    Ray<Real> ray;
    double length;  // |direction|
    double t_min, t_max;  // the query's window, in units of the given direction
    // The window is all of t > 0 (t_min <= 0, t_max infinite): then any hit the
    // tests return (finite, t > 0) is inside, with no division to check it.
    // A long direction could round a tiny t to 0: those keep the exact check.
    bool whole_ray = false;
};

template <class Real>
bool working_ray(const QueryRay& q, const glm::dvec3& frame_origin, std::optional<WorkingRay<Real>>& out) {
    const glm::dvec3 o(q.origin[0], q.origin[1], q.origin[2]);
    const glm::dvec3 d(q.direction[0], q.direction[1], q.direction[2]);
    const double t_min = q.t_min, t_max = q.t_max;
    for (int a = 0; a < 3; ++a)
        if (!std::isfinite(o[a]) || !std::isfinite(d[a])) return false;
    if (std::isnan(t_min) || std::isnan(t_max) || t_min > t_max) return false;
    const double length = glm::length(d);
    if (!(length > 0.0) || !std::isfinite(length)) return false;
    using Vec = glm::vec<3, Real>;
    const Vec dir(d / length);
    if (dir == Vec(0)) return false;
    // A float t_unit over a length up to 1e30 stays far above double's smallest number; a double t_unit
    // may itself be that small, and only a length up to 1 cannot make t_unit / length round to 0.
    const double longest = sizeof(Real) < sizeof(double) ? 1e30 : 1.0;
    const bool whole_ray = t_min <= 0.0 && t_max == std::numeric_limits<double>::infinity() && length <= longest;
    out.emplace(WorkingRay<Real>{Ray<Real>(Vec(o - frame_origin), dir), length, t_min, t_max, whole_ray});
    return true;
}

// The traversal's bound: the window's end in unit-direction units, a little
// beyond it (the exact window is applied to each hit).
template <class Real>
Real traversal_bound(const WorkingRay<Real>& w) {
    const double t = w.t_max * w.length * (1.0 + 1e-6);
    return t < static_cast<double>(std::numeric_limits<Real>::max()) ? static_cast<Real>(t)
                                                                     : std::numeric_limits<Real>::infinity();
}

// Whether a hit at t_unit (in units of the unit direction) is inside the
// query's window, which is in units of the given direction.
template <class Real>
KDRT_HOT_INLINE bool in_window(const WorkingRay<Real>& w, Real t_unit) {
    if (!(t_unit > Real(0))) return false;
    if (w.whole_ray) return true;
    const double t = static_cast<double>(t_unit) / w.length;
    return t > w.t_min && t <= w.t_max;
}

// A sphere's hit in the window: both roots are candidates (a window may start inside it).
template <class Real>
KDRT_HOT_INLINE bool first_root_in_window(const WorkingRay<Real>& w, Real t0, Real t1, Real& t_out) {
    if (in_window(w, t0)) { t_out = t0; return true; }
    if (in_window(w, t1)) { t_out = t1; return true; }
    return false;
}

// The first hit of object `id` inside the window.
template <class Real>
KDRT_HOT_INLINE bool hit_in_window(const SceneGeometry<Real>& g, const WorkingRay<Real>& w, std::uint32_t id,
                                   bool moller, bool textbook, Hit<Real>& h) {
    const auto sphere_count = static_cast<std::uint32_t>(g.spheres.size());
    h.id = static_cast<std::int32_t>(id);
    h.b1 = h.b2 = Real(0);
    if (id < sphere_count) {
        const auto& s = g.spheres[id];
        Real t0, t1;
        if (!(textbook ? sphere_roots_textbook(w.ray, s.center, s.radius, t0, t1)
                       : sphere_roots(w.ray, s.center, s.radius, t0, t1)))
            return false;
        return first_root_in_window(w, t0, t1, h.t);
    }
    const auto& tri = g.triangles[id - sphere_count];
    const bool hit = moller ? intersect_triangle_moller(w.ray, tri.v0, tri.v1, tri.v2, h.t, h.b1, h.b2)
                            : intersect_triangle(w.ray, tri.v0, tri.v1, tri.v2, h.t, h.b1, h.b2);
    return hit && in_window(w, h.t);
}

template <class Real>
class QueryTracer {
public:
    QueryTracer(const SceneGeometry<Real>& g, const KdTree* tree, Traversal traversal,
                const std::vector<std::uint32_t>& all_ids, bool moller, bool textbook)
        : g_(g), tree_(tree), traversal_(traversal), all_ids_(all_ids), moller_(moller), textbook_(textbook),
          mailbox_(traversal != Traversal::None && tree_duplicates_objects(tree)),
          batch_triangles_(leaf_batching_pays(g, IntersectConfig{moller, textbook})) {}

    Hit<Real> closest(const WorkingRay<Real>& w) const {
        return mailbox_ ? closest_with<Mailbox>(w) : closest_with<NoMailbox>(w);
    }
    bool any(const WorkingRay<Real>& w) const { return mailbox_ ? any_with<Mailbox>(w) : any_with<NoMailbox>(w); }

    // N rays at once through the packet traversal (Wald 2004), with the
    // single-ray results bit for bit; false (nothing done) when the traversal
    // is not Stack or the rays are not packet_compatible.
    template <int N>
    bool closest(const WorkingRay<Real>* const (&w)[N], Hit<Real> (&hits)[N]) const {
        const Ray<Real>* rays[N];
        if (!packs(w, rays)) return false;
        if (mailbox_) closest_packet_with<Mailbox>(w, rays, hits);
        else closest_packet_with<NoMailbox>(w, rays, hits);
        return true;
    }
    template <int N>
    bool any(const WorkingRay<Real>* const (&w)[N], bool (&blocked)[N]) const {
        const Ray<Real>* rays[N];
        if (!packs(w, rays)) return false;
        if (mailbox_) any_packet_with<Mailbox>(w, rays, blocked);
        else any_packet_with<NoMailbox>(w, rays, blocked);
        return true;
    }

private:
    template <int N>
    bool packs(const WorkingRay<Real>* const (&w)[N], const Ray<Real>* (&rays)[N]) const {
        if (traversal_ != Traversal::Stack) return false;
        for (int i = 0; i < N; ++i) rays[i] = &w[i]->ray;
        return packet_compatible(rays);
    }

    // Leaves are tested for all of a packet's lanes at once (test_leaf_packet).
    template <class Box, int N>
    void closest_packet_with(const WorkingRay<Real>* const (&w)[N], const Ray<Real>* const (&rays)[N],
                             Hit<Real> (&best)[N]) const {
        Box tested[N];
        Real bound[N];
        for (int i = 0; i < N; ++i) {
            best[i] = Hit<Real>{};
            bound[i] = traversal_bound(*w[i]);
        }
        const PacketShear<Real, N> shear(rays, IntersectConfig{moller_, textbook_});
        auto scalar = [&](int lane, std::uint32_t id) KDRT_HOT_INLINE_LAMBDA {
            Hit<Real> h;
            if (hit_in_window(g_, *w[lane], id, moller_, textbook_, h) && h.closer_than(best[lane].t, best[lane].id))
                best[lane] = h;
            return false;
        };
        auto take = [&](int lane, const Hit<Real>& h) KDRT_HOT_INLINE_LAMBDA {
            if (in_window(*w[lane], h.t) && h.closer_than(best[lane].t, best[lane].id)) best[lane] = h;
            return false;
        };
        auto roots = [&](int lane, std::uint32_t id, Real t0, Real t1) KDRT_HOT_INLINE_LAMBDA {
            Hit<Real> h;
            h.id = static_cast<std::int32_t>(id);
            if (first_root_in_window(*w[lane], t0, t1, h.t) && h.closer_than(best[lane].t, best[lane].id))
                best[lane] = h;
            return false;
        };
        auto visit = [&](std::uint32_t lanes, const std::uint32_t* ids, std::uint32_t count, Real(&done_at)[N])
                         KDRT_HOT_INLINE_LAMBDA {
                             test_leaf_packet(g_, shear, lanes, ids, count, tested, scalar, take, roots);
                             for (int i = 0; i < N; ++i) done_at[i] = best[i].t;
                         };
        traverse_stack_packet(*tree_, rays, bound, visit);
    }

    template <class Box, int N>
    void any_packet_with(const WorkingRay<Real>* const (&w)[N], const Ray<Real>* const (&rays)[N],
                         bool (&blocked)[N]) const {
        Box tested[N];
        Real bound[N];
        for (int i = 0; i < N; ++i) {
            blocked[i] = false;
            bound[i] = traversal_bound(*w[i]);
        }
        const PacketShear<Real, N> shear(rays, IntersectConfig{moller_, textbook_});
        auto scalar = [&](int lane, std::uint32_t id) KDRT_HOT_INLINE_LAMBDA {
            Hit<Real> h;
            return blocked[lane] = hit_in_window(g_, *w[lane], id, moller_, textbook_, h);
        };
        auto take = [&](int lane, const Hit<Real>& h) KDRT_HOT_INLINE_LAMBDA {
            return blocked[lane] = in_window(*w[lane], h.t);
        };
        auto roots = [&](int lane, std::uint32_t, Real t0, Real t1) KDRT_HOT_INLINE_LAMBDA {
            Real t;
            return blocked[lane] = first_root_in_window(*w[lane], t0, t1, t);
        };
        auto visit = [&](std::uint32_t lanes, const std::uint32_t* ids, std::uint32_t count, Real(&done_at)[N])
                         KDRT_HOT_INLINE_LAMBDA {
                             test_leaf_packet(g_, shear, unblocked_lanes(lanes, blocked), ids, count, tested,
                                              scalar, take, roots);
                             blocked_done_at(blocked, done_at);
                         };
        traverse_stack_packet(*tree_, rays, bound, visit);
    }

    // A leaf's triangles are tested kLeafLanes at a time (test_leaf_ray) when
    // that pays (leaf_batching_pays).
    template <class Box>
    Hit<Real> closest_with(const WorkingRay<Real>& w) const {
        Hit<Real> best;
        Box tested;
        auto single = [&](std::uint32_t id) KDRT_HOT_INLINE_LAMBDA {
            Hit<Real> h;
            if (hit_in_window(g_, w, id, moller_, textbook_, h) && h.closer_than(best.t, best.id)) best = h;
            return false;
        };
        if (batch_triangles_) {
            const PacketShear<Real, kLeafLanes<Real>> lanes(w.ray, IntersectConfig{moller_, textbook_});
            auto take = [&](const Hit<Real>& h) KDRT_HOT_INLINE_LAMBDA {
                if (in_window(w, h.t) && h.closer_than(best.t, best.id)) best = h;
                return false;
            };
            auto visit = [&](const std::uint32_t* ids, std::uint32_t count) {
                test_leaf_ray(g_, lanes, ids, count, tested, take, single);
                return best.t;
            };
            traverse(w, visit);
        } else {
            auto visit = [&](const std::uint32_t* ids, std::uint32_t count) {
                for (std::uint32_t i = 0; i < count; ++i)
                    if (!tested.seen(ids[i])) single(ids[i]);
                return best.t;
            };
            traverse(w, visit);
        }
        return best;
    }

    template <class Box>
    bool any_with(const WorkingRay<Real>& w) const {
        bool blocked = false;
        Box tested;
        auto single = [&](std::uint32_t id) KDRT_HOT_INLINE_LAMBDA {
            Hit<Real> h;
            return blocked = hit_in_window(g_, w, id, moller_, textbook_, h);
        };
        auto done_at = [&] {
            return blocked ? -std::numeric_limits<Real>::infinity() : std::numeric_limits<Real>::infinity();
        };
        if (batch_triangles_) {
            const PacketShear<Real, kLeafLanes<Real>> lanes(w.ray, IntersectConfig{moller_, textbook_});
            auto take = [&](const Hit<Real>& h) KDRT_HOT_INLINE_LAMBDA { return blocked = in_window(w, h.t); };
            auto visit = [&](const std::uint32_t* ids, std::uint32_t count) {
                if (!blocked) test_leaf_ray(g_, lanes, ids, count, tested, take, single);
                return done_at();
            };
            traverse(w, visit);
        } else {
            auto visit = [&](const std::uint32_t* ids, std::uint32_t count) {
                for (std::uint32_t i = 0; i < count && !blocked; ++i)
                    if (!tested.seen(ids[i])) single(ids[i]);
                return done_at();
            };
            traverse(w, visit);
        }
        return blocked;
    }

    template <class Visit>
    void traverse(const WorkingRay<Real>& w, Visit& visit) const {
        const Real bound = traversal_bound(w);
        switch (traversal_) {
            case Traversal::None: traverse_none(all_ids_, w.ray, bound, visit); break;
            case Traversal::Restart: traverse_restart(*tree_, w.ray, bound, visit); break;
            case Traversal::Ropes: traverse_ropes(*tree_, w.ray, bound, visit); break;
            case Traversal::Stack: traverse_stack(*tree_, w.ray, bound, visit); break;
            case Traversal::ShortStack: traverse_short_stack(*tree_, w.ray, bound, visit); break;
        }
    }

    const SceneGeometry<Real>& g_;
    const KdTree* tree_;
    Traversal traversal_;
    const std::vector<std::uint32_t>& all_ids_;
    bool moller_, textbook_, mailbox_;
    bool batch_triangles_;
};

inline QueryHit miss() {
    QueryHit h{};
    h.t = std::numeric_limits<float>::infinity();
    h.object = KDRT_NO_HIT;
    h.kind = KDRT_KIND_NONE;
    return h;
}

template <class Real>
QueryHit to_query_hit(const SceneGeometry<Real>& g, const WorkingRay<Real>& w, const Hit<Real>& hit) {
    if (!hit.valid()) return miss();
    QueryHit q{};
    q.t = static_cast<float>(static_cast<double>(hit.t) / w.length);
    q.object = static_cast<std::uint32_t>(hit.id);
    const auto id = static_cast<std::uint32_t>(hit.id);
    glm::dvec3 n;
    if (id < g.spheres.size()) {
        q.kind = KDRT_KIND_SPHERE;
        const auto& s = g.spheres[id];
        const glm::dvec3 p = glm::dvec3(w.ray.org) + static_cast<double>(hit.t) * glm::dvec3(w.ray.dir);
        n = safe_normalize(p - glm::dvec3(s.center));
    } else {
        q.kind = KDRT_KIND_TRIANGLE;
        q.u = static_cast<float>(hit.b1);
        q.v = static_cast<float>(hit.b2);
        const auto& t = g.triangles[id - g.spheres.size()];
        const glm::dvec3 v0(t.v0), v1(t.v1), v2(t.v2);
        n = safe_normalize(glm::cross(v1 - v0, v2 - v0));
    }
    for (int a = 0; a < 3; ++a) q.normal[a] = static_cast<float>(n[a]);
    return q;
}

inline constexpr std::size_t kGrain = 64;  // rays per task: enough to amortise the scheduling
inline constexpr int kPacket = 4;       // rays per packet: consecutive rays of a block, traced together when they can be

// Runs one block of queries: packets of kPacket consecutive valid rays through
// `packet(w, i0)` (false: it could not), the rest and the leftovers through `single(w, i)`;
// `invalid(i)` for rays that are not valid.
template <class Real, class Packet, class Single, class Invalid>
void run_block(std::span<const QueryRay> rays, const glm::dvec3& frame_origin, std::size_t begin, std::size_t end,
               Packet&& packet, Single&& single, Invalid&& invalid) {
    for (std::size_t i0 = begin; i0 < end; i0 += kPacket) {
        const std::size_t n = std::min<std::size_t>(kPacket, end - i0);
        std::optional<WorkingRay<Real>> w[kPacket];
        bool all_valid = n == kPacket;
        for (std::size_t k = 0; k < n; ++k) all_valid &= working_ray(rays[i0 + k], frame_origin, w[k]);
        if (all_valid) {
            const WorkingRay<Real>* lanes[kPacket];
            for (int k = 0; k < kPacket; ++k) lanes[k] = &*w[k];
            if (packet(lanes, i0)) continue;
        }
        for (std::size_t k = 0; k < n; ++k)
            if (w[k]) single(*w[k], i0 + k);
            else invalid(i0 + k);
    }
}

inline void intersect_rays(const RayQuerySetup& s, std::span<const QueryRay> rays, std::span<QueryHit> hits) {
    auto run = [&]<class Real>(Real) {
        const QueryTracer<Real> tracer(s.scene.geometry<Real>(), s.tree, s.traversal, s.all_ids, s.moller, s.textbook);
        const auto& g = s.scene.geometry<Real>();
        auto block = [&](const tbb::blocked_range<std::size_t>& range) {
            run_block<Real>(
                rays, s.scene.frame_origin, range.begin(), range.end(),
                [&](const WorkingRay<Real>* const (&w)[kPacket], std::size_t i0) {
                    Hit<Real> h[kPacket];
                    if (!tracer.closest(w, h)) return false;
                    for (int k = 0; k < kPacket; ++k) hits[i0 + k] = to_query_hit(g, *w[k], h[k]);
                    return true;
                },
                [&](const WorkingRay<Real>& w, std::size_t i) { hits[i] = to_query_hit(g, w, tracer.closest(w)); },
                [&](std::size_t i) { hits[i] = miss(); });
        };
        TsanForkJoin tsan;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), kGrain), tsan.task(block));
    };
    if (s.precision == Precision::Double) run(0.0);
    else run(0.0f);
}

inline void occluded_rays(const RayQuerySetup& s, std::span<const QueryRay> rays, std::span<std::uint8_t> occluded) {
    auto run = [&]<class Real>(Real) {
        const QueryTracer<Real> tracer(s.scene.geometry<Real>(), s.tree, s.traversal, s.all_ids, s.moller, s.textbook);
        auto block = [&](const tbb::blocked_range<std::size_t>& range) {
            run_block<Real>(
                rays, s.scene.frame_origin, range.begin(), range.end(),
                [&](const WorkingRay<Real>* const (&w)[kPacket], std::size_t i0) {
                    bool b[kPacket];
                    if (!tracer.any(w, b)) return false;
                    for (int k = 0; k < kPacket; ++k) occluded[i0 + k] = b[k] ? 1 : 0;
                    return true;
                },
                [&](const WorkingRay<Real>& w, std::size_t i) { occluded[i] = tracer.any(w) ? 1 : 0; },
                [&](std::size_t i) { occluded[i] = 0; });
        };
        TsanForkJoin tsan;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), kGrain), tsan.task(block));
    };
    if (s.precision == Precision::Double) run(0.0);
    else run(0.0f);
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
