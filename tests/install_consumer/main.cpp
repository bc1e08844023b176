// Builds a scene in code against the installed kdrt and renders it.
#include <kdrt/render.h>

#include <cstdio>

int main() {
    kdrt::Scene scene;
    scene.camera.position = {0, 0, -4};
    scene.settings.width = scene.settings.height = 9;
    kdrt::Material red;
    red.color = {1, 0, 0};
    scene.add_sphere({0, 0, 0}, 1.0, scene.add_material(red));
    scene.add_light({{0, 0, -10}, {1, 1, 1}});
    kdrt::RenderResult r = kdrt::render(scene, {});
    glm::vec3 c = r.image.at(4, 4);
    std::printf("centre pixel %.3f %.3f %.3f\n", c.x, c.y, c.z);
    return (c.x > 0.9f && c.y == 0.0f) ? 0 : 1;
}
