#include <kdrt/camera.h>

#include <glm/geometric.hpp>

#include <cmath>

namespace kdrt {

CameraFrame::CameraFrame(const Camera& camera, int width, int height) {
    position = camera.position;
    forward = glm::normalize(camera.look_at - camera.position);
    right = glm::normalize(glm::cross(forward, camera.up));
    up = glm::cross(right, forward);
    tan_half_fov = std::tan(camera.fov_y * (3.14159265358979323846 / 180.0) / 2.0);
    aspect = static_cast<double>(width) / static_cast<double>(height);
}

glm::dvec3 CameraFrame::direction(int x, int y, int width, int height, double sx, double sy) const {
    double u = (2.0 * (x + sx) / width - 1.0) * tan_half_fov * aspect;
    double v = (1.0 - 2.0 * (y + sy) / height) * tan_half_fov;
    return glm::normalize(forward + u * right + v * up);
}

void sample_offset(int s, int n, double& sx, double& sy) {
    if (n <= 1) {
        sx = sy = 0.5;
        return;
    }
    int k = static_cast<int>(std::lround(std::sqrt(static_cast<double>(n))));
    if (k * k == n) {
        sx = (s % k + 0.5) / k;
        sy = (s / k + 0.5) / k;
        return;
    }
    // R2 sequence: the plastic constant's powers give well-spread 2D points.
    const double g = 1.32471795724474602596;
    sx = std::fmod(0.5 + s / g, 1.0);
    sy = std::fmod(0.5 + s / (g * g), 1.0);
}

}  // namespace kdrt
