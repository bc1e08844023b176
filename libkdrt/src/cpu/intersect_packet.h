// The watertight triangle test (intersect_triangle, intersect.h) for the N
// rays of a packet at once. Rays that share the dominant axis kz (then also
// kx and ky: the packet's direction signs agree) run each step of the test
// as one vector operation over the lanes; the operations and their order are
// intersect_triangle's, so each lane gets its result bit for bit. The test's
// rare paths (an edge function exactly 0 in float, redone in double; the
// plane equation for huge triangles seen close up) are left to the scalar
// test, lane by lane. The kernels' twin, for CPU devices only like the
// packet traversal (traverse_packet.h): watertight_lanes in cl/visit_objects.cl,
// for a triangle against four rays and for four triangles against a ray.
#pragma once

#include "cpu/intersect.h"
#include "cpu/traverse_packet.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

namespace kdrt::detail::inline KDRT_CPU_ISA {

// The rays of a packet in lanes, as the watertight test needs them.
template <class Real, int N>
struct PacketShear {
    using V = typename PacketLanes<Real, N>::Vec;
    V org[3], dir[3], sx, sy, sz;
    int kx = 0, ky = 1, kz = 2;
    // The vector triangle test applies: every lane has the same kx, ky, kz, and
    // the test asked for is the watertight one (Moller-Trumbore has no vector twin).
    bool shared = true;
    bool spheres = true;  // the vector sphere test applies (not with the textbook quadratic)
    std::int32_t ignore[N];

    PacketShear(const Ray<Real>* const (&rays)[N], IntersectConfig config)
        : shared(!config.moller), spheres(!config.textbook) {
        kx = rays[0]->kx;
        ky = rays[0]->ky;
        kz = rays[0]->kz;
        for (int i = 0; i < N; ++i) {
            const Ray<Real>& r = *rays[i];
            shared = shared && r.kx == kx && r.ky == ky && r.kz == kz;
            for (int a = 0; a < 3; ++a) {
                org[a][i] = axis_of(r.org, a);
                dir[a][i] = axis_of(r.dir, a);
            }
            sx[i] = r.sx;
            sy[i] = r.sy;
            sz[i] = r.sz;
            ignore[i] = r.ignore;
        }
    }

