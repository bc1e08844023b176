// Test helper: a scene scaled about the origin and then moved, camera and
// lights included (for the scale-invariance tests).
#pragma once

#include <kdrt/scene.h>

namespace kdrt::test {

inline Scene transformed(Scene s, double scale, glm::dvec3 offset) {
    auto tf = [&](glm::dvec3 p) { return p * scale + offset; };
    s.camera.position = tf(s.camera.position);
    s.camera.look_at = tf(s.camera.look_at);
    for (auto& l : s.lights) l.position = tf(l.position);
    for (auto& sp : s.spheres) {
        sp.center = tf(sp.center);
        sp.radius *= scale;
    }
    for (auto& p : s.triangles.positions) p = tf(p);
    for (auto& m : s.meshes)
        for (auto& p : m.positions) p = tf(p);
    return s;
}

}  // namespace kdrt::test
