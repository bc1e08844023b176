#include "camera_orbit.h"

#include <glm/geometric.hpp>

#include <cmath>
#include <numbers>

namespace kdrt::cli {

Camera orbit_camera(const Camera& camera, int frame, int frames) {
    if (frame == 0 || frames <= 1) return camera;
    const double angle = 2.0 * std::numbers::pi * frame / frames;
    const glm::dvec3 k = glm::normalize(camera.up);
    const glm::dvec3 v = camera.position - camera.look_at;
    // Rodrigues' rotation of v about the unit axis k.
    const glm::dvec3 rotated =
        v * std::cos(angle) + glm::cross(k, v) * std::sin(angle) + k * glm::dot(k, v) * (1.0 - std::cos(angle));
    Camera c = camera;
    c.position = camera.look_at + rotated;
    return c;
}

}  // namespace kdrt::cli
