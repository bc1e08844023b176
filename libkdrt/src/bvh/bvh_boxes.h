// Float boxes as the BVH code handles them: an object's double box rounded
// outward, unions, surface areas. Shared by the builder, the collapse, the
// refit, the checks and the statistics, so that all of them agree bit for bit.
#pragma once

#include "bvh/bvh.h"
#include "common/float_step.h"

#include <kdrt/aabb.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace kdrt::detail {

// A box in floats; empty as lo = +inf, hi = -inf.
struct FloatBox {
    float lo[3] = {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                   std::numeric_limits<float>::infinity()};
    float hi[3] = {-std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                   -std::numeric_limits<float>::infinity()};

    bool empty() const { return !(lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2]); }
    void extend(const FloatBox& b) {
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], b.lo[a]);
            hi[a] = std::max(hi[a], b.hi[a]);
        }
    }
    bool contains(const FloatBox& b) const {
        for (int a = 0; a < 3; ++a)
            if (!(lo[a] <= b.lo[a] && b.hi[a] <= hi[a])) return false;
        return true;
    }
    // In double: a float box's area may exceed the float range.
    double area() const {
        if (empty()) return 0.0;
        const double dx = double(hi[0]) - lo[0], dy = double(hi[1]) - lo[1], dz = double(hi[2]) - lo[2];
        return 2.0 * (dx * dy + dy * dz + dz * dx);
    }
    Aabb to_aabb() const {
        if (empty()) return {};
        Aabb b;
        for (int a = 0; a < 3; ++a) {
            b.lo[a] = lo[a];
            b.hi[a] = hi[a];
        }
        return b;
    }
};

// The float box around a double box: each bound rounded outward to a float
// (+0 for -0, so equal boxes have equal bits). The caller has checked that the
// box is non-empty and inside the float range.
inline FloatBox round_out(const Aabb& b) {
    FloatBox f;
    for (int a = 0; a < 3; ++a) {
        float lo = static_cast<float>(b.lo[a]), hi = static_cast<float>(b.hi[a]);
        if (static_cast<double>(lo) > b.lo[a]) lo = float_step_down(lo);
        if (static_cast<double>(hi) < b.hi[a]) hi = float_step_up(hi);
        f.lo[a] = lo + 0.0f;
        f.hi[a] = hi + 0.0f;
    }
    return f;
}

}  // namespace kdrt::detail

namespace kdrt {

// The box of a wide node's child slot.
template <int N>
detail::FloatBox slot_box(const WideBvhNodeN<N>& node, int slot) {
    detail::FloatBox b;
    for (int a = 0; a < 3; ++a) {
        b.lo[a] = node.box[0][a][slot];
        b.hi[a] = node.box[1][a][slot];
    }
    return b;
}

}  // namespace kdrt

namespace kdrt::detail {

// Whether a BVH may hold the box: finite and inside the float range.
inline bool in_float_range(const Aabb& b) {
    constexpr double kFloatMax = std::numeric_limits<float>::max();
    for (int a = 0; a < 3; ++a)
        if (!(b.lo[a] >= -kFloatMax && b.hi[a] <= kFloatMax)) return false;
    return true;
}

// An object's box as the builder and the refit take it: a box the BVH holds,
// no box (empty, as Aabb{}: the object is left out), or neither (a NaN
// anywhere, or a box beyond the float range), which they refuse.
enum class BoxUse { Held, Empty, Refused };

inline BoxUse box_use(const Aabb& b) {
    for (int a = 0; a < 3; ++a)
        if (std::isnan(b.lo[a]) || std::isnan(b.hi[a])) return BoxUse::Refused;
    if (b.empty()) return BoxUse::Empty;
    return in_float_range(b) ? BoxUse::Held : BoxUse::Refused;
}

}  // namespace kdrt::detail
