// The cpu device's ray queries (kdrt/ray_query.h): world-space QueryRays taken
// into the working frame, traced through the committed scene's Tracer with a
// QueryWindow, in parallel with oneTBB, and their hits in world units.
//
// A ray is taken into the working frame in double (origin - frame_origin)
// and traced with its unit direction; t is reported in units of the given
// direction, and the window (t_min, t_max] is applied to that t. Hits have
// t > 0 as well. Invalid rays miss.
#pragma once

#include "common/tsan_fork_join.h"

#include "cpu/hit_window.h"
#include "cpu/surface.h"
#include "cpu/tracer.h"
#include "device/query_misses.h"

#include <kdrt/layout.h>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <utility>
#include <vector>

namespace kdrt::detail::inline KDRT_CPU_ISA {

// Whether query q can be traced, its direction `length` long and `dir` once
// normalised: finite components, a window with no NaN bound and t_min <= t_max,
// a finite nonzero length, and a direction still nonzero in Real.
template <class Real>
bool traceable(const QueryRay& q, double length, const glm::vec<3, Real>& dir) {
    for (int a = 0; a < 3; ++a)
        if (!std::isfinite(q.origin[a]) || !std::isfinite(q.direction[a])) return false;
    return q.t_min <= q.t_max && length > 0.0 && std::isfinite(length) && dir != glm::vec<3, Real>(0);
}

// out's window: query q's, whose direction is `length` long.
template <class Real>
void set_window(WorkingRay<Real>& out, const QueryRay& q, double length) {
    out.length = length;
    out.t_min = q.t_min;
    out.t_max = q.t_max;
    out.whole_ray = out.t_min <= 0.0 && out.t_max == std::numeric_limits<double>::infinity();
}

// The query ray in the working frame, into `out`; false (out unchanged) for an
// invalid ray (a NaN or infinite component, a zero direction, a NaN bound, t_min > t_max).
template <class Real>
bool working_ray(const QueryRay& q, const glm::dvec3& frame_origin, WorkingRay<Real>& out) {
    using Vec = glm::vec<3, Real>;
    const glm::dvec3 o(q.origin[0], q.origin[1], q.origin[2]);
    const glm::dvec3 d(q.direction[0], q.direction[1], q.direction[2]);
    const double length = glm::length(d);
    const Vec dir(d / length);
    if (!traceable(q, length, dir)) return false;
    out.ray = Ray<Real>(Vec(o - frame_origin), dir);
    set_window(out, q, length);
    return true;
}

// working_ray of K queries q[0..K-1] at once, lane k of each vector being
// q[k]: the same IEEE operations lane by lane, so the same rays, with the
// lanes' square roots and divisions in flight together. valid[k] as
// working_ray returns it; out[k] is written for every lane, meaningful where
// valid[k].
template <class Real, int K>
void working_rays(const QueryRay* q, const glm::dvec3& frame_origin, WorkingRay<Real> (&out)[K], bool (&valid)[K]) {
    static_assert(K == 4, "sqrt_lanes takes four doubles");
    using D = typename PacketLanes<double, K>::Vec;
    using V = typename PacketLanes<Real, K>::Vec;
    D o[3], d[3];
    for (int a = 0; a < 3; ++a)
        for (int k = 0; k < K; ++k) {
            o[a][k] = q[k].origin[a];
            d[a][k] = q[k].direction[a];
        }
    const D square = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    D length;
    sqrt_lanes(square, length);
    V org[3], dir[3];
    for (int a = 0; a < 3; ++a) {
        org[a] = __builtin_convertvector(o[a] - frame_origin[a], V);
        dir[a] = __builtin_convertvector(d[a] / length, V);
    }
    Ray<Real>* rays[K];
    for (int k = 0; k < K; ++k) rays[k] = &out[k].ray;
    make_rays<Real>(org, dir, rays);
    for (int k = 0; k < K; ++k) {
        valid[k] = traceable(q[k], length[k], out[k].ray.dir);
        set_window(out[k], q[k], length[k]);
    }
}

// Writes the hit of a ray from `org` along unit `dir`, whose query direction
// was `length` long, into q field by field (in place: no copy to reload).
template <class Real>
void write_query_hit(QueryHit& q, const SceneGeometry<Real>& g, const glm::vec<3, Real>& org,
                     const glm::vec<3, Real>& dir, double length, const Hit<Real>& hit) {
    if (!hit.valid()) {
        q = kQueryMiss;
        return;
    }
    q.geometry = q.primitive = 0;
    q.u = q.v = 0.0f;
    q.t = static_cast<float>(static_cast<double>(hit.t) / length);
    q.object = static_cast<std::uint32_t>(hit.id);
    const auto id = static_cast<std::uint32_t>(hit.id);
    glm::dvec3 n;
    if (id < g.spheres.size()) {
        q.kind = KDRT_KIND_SPHERE;
        const auto& s = g.spheres[id];
        const glm::dvec3 p = glm::dvec3(org) + static_cast<double>(hit.t) * glm::dvec3(dir);
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
}

template <class Real>
QueryHit to_query_hit(const SceneGeometry<Real>& g, const WorkingRay<Real>& w, const Hit<Real>& hit) {
    QueryHit q;
    write_query_hit(q, g, w.ray.org, w.ray.dir, w.length, hit);
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
        WorkingRay<Real> w[kPacket];  // set where valid[k] (not optionals: GCC zero-fills those for each packet)
        bool valid[kPacket];
        bool all_valid = n == kPacket;
        if (all_valid) {
            working_rays(rays.data() + i0, frame_origin, w, valid);
            for (int k = 0; k < kPacket; ++k) all_valid &= valid[k];
        } else {
            for (std::size_t k = 0; k < n; ++k) valid[k] = working_ray(rays[i0 + k], frame_origin, w[k]);
        }
        if (all_valid) {
            const WorkingRay<Real>* lanes[kPacket];
            for (int k = 0; k < kPacket; ++k) lanes[k] = &w[k];
            if (packet(lanes, i0)) continue;
        }
        for (std::size_t k = 0; k < n; ++k)
            if (valid[k]) single(w[k], i0 + k);
            else invalid(i0 + k);
    }
}

// A block's packet of rays with their windows, for the tracer's packet queries.
template <class Real>
struct QueryPacket {
    const Ray<Real>* rays[kPacket];
    QueryWindow<Real> windows[kPacket];
    explicit QueryPacket(const WorkingRay<Real>* const (&w)[kPacket]) {
        for (int k = 0; k < kPacket; ++k) {
            rays[k] = &w[k]->ray;
            windows[k].w = w[k];
        }
    }
};

// Closest hits waiting to become QueryHits: a hit object's data (for its
// normal) is read once a few more rays are traced, so that the loads started
// when the hits were found (here, and by Tracer::fetching for batched leaf
// tests) have arrived and incoherent rays' cache misses overlap.
template <class Real>
class PendingHits {
public:
    PendingHits(const SceneGeometry<Real>& g, std::span<QueryHit> out) : g_(g), out_(out) {}
    PendingHits(const PendingHits&) = delete;
    PendingHits& operator=(const PendingHits&) = delete;

