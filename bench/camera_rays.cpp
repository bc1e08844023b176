#include "camera_rays.h"

#include <kdrt/camera.h>

namespace kdrt::bench {

std::vector<detail::Ray<float>> make_camera_rays(const detail::PreparedScene& scene) {
    const int W = scene.settings.width, H = scene.settings.height;
    const CameraFrame cam(scene.camera, W, H);
    const glm::vec3 eye(cam.position);
    std::vector<detail::Ray<float>> rays;
    rays.reserve(static_cast<std::size_t>(W) * H);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) rays.emplace_back(eye, glm::vec3(cam.direction(x, y, W, H)));
    return rays;
}

std::size_t count_differences(const std::vector<std::int32_t>& a, const std::vector<std::int32_t>& b) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) n += a[i] != b[i];
    return n + (a.size() > b.size() ? a.size() - b.size() : b.size() - a.size());
}

}  // namespace kdrt::bench
