// A ray with what every intersection test and traversal precomputes once:
// the watertight triangle test's shear (Woop, Benthin, Wald 2013), the
// reciprocal direction for split planes, and the object it leaves.
#pragma once

#include "cpu/cpu_isa.h"

#include <glm/common.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

// The hot loop is one function: GCC otherwise leaves split_step, the leaf
// visit and the intersection tests out of line in the big traversal loops.
// The sanitizer builds and the tests (KDRT_NO_FORCED_INLINE) leave inlining to
// the compiler: forced into every instantiation, a file takes minutes to build.
#if defined(__GNUC__) && !defined(KDRT_NO_FORCED_INLINE)
#define KDRT_HOT_INLINE inline __attribute__((always_inline))
#define KDRT_HOT_INLINE_LAMBDA __attribute__((always_inline))
#else
#define KDRT_HOT_INLINE inline
#define KDRT_HOT_INLINE_LAMBDA
#endif
#if defined(__GNUC__)
#define KDRT_PREFETCH(address) __builtin_prefetch(address)
#define KDRT_NOINLINE __attribute__((noinline))
#else
#define KDRT_NOINLINE
#define KDRT_PREFETCH(address) ((void)0)
#endif

namespace kdrt::detail::inline KDRT_CPU_ISA {

// Prefetches every cache line that [p, p + bytes) touches.
KDRT_HOT_INLINE void prefetch_lines(const void* p, std::size_t bytes) {
    constexpr std::uintptr_t kLine = 64;
    const auto start = reinterpret_cast<std::uintptr_t>(p);
    for (std::uintptr_t at = start & ~(kLine - 1); at < start + bytes; at += kLine)
        KDRT_PREFETCH(reinterpret_cast<const void*>(at));
}

// Prefetches the cache lines of *p: a fixed count, unrolled, where T is
// aligned to lines; else those [p, p + sizeof(T)) touches.
template <class T>
KDRT_HOT_INLINE void prefetch_object(const T* p) {
    constexpr std::size_t kLine = 64;
    if constexpr (alignof(T) % kLine == 0) {
        const auto* bytes = reinterpret_cast<const unsigned char*>(p);
#pragma GCC unroll 8
        for (std::size_t at = 0; at < sizeof(T); at += kLine) KDRT_PREFETCH(bytes + at);
    } else {
        prefetch_lines(p, sizeof(T));
    }
}

inline constexpr std::int32_t kNoObject = -1;

// Component `axis` of a vector without glm's switch in operator[] (the hot
// loops index by a run-time axis at every node).
template <class Real>
inline Real axis_of(const glm::vec<3, Real>& v, int axis) {
    return (&v.x)[axis];
}

// The watertight test's other two axes for the dominant one, kz: (kz + 1) % 3
// and (kz + 2) % 3 without a remainder, swapped where dir[kz] < 0 (flip) to
// keep the winding.
inline void shear_axes(int kz, bool flip, int& kx, int& ky) {
    const int next = kz == 2 ? 0 : kz + 1, prev = kz == 0 ? 2 : kz - 1;
    kx = flip ? prev : next;
    ky = flip ? next : prev;
}

template <class Real>
struct Ray {
    using Vec = glm::vec<3, Real>;
    Vec org, dir;      // dir is normalised
    Vec inv_dir;       // 1 / dir, +-inf for zero components (never used for those)
    int kx = 0, ky = 1, kz = 2;  // watertight test: kz = dominant axis
    Real sx = 0, sy = 0, sz = 1;
    std::int32_t ignore = kNoObject;  // the object this ray leaves, if any
    Real org_max = 0;  // largest |org| component: the traversal's termination slack scales with it

    Ray() = default;  // storage for a ray assigned later; org, dir and inv_dir unset
    Ray(const Vec& o, const Vec& d, std::int32_t ignore_id = kNoObject) : org(o), dir(d), ignore(ignore_id) {
        for (int a = 0; a < 3; ++a) inv_dir[a] = Real(1) / dir[a];
        Vec ad = glm::abs(dir);
        kz = (ad.x > ad.y) ? (ad.x > ad.z ? 0 : 2) : (ad.y > ad.z ? 1 : 2);
        shear_axes(kz, dir[kz] < Real(0), kx, ky);
        sx = dir[kx] / dir[kz];
        sy = dir[ky] / dir[kz];
        sz = Real(1) / dir[kz];
        org_max = std::max({std::abs(org.x), std::abs(org.y), std::abs(org.z)});
    }
};

// Ray(org, dir) for K rays at once, lane k of the vectors (V: K Reals) being
// ray k's origin and direction components, into *out[k]: the same IEEE
// operations lane by lane, so the same rays, with the lanes' divisions in
// flight together.
template <class Real, int K, class V>
KDRT_HOT_INLINE void make_rays(const V (&org)[3], const V (&dir)[3], Ray<Real>* const (&out)[K]) {
    static_assert(sizeof(V) == K * sizeof(Real));
    const V ax = dir[0] < Real(0) ? -dir[0] : dir[0], ay = dir[1] < Real(0) ? -dir[1] : dir[1],
            az = dir[2] < Real(0) ? -dir[2] : dir[2];  // |dir|, for comparisons only (-0 stays)
    // kz as the constructor picks it: x where pick_x, y where pick_y, else z.
    const auto x_over_y = ax > ay;
    const auto pick_x = x_over_y & (ax > az), pick_y = ~x_over_y & (ay > az);
    // dir along kz, (kz + 1) % 3 and (kz + 2) % 3
    const V d_kz = pick_x ? dir[0] : pick_y ? dir[1] : dir[2];
    const V d_next = pick_x ? dir[1] : pick_y ? dir[2] : dir[0];
    const V d_prev = pick_x ? dir[2] : pick_y ? dir[0] : dir[1];
    const auto flip = d_kz < Real(0);  // kx and ky swapped, to keep the winding
    const V sx = (flip ? d_prev : d_next) / d_kz, sy = (flip ? d_next : d_prev) / d_kz, sz = Real(1) / d_kz;
    const V inv[3] = {Real(1) / dir[0], Real(1) / dir[1], Real(1) / dir[2]};
    for (int k = 0; k < K; ++k) {
        Ray<Real>& r = *out[k];
        r.org = glm::vec<3, Real>(org[0][k], org[1][k], org[2][k]);
        r.dir = glm::vec<3, Real>(dir[0][k], dir[1][k], dir[2][k]);
        r.inv_dir = glm::vec<3, Real>(inv[0][k], inv[1][k], inv[2][k]);
        r.kz = pick_x[k] ? 0 : pick_y[k] ? 1 : 2;
        shear_axes(r.kz, flip[k] != 0, r.kx, r.ky);
        r.sx = sx[k];
        r.sy = sy[k];
        r.sz = sz[k];
        r.ignore = kNoObject;
        r.org_max = std::max({std::abs(r.org.x), std::abs(r.org.y), std::abs(r.org.z)});
    }
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