    void add(std::size_t i, const WorkingRay<Real>& w, const Hit<Real>& hit) {
        if (!hit.valid()) {
            out_[i] = kQueryMiss;
            return;
        }
        const auto id = static_cast<std::size_t>(hit.id);
        if (id < g_.spheres.size()) prefetch_lines(&g_.spheres[id], sizeof(g_.spheres[id]));
        else prefetch_lines(&g_.triangles[id - g_.spheres.size()], sizeof(g_.triangles[0]));
        pending_[n_++] = {i, w.ray.org, w.ray.dir, w.length, hit};
        if (n_ == kPending) flush();
    }
    // Names the hits still waiting: at the end of a block.
    void flush() {
        for (int k = 0; k < n_; ++k) {
            const Entry& e = pending_[k];
            write_query_hit(out_[e.i], g_, e.org, e.dir, e.length, e.hit);
        }
        n_ = 0;
    }

private:
    static constexpr int kPending = 16;
    struct Entry {
        std::size_t i;
        glm::vec<3, Real> org, dir;
        double length;
        Hit<Real> hit;
    };
    const SceneGeometry<Real>& g_;
    std::span<QueryHit> out_;
    Entry pending_[kPending];
    int n_ = 0;
};

template <class Real>
void intersect_rays(const Tracer<Real>& tracer, const glm::dvec3& frame_origin, std::span<const QueryRay> rays,
                    std::span<QueryHit> hits) {
    const auto& g = tracer.geometry();
    auto block = [&](const tbb::blocked_range<std::size_t>& range) {
        PendingHits<Real> pending(g, hits);
        run_block<Real>(
            rays, frame_origin, range.begin(), range.end(),
            [&](const WorkingRay<Real>* const (&w)[kPacket], std::size_t i0) {
                const QueryPacket<Real> packet(w);
                Hit<Real> h[kPacket];
                if (!tracer.closest(packet.rays, packet.windows, h)) return false;
                for (int k = 0; k < kPacket; ++k) pending.add(i0 + k, *w[k], h[k]);
                return true;
            },
            [&](const WorkingRay<Real>& w, std::size_t i) {
                pending.add(i, w, tracer.closest(w.ray, QueryWindow<Real>{&w}));
            },
            [&](std::size_t i) { hits[i] = kQueryMiss; });
        pending.flush();
    };
    TsanForkJoin tsan;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), kGrain), tsan.task(block));
}

