// FORMAT.md's pinhole camera.
#pragma once

#include <kdrt/export.h>
#include <kdrt/scene.h>

#include <glm/vec3.hpp>

namespace kdrt {

// The camera's orthonormal frame and the tangent of half the vertical field of view.
struct KDRT_API CameraFrame {
    glm::dvec3 position, forward, right, up;
    double tan_half_fov = 0.0;
    double aspect = 1.0;  // W / H

    CameraFrame(const Camera& camera, int width, int height);

    // Normalised direction through image position (x + sx, y + sy), y = 0 the top
    // row; (sx, sy) = (0.5, 0.5) is the pixel centre of FORMAT.md's formula.
    glm::dvec3 direction(int x, int y, int width, int height, double sx = 0.5, double sy = 0.5) const;
};

// Sub-pixel position of sample s of n: the pixel centre for n = 1, a
// stratified k x k grid when n = k^2, otherwise the R2 low-discrepancy
// sequence (Roberts 2018). Deterministic, identical on every device.
KDRT_API void sample_offset(int s, int n, double& sx, double& sy);

}  // namespace kdrt
