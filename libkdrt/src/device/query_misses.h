// The answers of a query that finds nothing, as every device writes them:
// a miss (kdrt/layout.h: t = +inf, no ids, no kind) and a closest point of
// no surface (NaN point, distance +inf, no ids).
#pragma once

#include <kdrt/layout.h>

#include <limits>

namespace kdrt::detail {

inline QueryHit query_miss() {
    QueryHit h{};
    h.t = std::numeric_limits<float>::infinity();
    h.object = h.geometry = h.primitive = KDRT_NO_HIT;
    h.kind = KDRT_KIND_NONE;
    return h;
}

inline ClosestPoint no_closest_point() {
    ClosestPoint c{};
    for (float& x : c.point) x = std::numeric_limits<float>::quiet_NaN();
    c.distance = std::numeric_limits<float>::infinity();
    c.object = c.geometry = c.primitive = KDRT_NO_HIT;
    return c;
}

}  // namespace kdrt::detail
