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

inline constexpr std::int32_t kNoObject = -1;

// Component `axis` of a vector without glm's switch in operator[] (the hot
// loops index by a run-time axis at every node).
template <class Real>
inline Real axis_of(const glm::vec<3, Real>& v, int axis) {
    return (&v.x)[axis];
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
        kx = kz == 2 ? 0 : kz + 1;  // (kz + 1) % 3 and (kz + 2) % 3, without a remainder
        ky = kz == 0 ? 2 : kz - 1;
        if (dir[kz] < Real(0)) std::swap(kx, ky);  // keep the winding
        sx = dir[kx] / dir[kz];
        sy = dir[ky] / dir[kz];
        sz = Real(1) / dir[kz];
        org_max = std::max({std::abs(org.x), std::abs(org.y), std::abs(org.z)});
    }
};

}  // namespace kdrt::detail::KDRT_CPU_ISA