template <class Real>
void occluded_rays(const Tracer<Real>& tracer, const glm::dvec3& frame_origin, std::span<const QueryRay> rays,
                   std::span<std::uint8_t> occluded) {
    auto block = [&](const tbb::blocked_range<std::size_t>& range) {
        run_block<Real>(
            rays, frame_origin, range.begin(), range.end(),
            [&](const WorkingRay<Real>* const (&w)[kPacket], std::size_t i0) {
                const QueryPacket<Real> packet(w);
                bool b[kPacket];
                if (!tracer.any(packet.rays, packet.windows, b)) return false;
                for (int k = 0; k < kPacket; ++k) occluded[i0 + k] = b[k] ? 1 : 0;
                return true;
            },
            [&](const WorkingRay<Real>& w, std::size_t i) {
                occluded[i] = tracer.any(w.ray, QueryWindow<Real>{&w}) ? 1 : 0;
            },
            [&](std::size_t i) { occluded[i] = 0; });
    };
    TsanForkJoin tsan;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), kGrain), tsan.task(block));
}

// counts[i]: how many hits ray i has in its window (Tracer::every).
template <class Real>
void count_rays(const Tracer<Real>& tracer, const glm::dvec3& frame_origin, std::span<const QueryRay> rays,
                std::span<std::uint32_t> counts) {
    auto block = [&](const tbb::blocked_range<std::size_t>& range) {
        std::vector<std::uint32_t> seen;
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            WorkingRay<Real> w;
            std::uint32_t n = 0;
            if (working_ray(rays[i], frame_origin, w))
                tracer.every(w.ray, QueryWindow<Real>{&w}, seen, [&](const Hit<Real>&) { ++n; });
            counts[i] = n;
        }
    };
    TsanForkJoin tsan;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), kGrain), tsan.task(block));
}

// counts[i]: ray i's hits with a geometry's hits at one query t counted
// once (geometry_of: each object's geometry), as every_hit_rays' lists merged
// by kdrt::all_hits(..., OncePerGeometry) count them: by (t, object), a hit
// dropped when the one before it has its geometry and t.
template <class Real>
void count_rays_once_per_geometry(const Tracer<Real>& tracer, const glm::dvec3& frame_origin,
                                  std::span<const QueryRay> rays, std::span<std::uint32_t> counts,
                                  std::span<const std::uint32_t> geometry_of) {
    auto block = [&](const tbb::blocked_range<std::size_t>& range) {
        std::vector<std::uint32_t> seen;
        std::vector<std::pair<float, std::uint32_t>> hits;  // (query t, object)
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            WorkingRay<Real> w;
            hits.clear();
            if (working_ray(rays[i], frame_origin, w))
                tracer.every(w.ray, QueryWindow<Real>{&w}, seen, [&](const Hit<Real>& h) {
                    hits.push_back({static_cast<float>(static_cast<double>(h.t) / w.length),
                                    static_cast<std::uint32_t>(h.id)});
                });
            std::sort(hits.begin(), hits.end());
            std::uint32_t n = 0;
            for (std::size_t k = 0; k < hits.size(); ++k)
                if (k == 0 || hits[k].first != hits[k - 1].first ||
                    geometry_of[hits[k].second] != geometry_of[hits[k - 1].second])
                    ++n;
            counts[i] = n;
        }
    };
    TsanForkJoin tsan;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), kGrain), tsan.task(block));
}

