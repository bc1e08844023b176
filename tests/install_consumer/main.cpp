// Builds a scene in code against the installed kdrt, renders it, and catches
// a kdrt::Error thrown inside the library (its typeinfo must be exported).
#include <kdrt/error.h>
#include <kdrt/render.h>
#include <kdrt/scene_loader.h>
#include <kdrt/version.h>

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
    std::printf("kdrt %s: centre pixel %.3f %.3f %.3f\n", KDRT_VERSION_STRING, c.x, c.y, c.z);
    if (!(c.x > 0.9f && c.y == 0.0f)) return 1;

    try {
        kdrt::load_scene("no/such/scene.json");
    } catch (const kdrt::Error& e) {
        std::printf("caught kdrt::Error(%s): %s\n", kdrt::to_string(e.code()), e.what());
        return e.code() == kdrt::ErrorCode::Io ? 0 : 1;
    } catch (...) {
        std::printf("a kdrt::Error from the library was not caught as one\n");
        return 1;
    }
    return 1;
}
