#include <kdrt/scene_features.h>

namespace kdrt {

SceneFeatures SceneFeatures::of(const Scene& scene, int max_depth) {
    SceneFeatures f;
    f.spheres = !scene.spheres.empty();
    f.triangles = scene.triangle_count() > 0;
    f.lights = !scene.lights.empty();
    for (const Material& m : scene.materials) {
        f.reflection = f.reflection || m.reflect > 0.0;
        f.refraction = f.refraction || m.transmit > 0.0;
    }
    // Without mirrors or glass no ray ever bounces: depth 1 is the whole story.
    f.max_depth = (f.reflection || f.refraction) ? max_depth : 1;
    return f;
}

SceneFeatures SceneFeatures::all(int max_depth) {
    SceneFeatures f;
    f.spheres = f.triangles = f.lights = f.reflection = f.refraction = true;
    f.max_depth = max_depth;
    return f;
}

std::vector<std::string> SceneFeatures::names() const {
    std::vector<std::string> n;
    if (spheres) n.push_back("spheres");
    if (triangles) n.push_back("triangles");
    if (lights) n.push_back("shadows");
    if (reflection) n.push_back("reflection");
    if (refraction) n.push_back("refraction");
    return n;
}

}  // namespace kdrt
