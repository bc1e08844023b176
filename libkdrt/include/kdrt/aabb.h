// Axis-aligned bounding box in double precision, used by the builders.
#pragma once

#include <glm/common.hpp>
#include <glm/vec3.hpp>

#include <limits>

namespace kdrt {

struct Aabb {
    glm::dvec3 lo{std::numeric_limits<double>::infinity()};
    glm::dvec3 hi{-std::numeric_limits<double>::infinity()};

    bool empty() const { return !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z); }
    void extend(const glm::dvec3& p) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
    void extend(const Aabb& b) { lo = glm::min(lo, b.lo); hi = glm::max(hi, b.hi); }
    glm::dvec3 extent() const { return hi - lo; }
    double surface_area() const {
        if (empty()) return 0.0;
        glm::dvec3 d = hi - lo;
        return 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
    }
    Aabb intersect(const Aabb& b) const { return {glm::max(lo, b.lo), glm::min(hi, b.hi)}; }
    bool operator==(const Aabb&) const = default;
};

}  // namespace kdrt