    // One ray in every lane: for testing N objects at once (test_leaf_ray).
    PacketShear(const Ray<Real>& r, IntersectConfig config)
        : kx(r.kx), ky(r.ky), kz(r.kz), shared(!config.moller), spheres(!config.textbook) {
        for (int a = 0; a < 3; ++a) {
            org[a] = V{} + axis_of(r.org, a);
            dir[a] = V{} + axis_of(r.dir, a);
        }
        sx = V{} + r.sx;
        sy = V{} + r.sy;
        sz = V{} + r.sz;
        for (int i = 0; i < N; ++i) ignore[i] = r.ignore;
    }
};

// watertight_lanes' answer in each lane: t, and the barycentrics' numerators
// and denominator, divided only for the hit lanes a caller reads (hit()), as
// intersect_triangle divides them: the same quotients, bit for bit.
template <class Real, int N>
struct TriangleLanes {
    using V = typename PacketShear<Real, N>::V;
    V t, v, w, det;
    KDRT_HOT_INLINE Hit<Real> hit(int lane, std::int32_t id) const {
        Hit<Real> h;
        h.t = t[lane];
        h.id = id;
        h.b1 = v[lane] / det[lane];
        h.b2 = w[lane] / det[lane];
        return h;
    }
};

// intersect_triangle for the lanes in `lanes` (the packet must be `shared`),
// with the triangle's vertices given by component: the same triangle for every
// lane (VX = Real) or a triangle per lane (VX = the lane vector). Returns the
// lanes that hit, with their answers in `out`; `scalar` gets the lanes whose
// answer needs intersect_triangle itself.
template <class Real, int N, class VX>
KDRT_HOT_INLINE std::uint32_t watertight_lanes(const PacketShear<Real, N>& p, std::uint32_t lanes,
                                               const VX (&v0)[3], const VX (&v1)[3], const VX (&v2)[3],
                                               TriangleLanes<Real, N>& out, std::uint32_t& scalar) {
    using V = typename PacketShear<Real, N>::V;
    const int kx = p.kx, ky = p.ky, kz = p.kz;
    // A = v0 - org, by component, as intersect_triangle's vector subtraction.
    const V Akz = v0[kz] - p.org[kz], Bkz = v1[kz] - p.org[kz], Ckz = v2[kz] - p.org[kz];
    const V ax = (v0[kx] - p.org[kx]) - p.sx * Akz, ay = (v0[ky] - p.org[ky]) - p.sy * Akz;
    const V bx = (v1[kx] - p.org[kx]) - p.sx * Bkz, by = (v1[ky] - p.org[ky]) - p.sy * Bkz;
    const V cx = (v2[kx] - p.org[kx]) - p.sx * Ckz, cy = (v2[ky] - p.org[ky]) - p.sy * Ckz;
    const V u = cx * by - cy * bx;
    const V v = ax * cy - ay * cx;
    const V w = bx * ay - by * ax;
    const V zero = {};
    std::uint32_t slow = 0;
    if constexpr (sizeof(Real) < sizeof(double)) slow = lane_bits<N>((u == zero) | (v == zero) | (w == zero)) & lanes;
    const std::uint32_t outside =
        lane_bits<N>(((u < zero) | (v < zero) | (w < zero)) & ((u > zero) | (v > zero) | (w > zero)));
    const V det = u + v + w;
    std::uint32_t live = lanes & ~slow & ~outside & ~lane_bits<N>(det == zero);
    if (live == 0) {
        scalar = slow;
        return 0;
    }
    const V az = p.sz * Akz, bz = p.sz * Bkz, cz = p.sz * Ckz;
    const V T = u * az + v * bz + w * cz;
    const V t = T / det;
    // intersect_triangle's plane-equation fallback, and t not finite (t - t is NaN then): the scalar test.
    // (|x| as a select: no vector-returning helper, whose ABI would depend on -mavx.)
    const V abs_az = az < zero ? -az : az, abs_bz = bz < zero ? -bz : bz, abs_cz = cz < zero ? -cz : cz;
    const V abs_t = t < zero ? -t : t;
    const V zmax_ab = abs_az > abs_bz ? abs_az : abs_bz;
    const V zmax = zmax_ab > abs_cz ? zmax_ab : abs_cz;
    const std::uint32_t rare = lane_bits<N>((zmax > Real(256) * abs_t) | ((t - t) != zero)) & live;
    scalar = slow | rare;
    live &= ~rare & lane_bits<N>(t > zero);
    out.t = t;
    out.v = v;
    out.w = w;
    out.det = det;
    return live;
}

// One triangle against the lanes of a packet.
template <class Real, int N>
KDRT_HOT_INLINE std::uint32_t intersect_triangle_packet(const PacketShear<Real, N>& p, std::uint32_t lanes,
                                                        const glm::vec<3, Real>& v0, const glm::vec<3, Real>& v1,
                                                        const glm::vec<3, Real>& v2,
                                                        TriangleLanes<Real, N>& out, std::uint32_t& scalar) {
    const Real a[3] = {v0.x, v0.y, v0.z}, b[3] = {v1.x, v1.y, v1.z}, c[3] = {v2.x, v2.y, v2.z};
    return watertight_lanes(p, lanes, a, b, c, out, scalar);
}

// sphere_roots (intersect.h) for the lanes in `lanes`, for radii up to 2^60
// (beyond, the scalar test's scaled frame is needed). Returns the lanes whose
// ray meets the sphere, with both roots, t0 <= t1, in those lanes; `scalar`
// gets the lanes with q = 0, which the scalar test answers.
template <class Real, int N>
KDRT_HOT_INLINE std::uint32_t sphere_roots_packet(const PacketShear<Real, N>& p, std::uint32_t lanes,
                                                  const glm::vec<3, Real>& center, Real radius,
                                                  typename PacketShear<Real, N>::V& t0_out,
                                                  typename PacketShear<Real, N>::V& t1_out, std::uint32_t& scalar) {
    using V = typename PacketShear<Real, N>::V;
    // Each line is sphere_roots' vector expression, component by component in glm's order.
    const V fx = p.org[0] - center.x, fy = p.org[1] - center.y, fz = p.org[2] - center.z;
    const V b = -((fx * p.dir[0] + fy * p.dir[1]) + fz * p.dir[2]);
    const V lx = fx + b * p.dir[0], ly = fy + b * p.dir[1], lz = fz + b * p.dir[2];
    const Real r2 = radius * radius;
    const V disc = r2 - ((lx * lx + ly * ly) + lz * lz);
    const V zero = {};
    std::uint32_t live = lanes & ~lane_bits<N>(disc < zero);
    scalar = 0;
    if (live == 0) return 0;
    const V c = ((fx * fx + fy * fy) + fz * fz) - r2;
    V q = {};
    for (int i = 0; i < N; ++i) q[i] = b[i] + std::copysign(std::sqrt(std::max(disc[i], Real(0))), b[i]);
    scalar = lane_bits<N>(q == zero) & live;
    live &= ~scalar;
    const V t0 = c / q, t1 = q;
    const auto swap = t0 > t1;
    t0_out = swap ? t1 : t0;
    t1_out = swap ? t0 : t1;
    return live;
}

// A leaf's triangles lie scattered over the geometry array: asking for all
// of them before the first test lets their cache misses overlap, where the
// packet test would otherwise wait for each in turn (on a 2M-triangle mesh a
// third of a camera packet's time went to the load of a triangle's first vertex).
// Its twin is in the kernels of CPU devices (visit_objects.cl); a GPU hides
// such latency with other work-items.
template <class Real>
KDRT_HOT_INLINE void prefetch_leaf(const SceneGeometry<Real>& g, const std::uint32_t* ids, std::uint32_t count) {
    constexpr std::uint32_t kMost = 16;  // a few cache lines' worth of requests in flight
    const auto sphere_count = static_cast<std::uint32_t>(g.spheres.size());
    for (std::uint32_t k = 0; k < count && k < kMost; ++k) {
        if (ids[k] < sphere_count) continue;
        prefetch_lines(&g.triangles[ids[k] - sphere_count], sizeof(typename SceneGeometry<Real>::TriangleData));
    }
}

// Tests a leaf's objects for the lanes in `lanes`, through the vector tests
// where they apply and `scalar(lane, id)` elsewhere (packets whose lanes
// differ in kz, huge spheres, a ray leaving a sphere, the tests' rare paths).
// `take(lane, hit)` gets each vector triangle hit, `roots(lane, id, t0, t1)`
// each sphere the lane's line meets, for the caller's choice of root. All
// three return true when that lane needs no more tests (a shadow ray found a
// blocker); the lane then leaves `lanes`. `tested` are the lanes' mailboxes
// (Mailbox or NoMailbox, mailbox.h).
template <class Real, int N, class Box, class Scalar, class Take, class Roots>
KDRT_HOT_INLINE void test_leaf_packet(const SceneGeometry<Real>& g, const PacketShear<Real, N>& p,
                                      std::uint32_t lanes, const std::uint32_t* ids, std::uint32_t count,
                                      Box (&tested)[N], Scalar&& scalar, Take&& take, Roots&& roots) {
    using V = typename PacketShear<Real, N>::V;
    const auto sphere_count = static_cast<std::uint32_t>(g.spheres.size());
    prefetch_leaf(g, ids, count);
    for (std::uint32_t k = 0; k < count && lanes != 0; ++k) {
        const std::uint32_t id = ids[k];
        std::uint32_t todo = 0;
        for (std::uint32_t l = lanes; l != 0; l &= l - 1) {
            const int i = __builtin_ctz(l);
            if (!tested[i].seen(id)) todo |= 1u << i;
        }
        if (todo == 0) continue;
        std::uint32_t slow = todo, hits = 0;
        TriangleLanes<Real, N> tri_hits;
        if (id < sphere_count) {
            const auto& sphere = g.spheres[id];
            if (p.spheres && sphere.radius <= Real(1.152921504606846976e18)) {  // 2^60, as sphere_roots
                std::uint32_t leaving = 0;  // intersect_sphere's own rule for a ray leaving this sphere
                for (std::uint32_t l = todo; l != 0; l &= l - 1)
                    if (p.ignore[__builtin_ctz(l)] == static_cast<std::int32_t>(id)) leaving |= l & (0u - l);
                V t0, t1;
                hits = sphere_roots_packet(p, todo & ~leaving, sphere.center, sphere.radius, t0, t1, slow);
                slow |= leaving;
                for (std::uint32_t l = hits; l != 0; l &= l - 1) {
                    const int i = __builtin_ctz(l);
                    if (roots(i, id, t0[i], t1[i])) lanes &= ~(1u << i);
                }
                hits = 0;
            }
        } else if (p.shared) {
            for (std::uint32_t l = todo; l != 0; l &= l - 1)  // a flat triangle is never hit by a ray leaving it
                if (p.ignore[__builtin_ctz(l)] == static_cast<std::int32_t>(id)) todo &= ~(l & (0u - l));
            const auto& tri = g.triangles[id - sphere_count];
            hits = todo ? intersect_triangle_packet(p, todo, tri.v0, tri.v1, tri.v2, tri_hits, slow) : 0;
            if (!todo) slow = 0;
        }
        for (std::uint32_t l = hits; l != 0; l &= l - 1) {
            const int i = __builtin_ctz(l);
            if (take(i, tri_hits.hit(i, static_cast<std::int32_t>(id)))) lanes &= ~(1u << i);
        }
        for (std::uint32_t l = slow & lanes; l != 0; l &= l - 1) {
            const int i = __builtin_ctz(l);
            if (scalar(i, id)) lanes &= ~(1u << i);
        }
    }
}

// out = {f(0), ..., f(N - 1)}, assembled in registers (an out-parameter: a
// function returning an AVX-sized vector would change ABI with -mavx).
template <int N, class V, class F>
KDRT_HOT_INLINE void set_lanes(V& out, F&& f) {
    [&]<int... I>(std::integer_sequence<int, I...>) { out = V{f(I)...}; }(std::make_integer_sequence<int, N>{});
}

// watertight_lanes' answers for one ray and a triangle per lane, handed to a
// leaf test's callbacks: each hit lane to `take(hit)`, each rare lane to
// `single(id)`; `id_of(lane)` is the lane's object. True as soon as one of
// them says the ray needs no more tests.
template <class Real, int N, class IdOf, class Take, class Single>
KDRT_HOT_INLINE bool take_lane_hits(std::uint32_t hits, std::uint32_t slow, const TriangleLanes<Real, N>& found,
                                    IdOf&& id_of, Take&& take, Single&& single) {
    for (std::uint32_t l = hits; l != 0; l &= l - 1) {
        const int i = __builtin_ctz(l);
        if (take(found.hit(i, static_cast<std::int32_t>(id_of(i))))) return true;
    }
    for (std::uint32_t l = slow; l != 0; l &= l - 1)
        if (single(static_cast<std::uint32_t>(id_of(__builtin_ctz(l))))) return true;
    return false;
}

// A leaf's objects for one ray, with its triangles taken N at a time, one
// per lane (`p` is the ray in every lane). Each triangle gets
// intersect_triangle's result bit for bit, as in the packets, and goes to
// `take(hit)`, in no particular order. Spheres, the test's rare paths and
// Moller-Trumbore (`p.shared` false) go to `single(id)` instead. Both return
// true when the ray needs no more tests (a shadow ray found a blocker); the
// function then returns true. `tested` is the ray's mailbox (mailbox.h).
template <class Real, int N, class Box, class Take, class Single>
KDRT_HOT_INLINE bool test_leaf_ray(const SceneGeometry<Real>& g, const PacketShear<Real, N>& p,
                                   const std::uint32_t* ids, std::uint32_t count, Box& tested, Take&& take,
                                   Single&& single) {
    using V = typename PacketShear<Real, N>::V;
    const auto sphere_count = static_cast<std::uint32_t>(g.spheres.size());
    prefetch_leaf(g, ids, count);
    std::uint32_t batch[N];
    int n = 0;
    auto flush = [&]() KDRT_HOT_INLINE_LAMBDA {
        const typename SceneGeometry<Real>::TriangleData* tri[N];
        for (int i = 0; i < N; ++i)  // unused lanes repeat lane 0: finite values, masked out
            tri[i] = &g.triangles[batch[i < n ? i : 0] - sphere_count];
        // Each vector built whole in registers: lane-by-lane stores into a
        // vector in memory stall the load that follows them.
        V v[3][3];
        for (int a = 0; a < 3; ++a) {
            set_lanes<N>(v[0][a], [&](int i) { return axis_of(tri[i]->v0, a); });
            set_lanes<N>(v[1][a], [&](int i) { return axis_of(tri[i]->v1, a); });
            set_lanes<N>(v[2][a], [&](int i) { return axis_of(tri[i]->v2, a); });
        }
        std::uint32_t slow = 0;
        TriangleLanes<Real, N> found;
        const std::uint32_t hits = watertight_lanes(p, (1u << n) - 1u, v[0], v[1], v[2], found, slow);
        return take_lane_hits(hits, slow, found, [&](int i) { return batch[i]; }, take, single);
    };
    for (std::uint32_t k = 0; k < count; ++k) {
        const std::uint32_t id = ids[k];
        if (tested.seen(id)) continue;
        if (id < sphere_count || !p.shared) {
            if (single(id)) return true;
            continue;
        }
        if (static_cast<std::int32_t>(id) == p.ignore[0]) continue;  // a flat triangle is never hit by a ray leaving it
        batch[n++] = id;
        if (n == N) {
            if (flush()) return true;
            n = 0;
        }
    }
    return n > 0 && flush();
}

// How many objects a single ray's leaf test takes at once (test_leaf_ray):
// a vector register's worth of floats in the AVX2 copy (cpu_isa.h), four otherwise.
template <class Real>
inline constexpr int kLeafLanes = KDRT_CPU_VECTOR_BYTES >= 32 && sizeof(Real) == sizeof(float) ? 8 : 4;

// Whether test_leaf_ray pays for a scene: only triangles under the watertight
// test have a batched test; a scene of spheres would pay for the batching
// (building the ray's lanes) and gain nothing.
template <class Real>
bool leaf_batching_pays(const SceneGeometry<Real>& g, IntersectConfig config) {
    return !g.triangles.empty() && !config.moller;
}

// Shadow (any-hit) packets: the lanes of `lanes` not blocked yet, and each
// lane's done-at distance as a single shadow ray's visit returns it.
template <int N>
KDRT_HOT_INLINE std::uint32_t unblocked_lanes(std::uint32_t lanes, const bool (&blocked)[N]) {
    std::uint32_t open = 0;
    for (std::uint32_t l = lanes; l != 0; l &= l - 1)
        if (!blocked[__builtin_ctz(l)]) open |= l & (0u - l);
    return open;
}

template <class Real, int N>
KDRT_HOT_INLINE void blocked_done_at(const bool (&blocked)[N], Real (&done_at)[N]) {
    for (int i = 0; i < N; ++i)
        done_at[i] = blocked[i] ? -std::numeric_limits<Real>::infinity() : std::numeric_limits<Real>::infinity();
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
