// The answers of a query that finds nothing, as every device writes them:
// a miss (kdrt/layout.h: t = +inf, no ids, no kind) and a closest point of
// no surface (NaN point, distance +inf, no ids).
#pragma once

#include <kdrt/layout.h>

#include <limits>

namespace kdrt::detail {

// A constant, so that writing a miss copies whole vectors: a QueryHit built
// field by field on the stack and then copied stalls each store on its reload.
inline constexpr QueryHit kQueryMiss{std::numeric_limits<float>::infinity(), {0.0f, 0.0f, 0.0f}, 0.0f, 0.0f,
                                     KDRT_NO_HIT, KDRT_NO_HIT, KDRT_NO_HIT, KDRT_KIND_NONE};

inline ClosestPoint no_closest_point() {
    ClosestPoint c{};
    for (float& x : c.point) x = std::numeric_limits<float>::quiet_NaN();
    c.distance = std::numeric_limits<float>::infinity();
    c.object = c.geometry = c.primitive = KDRT_NO_HIT;
    return c;
}

}  // namespace kdrt::detail
