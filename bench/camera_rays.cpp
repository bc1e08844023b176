#include "camera_rays.h"

namespace kdrt::bench {

std::vector<ShadingRay> make_camera_rays(const WorkingScene& scene) {
    const int W = scene.width(), H = scene.height();
    std::vector<ShadingRay> rays;
    rays.reserve(static_cast<std::size_t>(W) * H);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) rays.push_back(scene.camera_ray(x, y));
    return rays;
}

std::size_t count_differences(const std::vector<std::int32_t>& a, const std::vector<std::int32_t>& b) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) n += a[i] != b[i];
    return n + (a.size() > b.size() ? a.size() - b.size() : b.size() - a.size());
}

}  // namespace kdrt::bench