// Every hit of every ray, nearest first (then by object), in ray order:
// ray i's are hits[splits[i] .. splits[i + 1]). Blocks of rays collect their
// hits apart, in parallel; then they are put in place.
template <class Real>
void every_hit_rays(const Tracer<Real>& tracer, const glm::dvec3& frame_origin, std::span<const QueryRay> rays,
                    std::vector<std::uint64_t>& splits, std::vector<QueryHit>& hits) {
    const auto& g = tracer.geometry();
    constexpr std::size_t kBlock = 1024;
    const std::size_t blocks = (rays.size() + kBlock - 1) / kBlock;
    std::vector<std::vector<QueryHit>> block_hits(blocks);
    splits.assign(rays.size() + 1, 0);
    auto block = [&](const tbb::blocked_range<std::size_t>& range) {
        std::vector<std::uint32_t> seen;
        for (std::size_t b = range.begin(); b < range.end(); ++b) {
            std::vector<QueryHit>& out = block_hits[b];
            const std::size_t end = std::min(rays.size(), (b + 1) * kBlock);
            for (std::size_t i = b * kBlock; i < end; ++i) {
                WorkingRay<Real> w;
                const std::size_t first = out.size();
                if (working_ray(rays[i], frame_origin, w))
                    tracer.every(w.ray, QueryWindow<Real>{&w}, seen,
                                 [&](const Hit<Real>& h) { out.push_back(to_query_hit(g, w, h)); });
                std::sort(out.begin() + static_cast<std::ptrdiff_t>(first), out.end(),
                          [](const QueryHit& x, const QueryHit& y) {
                              return x.t < y.t || (x.t == y.t && x.object < y.object);
                          });
                splits[i + 1] = out.size() - first;
            }
        }
    };
    TsanForkJoin tsan;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 1), tsan.task(block));
    for (std::size_t i = 0; i < rays.size(); ++i) splits[i + 1] += splits[i];
    hits.resize(splits.back());
    auto place = [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t b = range.begin(); b < range.end(); ++b)
            std::copy(block_hits[b].begin(), block_hits[b].end(),
                      hits.begin() + static_cast<std::ptrdiff_t>(splits[b * kBlock]));
    };
    TsanForkJoin tsan_place;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 1), tsan_place.task(place));
}

// out[i]: the surface point nearest to points[i] (world space); ids internal.
// A point with a non-finite coordinate gets no_closest_point().
template <class Real>
void closest_point_queries(const Tracer<Real>& tracer, const glm::dvec3& frame_origin,
                           std::span<const std::array<float, 3>> points, std::span<ClosestPoint> out) {
    const auto& g = tracer.geometry();
    auto block = [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            const glm::dvec3 world(points[i][0], points[i][1], points[i][2]);
            out[i] = no_closest_point();
            if (!std::isfinite(world.x) || !std::isfinite(world.y) || !std::isfinite(world.z)) continue;
            const glm::dvec3 p = world - frame_origin;
            const NearestPoint n = tracer.nearest(p);
            if (!n.valid()) continue;
            ClosestPoint& c = out[i];
            const glm::dvec3 q = n.point + frame_origin;
            for (int a = 0; a < 3; ++a) c.point[a] = static_cast<float>(q[a]);
            c.distance = static_cast<float>(std::sqrt(n.d2));
            c.object = n.id;
            glm::dvec3 normal;
            if (n.id < g.spheres.size()) {
                normal = safe_normalize(n.point - glm::dvec3(g.spheres[n.id].center));
            } else {
                const auto& t = g.triangles[n.id - g.spheres.size()];
                const glm::dvec3 v0(t.v0), v1(t.v1), v2(t.v2);
                normal = safe_normalize(glm::cross(v1 - v0, v2 - v0));
                c.u = static_cast<float>(n.b1);
                c.v = static_cast<float>(n.b2);
            }
            for (int a = 0; a < 3; ++a) c.normal[a] = static_cast<float>(normal[a]);
        }
    };
    TsanForkJoin tsan;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), kGrain), tsan.task(block));
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
