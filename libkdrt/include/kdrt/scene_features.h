// The effects a scene calls for. Renderers simulate only these: no shadow
// rays without lights, no bounce loop without mirrors or glass, no
// refraction code without glass.
#pragma once

#include <kdrt/export.h>
#include <kdrt/scene.h>

#include <string>
#include <vector>

namespace kdrt {

struct KDRT_API SceneFeatures {
    bool spheres = false;
    bool triangles = false;
    bool lights = false;
    bool reflection = false;  // some material has reflect > 0
    bool refraction = false;  // some material has transmit > 0
    int max_depth = 1;        // effective: 1 when nothing reflects or refracts

    static SceneFeatures of(const Scene& scene, int max_depth);
    static SceneFeatures all(int max_depth);  // the generic set: everything on
    std::vector<std::string> names() const;   // enabled features, for reports
};

}  // namespace kdrt
