// working_rays (a packet's four query rays set up at once, as vectors)
// against working_ray one ray at a time: the same validity and, for a valid
// ray, the same WorkingRay bit for bit. Templates in the cpu device's
// instruction-set namespace, so that a test file compiles them in the copy it
// tests (test_working_rays_avx2.cpp: the AVX2 one, inside its target pragma);
// they return counts, which the test cases check.
#pragma once

#include "cpu/ray_query_loops.h"

#include <kdrt/layout.h>

#include <glm/vec3.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace kdrt::detail::inline KDRT_CPU_ISA {

// Query rays that stress the setup, in groups of four: directions over forty
// decades, ties between the largest components (the shear axis), negative
// dominant components, signed zeros, components that round to zero once
// normalised, denormals; windows with t_min > 0; and rays that working_ray
// refuses (NaN or infinite components, zero directions, NaN or reversed
// windows) among valid ones.
inline std::vector<QueryRay> setup_test_rays(std::uint32_t seed) {
    std::mt19937 rng(seed);
    auto rnd = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    std::vector<QueryRay> rays;
    for (int i = 0; i < 6000; ++i) {
        const double scale = std::pow(10.0, rnd(-20.0, 20.0));
        float d[3];
        for (float& c : d) c = static_cast<float>(rnd(-1.0, 1.0) * scale);
        const int a = i % 3, b = (i + 1) % 3, c = (i + 2) % 3;
        switch (i % 10) {
            case 0: d[b] = d[a]; break;                              // |d[a]| = |d[b]|
            case 1: d[c] = -d[a]; break;                             // equal magnitudes, opposite signs
            case 2: d[b] = d[c] = d[a]; break;                       // all three equal
            case 3: d[a] = -0.0f; break;                             // a negative zero
            case 4: d[b] = d[c] = 0.0f; break;                       // along an axis
            case 5: d[a] = std::copysign(1e-40f, d[a]); break;       // a denormal
            case 6: d[a] = std::copysign(1e-30f, d[a]); d[b] = 3e30f; break;  // d[a] rounds to zero once normalised
            default: break;
        }
        QueryRay q{};
        for (int k = 0; k < 3; ++k) {
            q.origin[k] = static_cast<float>(rnd(-1e3, 1e3));
            q.direction[k] = d[k];
        }
        q.t_min = 0.0f;
        q.t_max = inf;
        switch (i % 23) {
            case 0: q.t_min = static_cast<float>(rnd(0.0, 10.0)); break;
            case 1: q.t_min = -static_cast<float>(rnd(0.0, 10.0)); q.t_max = static_cast<float>(rnd(0.0, 10.0)); break;
            case 2: q.t_max = -1.0f; break;  // t_min > t_max
            case 3: q.direction[a] = nan; break;
            case 4: q.direction[b] = -inf; break;
            case 5: q.origin[c] = (i & 1) != 0 ? nan : inf; break;
            case 6: q.t_min = nan; break;
            case 7: q.t_max = nan; break;
            case 8: q.direction[0] = q.direction[1] = q.direction[2] = 0.0f; break;
            case 9: q.t_min = q.t_max = -inf; break;
            default: break;
        }
        rays.push_back(q);
    }
    return rays;
}

// Whether two values have the same bits (-0 and +0 differ, a NaN equals its own bits).
template <class T>
bool same_bits(const T& a, const T& b) {
    return std::memcmp(&a, &b, sizeof(T)) == 0;
}

// The fields in which two working rays differ, by name ("" if none).
template <class Real>
std::string working_ray_differences(const WorkingRay<Real>& a, const WorkingRay<Real>& b) {
    std::string d;
    auto field = [&](const char* name, const auto& x, const auto& y) {
        if (!same_bits(x, y)) d += std::string(d.empty() ? "" : ", ") + name;
    };
    field("org", a.ray.org, b.ray.org);
    field("dir", a.ray.dir, b.ray.dir);
    field("inv_dir", a.ray.inv_dir, b.ray.inv_dir);
    field("kx", a.ray.kx, b.ray.kx);
    field("ky", a.ray.ky, b.ray.ky);
    field("kz", a.ray.kz, b.ray.kz);
    field("sx", a.ray.sx, b.ray.sx);
    field("sy", a.ray.sy, b.ray.sy);
    field("sz", a.ray.sz, b.ray.sz);
    field("ignore", a.ray.ignore, b.ray.ignore);
    field("org_max", a.ray.org_max, b.ray.org_max);
    field("length", a.length, b.length);
    field("t_min", a.t_min, b.t_min);
    field("t_max", a.t_max, b.t_max);
    field("whole_ray", a.whole_ray, b.whole_ray);
    return d;
}

struct SetupReport {
    int valid = 0, invalid = 0, mismatches = 0;
    std::string first;  // the first mismatch, described
};

// Each group of four consecutive rays through working_rays, against
// working_ray for each of them.
template <class Real>
SetupReport check_working_rays(const std::vector<QueryRay>& rays, const glm::dvec3& frame_origin) {
    SetupReport r;
    for (std::size_t i = 0; i + 4 <= rays.size(); i += 4) {
        WorkingRay<Real> four[4], one[4];
        bool four_valid[4];
        working_rays(rays.data() + i, frame_origin, four, four_valid);
        for (int k = 0; k < 4; ++k) {
            const bool valid = working_ray(rays[i + k], frame_origin, one[k]);
            ++(valid ? r.valid : r.invalid);
            const std::string d = valid != four_valid[k] ? std::string("validity")
                                  : valid                ? working_ray_differences(four[k], one[k])
                                                         : std::string();
            if (!d.empty() && r.mismatches++ == 0) r.first = "ray " + std::to_string(i + k) + ": " + d;
        }
    }
    return r;
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
