// Builds a scene in code and renders it to a PNG file with kdrt::render().
#include <kdrt/image.h>
#include <kdrt/render.h>

#include <cstdint>
#include <cstdio>

int main() {
    kdrt::Scene scene;
    scene.camera.position = {0, 1, -6};
    scene.camera.look_at = {0, 0, 0};
    scene.settings.width = 320;
    scene.settings.height = 240;
    scene.settings.background = {0.2, 0.25, 0.3};

    kdrt::Material red;
    red.color = {0.9, 0.2, 0.2};
    red.specular = 0.5;
    kdrt::Material mirror;
    mirror.color = {0.8, 0.8, 0.8};
    mirror.reflect = 0.4;
    kdrt::MaterialId red_id = scene.add_material(red);
    kdrt::MaterialId mirror_id = scene.add_material(mirror);

    // Each add_* returns the id that renders and ray queries report for it.
    std::uint32_t ball = scene.add_sphere({0, 0, 0}, 1.0, red_id);
    scene.add_triangle({-5, -1, -5}, {-5, -1, 5}, {5, -1, -5}, mirror_id);
    scene.add_triangle({5, -1, -5}, {-5, -1, 5}, {5, -1, 5}, mirror_id);
    scene.add_light({{-3, 5, -4}, {1, 1, 1}});

    kdrt::RenderOptions options;      // device: $KDRT_DEVICE, else "cpu"
    options.frame.want_ids = true;    // also return the object id seen by each pixel
    kdrt::RenderResult result = kdrt::render(scene, options);
    kdrt::write_image("01_render.png", result.image);

    int centre = (scene.settings.height / 2) * scene.settings.width + scene.settings.width / 2;
    const kdrt::RenderStats& stats = result.stats;
    std::printf("%dx%d on %s in %.1f ms, centre pixel sees object %d (the ball is %u)\n", result.image.width,
                result.image.height, stats.device_name.c_str(), stats.render_ms, result.ids[centre], ball);
    return result.ids[centre] == static_cast<std::int32_t>(ball) ? 0 : 1;
}
